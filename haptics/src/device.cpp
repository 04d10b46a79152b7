// Capability records of the supported device models.
//
// Sources, abbreviated below:
//  [chai3d] CHAI3D's per-model table (chai3d/chai3d:src/devices/CPhantomDevices.cpp): max force,
//           max torque, max stiffness, which models actuate rotation.
//  [hdapi]  the OpenHaptics gimbal limits maxGimbalTorque(188,188,48) mN·m of the vendor's
//           CommandJointTorque example.
//  [rate]   the OpenHaptics servo scheduler, 1 kHz nominal (the vendor's measured Touch rate
//           stats: mean 978-1011 Hz).
//  [spec]   the vendor's product specification sheet (3D Systems / SensAble): workspace box,
//           continuous force, encoder resolution, DOF. To be checked against the datasheet of
//           the unit in hand.
#include "sulcus/haptics/device.h"

namespace sulcus {
namespace {

constexpr double mm = 1e-3;

// A box of the given size (mm) centred on the origin: width X, height Y, depth Z.
void set_box(DeviceCapabilities& c, double w_mm, double h_mm, double d_mm) {
    c.workspace_max_m = Vec3(w_mm, h_mm, d_mm) * (0.5 * mm);
    c.workspace_min_m = -c.workspace_max_m;
}

}  // namespace

DeviceCapabilities touch_capabilities() {
    DeviceCapabilities c;
    c.name = "3D Systems Touch";
    c.input_dof = 6;                    // [spec] position + encoded gimbal
    c.output_dof = 3;                   // [spec], [chai3d] (no actuated rotation)
    set_box(c, 160, 120, 70);           // [spec] 160 W x 120 H x 70 D mm
    c.max_force_N = 3.3;                // [chai3d], [spec]
    c.max_continuous_force_N = 0.88;    // [spec]
    c.max_torque_Nm = 0.0;              // [chai3d]
    c.max_stiffness_N_per_m = 400.0;    // [chai3d]
    c.position_resolution_m = 0.055e-3;  // [spec] > 450 dpi
    c.nominal_rate_Hz = 1000.0;         // [rate]
    return c;
}

DeviceCapabilities touch_x_capabilities() {
    // The Touch X is the renamed Phantom Desktop; CHAI3D knows it as "PHANTOM Desktop".
    DeviceCapabilities c;
    c.name = "3D Systems Touch X";
    c.input_dof = 6;                    // [spec]
    c.output_dof = 3;                   // [spec], [chai3d]
    set_box(c, 160, 120, 120);          // [spec] 160 W x 120 H x 120 D mm
    c.max_force_N = 7.9;                // [chai3d] (PHANTOM Desktop), [spec]
    c.max_continuous_force_N = 1.75;    // [spec]
    c.max_torque_Nm = 0.0;              // [chai3d]
    c.max_stiffness_N_per_m = 1000.0;   // [chai3d] (PHANTOM Desktop)
    c.position_resolution_m = 0.023e-3;  // [spec] > 1100 dpi
    c.nominal_rate_Hz = 1000.0;         // [rate]
    return c;
}

DeviceCapabilities phantom_omni_capabilities() {
    DeviceCapabilities c;
    c.name = "SensAble Phantom Omni";
    c.input_dof = 6;                    // [spec]
    c.output_dof = 3;                   // [spec], [chai3d]
    set_box(c, 160, 120, 70);           // [spec] 160 W x 120 H x 70 D mm
    c.max_force_N = 3.3;                // [chai3d], [spec]
    c.max_continuous_force_N = 0.88;    // [spec]
    c.max_torque_Nm = 0.0;              // [chai3d]
    c.max_stiffness_N_per_m = 700.0;    // [chai3d]
    c.position_resolution_m = 0.055e-3;  // [spec] > 450 dpi
    c.nominal_rate_Hz = 1000.0;         // [rate]
    return c;
}

DeviceCapabilities phantom_premium_15_capabilities() {
    DeviceCapabilities c;
    c.name = "SensAble Phantom Premium 1.5";
    c.input_dof = 6;                    // [spec] with the encoder gimbal (3 without)
    c.output_dof = 3;                   // [spec]
    set_box(c, 381, 267, 191);          // [spec] 381 W x 267 H x 191 D mm
    c.max_force_N = 8.5;                // [chai3d] (Premium 1.5 6DOF row), [spec]
    c.max_continuous_force_N = 1.4;     // [spec]
    c.max_torque_Nm = 0.0;              // passive gimbal
    c.max_stiffness_N_per_m = 800.0;    // [chai3d] (Premium 1.5 6DOF row)
    c.position_resolution_m = 0.03e-3;   // [spec] > 860 dpi
    c.nominal_rate_Hz = 1000.0;         // [rate]
    return c;
}

DeviceCapabilities phantom_premium_15_6dof_capabilities() {
    DeviceCapabilities c = phantom_premium_15_capabilities();
    c.name = "SensAble Phantom Premium 1.5 6DOF";
    c.output_dof = 6;                   // [chai3d] m_actuatedRotation = true
    c.max_torque_Nm = 0.188;            // [chai3d], [hdapi] 188 mN·m about the gimbal's first two axes
    return c;
}

std::vector<DeviceCapabilities> known_devices() {
    return {touch_capabilities(), touch_x_capabilities(), phantom_omni_capabilities(),
            phantom_premium_15_capabilities(), phantom_premium_15_6dof_capabilities()};
}

}  // namespace sulcus
