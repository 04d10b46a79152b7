// The mouse and keyboard as a Device, for a desk without a haptic device. The UI thread turns its
// input into a target pose (app: MouseProbeDriver) and hands it over with set_target(), lock-free;
// each read() on the servo thread moves the pose toward the latest target at a bounded linear and
// angular speed and clamps it to the workspace box, so the display-rate jumps of the cursor
// become smooth motion at the servo rate. Input only: 6 DOF in, 0 out; the force the loop sends
// is kept for the screen (last_force()), since none can reach the hand. See docs/mouse-device.md.
#pragma once

#include "sulcus/haptics/device.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

namespace sulcus {

struct MouseDeviceConfig {
    double rate_hz = 1000.0;  // read() advances the pose by one tick of 1 / rate_hz per call
    Pose start_pose;          // the pose at start()
    // The box the position is kept in, device frame (m). Both left zero: ±0.1 m around the
    // start pose's position.
    Vec3 workspace_min_m{0.0};
    Vec3 workspace_max_m{0.0};
    double max_speed_m_per_s = 0.05;           // at most this far per second toward the target
    double max_angular_speed_rad_per_s = 2.0;  // at most this angle per second toward the target
};

class MouseDevice final : public Device {
public:
    explicit MouseDevice(MouseDeviceConfig config = {});
    ~MouseDevice() override;
    MouseDevice(const MouseDevice&) = delete;
    MouseDevice& operator=(const MouseDevice&) = delete;

    const DeviceCapabilities& capabilities() const override { return caps_; }
    // Checks the settings and puts the pose on the start pose (inside the box). The target is
    // whatever set_target() last gave (it survives stop/start); with none yet, the pose holds.
    // "" or one line saying why not.
    std::string start() override;
    // One tick toward the target (rate-limited, clamped); false with kDeviceFaultNotStarted
    // before start() or after stop().
    bool read(DeviceSample& sample) noexcept override;
    // Nothing is rendered; the wrench is kept for last_force()/last_torque(). A non-finite one is
    // counted, kept as zero, and reported as kDeviceFaultBadCommand from then on (until start()).
    void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept override;
    void stop() override;

    // UI side (one thread): the pose to move toward, device frame. A non-finite position or
    // orientation, or a zero quaternion, is ignored (the previous target stays) and counted; the
    // quaternion is normalised. Lock-free, never blocks the servo thread. False when ignored.
    bool set_target(const Pose& pose) noexcept;
    uint64_t rejected_targets() const noexcept { return rejected_.load(std::memory_order_relaxed); }

    // The last wrench written (zero before any); lock-free, any thread.
    Vec3 last_force() const noexcept;
    Vec3 last_torque() const noexcept;
    uint64_t bad_commands() const noexcept { return bad_commands_.load(std::memory_order_relaxed); }

    // The pose read() last gave (the start pose before any). Servo thread, or when not running.
    const Pose& current() const noexcept { return pose_; }
    // The workspace box in use (the defaults resolved).
    const Vec3& workspace_min() const noexcept { return caps_.workspace_min_m; }
    const Vec3& workspace_max() const noexcept { return caps_.workspace_max_m; }

private:
    struct Shared;  // the seqlocks for the target and the wrench (kept in the .cpp)

    MouseDeviceConfig config_;
    DeviceCapabilities caps_;
    std::unique_ptr<Shared> shared_;
    std::atomic<uint64_t> rejected_{0};
    std::atomic<uint64_t> bad_commands_{0};

    // Servo-thread state.
    bool running_ = false;
    Pose pose_;
    double dt_s_ = 1e-3;
    uint32_t fault_ = kDeviceFaultNotStarted;
};

}  // namespace sulcus
