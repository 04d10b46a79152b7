// A haptic device as the servo loop sees it: what it can do (capabilities), what it reports each
// tick (a sample) and the wrench it is sent. Backends (vendor library, simulated hand, replayed
// trace) implement Device; see docs/devices.md.
#pragma once

#include "sulcus/engine/types.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sulcus {

// What a device model can sense and render. Workspace is a box in the device frame (metres,
// +Y up, centred on the workspace's middle). A figure the device does not have is 0.
struct DeviceCapabilities {
    std::string name;
    int input_dof = 0;   // sensed: 3 position, +3 with an encoded gimbal
    int output_dof = 0;  // actuated: 3 force, 6 with gimbal torques
    Vec3 workspace_min_m{0.0};
    Vec3 workspace_max_m{0.0};
    double max_force_N = 0.0;             // peak force
    double max_continuous_force_N = 0.0;  // force the motors hold without overheating
    double max_torque_Nm = 0.0;           // 0 when the gimbal is passive
    double max_stiffness_N_per_m = 0.0;   // highest contact stiffness to render
    double position_resolution_m = 0.0;   // nominal encoder resolution at the tip
    double nominal_rate_Hz = 1000.0;      // servo rate of the vendor scheduler
};

// The device models with known figures (sources in device.cpp).
DeviceCapabilities touch_capabilities();             // 3D Systems Touch (USB / Ethernet)
DeviceCapabilities touch_x_capabilities();           // 3D Systems Touch X (former Phantom Desktop)
DeviceCapabilities phantom_omni_capabilities();      // SensAble Phantom Omni (FireWire, legacy)
DeviceCapabilities phantom_premium_15_capabilities();       // Phantom Premium 1.5, 3-DOF output
DeviceCapabilities phantom_premium_15_6dof_capabilities();  // Phantom Premium 1.5 6DOF
std::vector<DeviceCapabilities> known_devices();

// Fault codes of a DeviceSample (a backend may add its own above 255).
enum DeviceFault : uint32_t {
    kDeviceFaultNone = 0,
    kDeviceFaultNotStarted = 1,   // read before start() or after stop()
    kDeviceFaultBadCommand = 2,   // a non-finite force or torque was written (zero was applied)
    kDeviceFaultComm = 3,         // communication with the device was lost
};

// One tick's reading of the device, device frame.
struct DeviceSample {
    Pose pose;                       // stylus pose (metres, unit quaternion w, x, y, z)
    Vec3 linear_velocity_m_per_s{0.0};
    uint32_t buttons = 0;            // bit i: button i+1 pressed
    bool connected = false;
    uint32_t fault = kDeviceFaultNone;
};

// A device backend. start() and stop() run outside the servo loop; read() and write() run in
// it, once each per tick, and must not block, allocate or throw.
class Device {
public:
    virtual ~Device() = default;
    virtual const DeviceCapabilities& capabilities() const = 0;
    // Opens the device and starts its servo clock; "" on success, else one line saying why not.
    virtual std::string start() = 0;
    // The latest sample; false (with `sample.fault` set) when there is none to give.
    virtual bool read(DeviceSample& sample) noexcept = 0;
    // The force (N) and torque (N·m) to render until the next write, device frame.
    virtual void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept = 0;
    virtual void stop() = 0;
};

}  // namespace sulcus
