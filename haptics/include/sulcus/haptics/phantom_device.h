// A Phantom / Touch device through 3D Systems' OpenHaptics device API (libHD), loaded at run
// time with dlopen, so the project builds and runs without OpenHaptics installed and start()
// says in one line what is missing. OpenHaptics runs its own 1 kHz scheduler thread; the
// backend's callback there exchanges samples and commands with the servo loop's thread without
// locks (read() and write() never block). See docs/devices.md, "Phantom through OpenHaptics".
#pragma once

#include "sulcus/haptics/device.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sulcus {

// Fault codes of a PhantomDevice sample: kPhantomFaultHdBase + the HDAPI error code that caused
// it (e.g. 0x10201 for HD_EXCEEDED_MAX_FORCE), so the exact vendor error survives in the sample
// and in recordings. Codes of device.h (< 256) keep their meaning.
inline constexpr uint32_t kPhantomFaultHdBase = 0x10000;
constexpr uint32_t phantom_fault_from_hd(unsigned hd_error) noexcept { return kPhantomFaultHdBase + (hd_error & 0xFFFFu); }
constexpr bool is_phantom_hd_fault(uint32_t fault) noexcept { return (fault & ~0xFFFFu) == kPhantomFaultHdBase; }
constexpr unsigned phantom_fault_hd_error(uint32_t fault) noexcept { return fault & 0xFFFFu; }

// "HD_COMM_ERROR (0x0302): <what it means and what to do>" for every HDAPI error code; a code
// not in the API gives "unknown HD error 0x....".
std::string describe_hd_error(unsigned hd_error);
// A sample's fault in words (device.h codes and Phantom codes).
std::string describe_phantom_fault(uint32_t fault);

// The capability record for an HD_DEVICE_MODEL_TYPE string (case-insensitive match on "Touch X",
// "Desktop", "Omni", "Touch", "Premium" with or without "6DOF"); `fallback` when none matches.
DeviceCapabilities phantom_capabilities_for_model(const std::string& model, const DeviceCapabilities& fallback);

struct PhantomOptions {
    // The library to load. A non-empty `library_path` is the only one tried; else the
    // environment variable SULCUS_LIBHD when set (and use_env); else the candidates in order.
    std::string library_path;
    bool use_env = true;
    std::vector<std::string> library_candidates = {"libHD.so", "libHD.so.3.4", "libHD.so.3"};
    // OpenHaptics device configuration name (Touch_Setup); "" = the default device.
    std::string device_name;
    // The record used when the model string matches none we know; device figures overwrite it.
    DeviceCapabilities fallback = touch_capabilities();
    // The scheduler callback sends zero when no write() arrived for this long (s) while the last
    // command was not zero; <= 0 switches the watchdog off.
    double watchdog_s = 0.05;
    // start() waits this long (s) for the scheduler's first frame (so the first read() has a pose).
    double first_frame_timeout_s = 1.0;
    // Send torque (HD_CURRENT_TORQUE, mN·m) on models with 6 actuated DOF.
    bool torque_output = true;
    // dlclose libHD at stop(). Off by default: CHAI3D reports the vendor driver failing when it is
    // loaded a second time in a process after an unload, so the library stays loaded and is
    // reused by the next start().
    bool unload_library_on_stop = false;
};

class PhantomDevice final : public Device {
public:
    explicit PhantomDevice(PhantomOptions options = {});
    ~PhantomDevice() override;  // stop()
    PhantomDevice(const PhantomDevice&) = delete;
    PhantomDevice& operator=(const PhantomDevice&) = delete;

    // The model's record with the figures the device reported; the fallback before start().
    const DeviceCapabilities& capabilities() const override { return caps_; }
    // Loads libHD, initialises and checks the device, schedules the servo callback, starts the
    // scheduler and waits for its first frame. "" or one line; on failure everything done so
    // far is undone. One PhantomDevice runs per process at a time.
    std::string start() override;
    // The latest frame's sample (single reader: the servo thread). False before start() / after
    // stop(). After a communication error: connected = false, fault latched.
    bool read(DeviceSample& sample) noexcept override;
    // The wrench for the next frames (N, N·m). A non-finite one sends zero and latches
    // kDeviceFaultBadCommand.
    void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept override;
    // Sends zero, stops the scheduler, unschedules, disables the device. Idempotent.
    void stop() override;

    // Clears a latched force / command fault at the next frame (any thread), so that
    // ServoLoop::reset_safety() (SafetyLayer::reset()) can succeed. A communication fault needs stop() and start().
    void clear_fault() noexcept;

    const std::string& model() const noexcept { return model_; }      // HD_DEVICE_MODEL_TYPE
    const std::string& library() const noexcept { return library_; }  // the library loaded
    bool sends_torque() const noexcept;
    uint64_t frames() const noexcept;          // scheduler frames since start()
    uint64_t watchdog_trips() const noexcept;  // times the watchdog zeroed a stale command

    struct Impl;

private:
    PhantomOptions options_;
    DeviceCapabilities caps_;
    std::string model_;
    std::string library_;
    std::unique_ptr<Impl> impl_;
};

}  // namespace sulcus
