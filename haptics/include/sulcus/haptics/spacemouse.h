// A 3Dconnexion SpaceMouse as a 6-DOF input for the probe (no force output): a pure parser of its
// HID input reports and a velocity-style mapping from its deflection to a pose increment. No
// transport here: whoever reads the hidraw/hidapi bytes hands them to parse_spacemouse_report().
// Report layouts and IDs: docs/spacemouse.md.
#pragma once

#include "sulcus/engine/types.h"

#include <cstddef>
#include <cstdint>

namespace sulcus {

// USB vendor IDs: the Logitech era and 3Dconnexion's own.
inline constexpr uint16_t kSpaceMouseVendorLogitech = 0x046D;
inline constexpr uint16_t kSpaceMouseVendor3Dconnexion = 0x256F;

// Raw counts that map to full deflection (scaled ±1). Tested devices report about ±350; a larger
// raw value is still kept in the raw field, and its scaled value is clamped to ±1.
inline constexpr double kSpaceMouseFullScale = 350.0;

// Report IDs (first byte of every input report).
inline constexpr uint8_t kSpaceMouseReportTranslation = 1;  // split: x,y,z; combined: all six
inline constexpr uint8_t kSpaceMouseReportRotation = 2;     // split layout: rx,ry,rz
inline constexpr uint8_t kSpaceMouseReportButtons = 3;      // 32-bit bitmask

// Report sizes in bytes, the ID byte included.
inline constexpr size_t kSpaceMouseAxesReportSize = 7;       // ID + 3 × int16 LE
inline constexpr size_t kSpaceMouseCombinedReportSize = 13;  // ID + 6 × int16 LE
inline constexpr size_t kSpaceMouseButtonsReportSize = 5;    // ID + uint32 LE

enum class SpaceMouseLayout : uint8_t {
    split,     // report 1 = translation, report 2 = rotation (7 bytes each)
    combined,  // report 1 = translation then rotation (13 bytes)
};

// The device's latest deflection. Axes are in the device's own HID frame, unchanged.
struct SpaceMouseState {
    int16_t translation_raw[3] = {0, 0, 0};  // x, y, z counts
    int16_t rotation_raw[3] = {0, 0, 0};     // rx, ry, rz counts
    Vec3 translation{0.0};                   // raw / kSpaceMouseFullScale, clamped to [-1, 1]
    Vec3 rotation{0.0};                      // likewise
    uint32_t buttons = 0;                    // bit i: button i+1 pressed
};

// Folds one input report (report ID first, as hidapi returns it for numbered reports) into
// `state`. Returns false and leaves `state` untouched for a null or empty buffer, an unknown
// report ID (e.g. 0x17, battery) or a report shorter than its layout needs. Trailing bytes past
// the layout are ignored. Report 2 is accepted in either layout. Allocation-free, no throw.
bool parse_spacemouse_report(const uint8_t* data, size_t size, SpaceMouseLayout layout,
                             SpaceMouseState& state) noexcept;

// True for the vendor/product pairs listed in spacemouse_report.cpp.
bool is_spacemouse(uint16_t vendor, uint16_t product) noexcept;

// The report layout a product sends. Older models send split reports; the SpaceMouse Wireless
// (0xC62E) and every later product send the combined report. Unknown products get the combined
// layout, as the newer models do (see docs/spacemouse.md for why this is a choice).
SpaceMouseLayout layout_for_product(uint16_t vendor, uint16_t product) noexcept;

// How deflection becomes motion. Each scaled axis s first loses its dead zone d:
//   shaped(s) = sign(s) · (|s| − d) / (1 − d)   for |s| > d, else 0,
// so motion starts from zero at the dead-zone edge and full deflection gives the full gain.
struct SpaceMouseMapping {
    double translation_gain_m_per_s = 0.05;  // speed at full deflection of one axis
    double rotation_gain_rad_per_s = 1.0;    // angular speed at full deflection of one axis
    double dead_zone = 8.0 / kSpaceMouseFullScale;  // per axis, scaled units (OCCT's z threshold)
    Vec3 translation_sign{1.0, 1.0, 1.0};    // per-axis sign from the HID frame to the pose frame
    Vec3 rotation_sign{1.0, 1.0, 1.0};
    // false: velocities are in the pose's parent (world) frame; true: in the current tool frame.
    bool tool_frame = false;
};

// The per-axis dead-zone shaping above; exposed so the docs' formula is testable.
double spacemouse_shape_axis(double scaled, double dead_zone) noexcept;

// Advances `current` by one tick of dt_s seconds at the velocity the state commands: position by
// v·dt, orientation by the rotation vector ω·dt (exact exponential, renormalised). A non-finite
// or non-positive dt_s, or a non-finite mapping, returns `current` unchanged.
Pose integrate_spacemouse(const Pose& current, const SpaceMouseState& state, double dt_s,
                          const SpaceMouseMapping& mapping) noexcept;

}  // namespace sulcus
