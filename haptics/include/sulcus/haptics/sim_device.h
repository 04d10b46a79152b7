// A simulated hand holding a device stylus: a Device for closed-loop tests without hardware.
//
// The stylus and the hand on it are one point mass tied to a scripted target by the grip, a
// spring and a damper; the force written to the device pushes the mass. So the hand follows its
// script in free space and yields to the rendered force in contact, as a trainee's hand does.
// Translation only: the orientation is the script's. Deterministic, no allocation in read/write.
#pragma once

#include "sulcus/engine/scene_file.h"
#include "sulcus/haptics/device.h"

#include <vector>

namespace sulcus {

// The hand. Defaults: a light grip on a stylus (docs/devices.md): 0.1 kg moving mass (fingers
// plus the device's apparent mass at the tip), 300 N/m grip stiffness, 3 N·s/m grip damping
// (damping ratio about 0.27, grip natural frequency about 8.7 Hz).
struct HandParameters {
    double mass_kg = 0.1;
    double grip_stiffness_N_per_m = 300.0;
    double grip_damping_N_s_per_m = 3.0;
    // Servo tick (s); 0 means 1 / the capabilities' nominal rate.
    double dt_s = 0.0;
    // Saturate the force at the capabilities' max_force_N, as the motors do.
    bool saturate_force = true;
    // What an ideal hand on an ideal device lacks (both off by default):
    // ticks between a force being written and it acting on the hand (0 .. kMaxHandLatencyTicks),
    // e.g. 1 when the simulation answers a sample one tick late;
    int latency_ticks = 0;
    // the encoders' resolution (m): read() rounds each coordinate to this grid; 0 = exact.
    double position_resolution_m = 0.0;
};

inline constexpr int kMaxHandLatencyTicks = 8;

class SimulatedHand final : public Device {
public:
    // `script`: the target pose over time (strictly increasing t; linear in position, slerp in
    // orientation, held at both ends). Time starts at the first sample's t.
    SimulatedHand(std::vector<TrajectorySample> script, HandParameters hand = {},
                  DeviceCapabilities caps = phantom_premium_15_capabilities());

    const DeviceCapabilities& capabilities() const override { return caps_; }
    // Checks the script and parameters, puts the hand at rest on the first target.
    std::string start() override;
    bool read(DeviceSample& sample) noexcept override;
    // Applies the force for one tick (zero-order hold) and advances the hand by one tick with
    // semi-implicit Euler. Torque is accepted and ignored (translation only).
    void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept override;
    void stop() override;

    void set_buttons(uint32_t buttons) noexcept { buttons_ = buttons; }

    double time_s() const { return t_; }
    double dt_s() const { return dt_; }
    const Vec3& position_m() const { return x_; }
    const Vec3& velocity_m_per_s() const { return v_; }
    Pose target() const;
    // Kinetic energy plus the energy in the grip spring (J).
    double energy_J() const;

private:
    void target_at(double t, Pose& pose, Vec3& velocity) const noexcept;

    std::vector<TrajectorySample> script_;
    HandParameters hand_;
    DeviceCapabilities caps_;
    double dt_ = 1e-3;
    double t_ = 0.0;
    Vec3 x_{0.0};
    Vec3 v_{0.0};
    Quat orientation_{1.0, 0.0, 0.0, 0.0};
    Vec3 pending_[kMaxHandLatencyTicks + 1] = {};  // forces in flight (ring), no allocation
    int pending_head_ = 0;
    uint32_t buttons_ = 0;
    uint32_t fault_ = kDeviceFaultNotStarted;
    bool running_ = false;
    mutable size_t cursor_ = 0;
};

}  // namespace sulcus
