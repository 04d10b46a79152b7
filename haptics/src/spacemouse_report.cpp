// SpaceMouse HID report parsing, product table and the deflection-to-motion mapping.
#include "sulcus/haptics/spacemouse.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

namespace {

int16_t read_i16_le(const uint8_t* p) noexcept {
    return static_cast<int16_t>(static_cast<uint16_t>(p[0]) | (static_cast<uint16_t>(p[1]) << 8));
}

uint32_t read_u32_le(const uint8_t* p) noexcept {
    return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
           (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}

double scale_axis(int16_t raw) noexcept {
    return std::clamp(static_cast<double>(raw) / kSpaceMouseFullScale, -1.0, 1.0);
}

// Three int16 LE axes starting at p into a raw triple and its scaled vector.
void read_axes(const uint8_t* p, int16_t (&raw)[3], Vec3& scaled) noexcept {
    for (int i = 0; i < 3; ++i) {
        raw[i] = read_i16_le(p + 2 * i);
        scaled[i] = scale_axis(raw[i]);
    }
}

// Product IDs from OCCT (Open-Cascade-SAS/OCCT:src/WNT/WNT_HIDSpaceMouse.cxx); the wireless
// receiver 0xC652 from bj-rn/VL.Devices.SpaceMouseHID (README). The sources do not say which
// product sends which layout, only that "newer devices" send the 13-byte combined report. The
// choice below is ours: the SpaceMouse Wireless (0xC62E) and everything after it is taken as
// combined, everything before as split.
struct ProductEntry {
    uint16_t product;
    SpaceMouseLayout layout;
};
constexpr ProductEntry kProducts[] = {
    {0xC603, SpaceMouseLayout::split},     // SpaceMouse
    {0xC605, SpaceMouseLayout::split},     // CADMan
    {0xC606, SpaceMouseLayout::split},     // SpaceMouse Classic
    {0xC621, SpaceMouseLayout::split},     // SpaceBall 5000
    {0xC623, SpaceMouseLayout::split},     // SpaceTraveler
    {0xC625, SpaceMouseLayout::split},     // SpacePilot
    {0xC626, SpaceMouseLayout::split},     // SpaceNavigator
    {0xC627, SpaceMouseLayout::split},     // SpaceExplorer
    {0xC628, SpaceMouseLayout::split},     // Navigator for Notebooks
    {0xC629, SpaceMouseLayout::split},     // SpacePilot Pro
    {0xC62B, SpaceMouseLayout::split},     // SpaceMouse Pro
    {0xC62E, SpaceMouseLayout::combined},  // SpaceMouse Wireless (cabled)
    {0xC62F, SpaceMouseLayout::combined},  // SpaceMouse Wireless (wireless)
    {0xC631, SpaceMouseLayout::combined},  // SpaceMouse Pro Wireless (cabled)
    {0xC632, SpaceMouseLayout::combined},  // SpaceMouse Pro Wireless (wireless)
    {0xC633, SpaceMouseLayout::combined},  // SpaceMouse Enterprise
    {0xC635, SpaceMouseLayout::combined},  // SpaceMouse Compact
    {0xC652, SpaceMouseLayout::combined},  // wireless receiver
};

bool known_vendor(uint16_t vendor) noexcept {
    return vendor == kSpaceMouseVendorLogitech || vendor == kSpaceMouseVendor3Dconnexion;
}

const ProductEntry* find_product(uint16_t vendor, uint16_t product) noexcept {
    if (!known_vendor(vendor)) return nullptr;
    for (const ProductEntry& e : kProducts)
        if (e.product == product) return &e;
    return nullptr;
}

bool finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Unit quaternion of the rotation vector r (axis · angle), exact for any angle.
Quat quat_from_rotation_vector(const Vec3& r) noexcept {
    const double angle = glm::length(r);
    if (angle < 1e-300) return Quat(1.0, 0.0, 0.0, 0.0);
    const Vec3 axis = r / angle;
    const double s = std::sin(0.5 * angle);
    return Quat(std::cos(0.5 * angle), axis.x * s, axis.y * s, axis.z * s);
}

}  // namespace

bool parse_spacemouse_report(const uint8_t* data, size_t size, SpaceMouseLayout layout,
                             SpaceMouseState& state) noexcept {
    if (data == nullptr || size == 0) return false;
    switch (data[0]) {
    case kSpaceMouseReportTranslation:
        if (layout == SpaceMouseLayout::combined) {
            if (size < kSpaceMouseCombinedReportSize) return false;
            read_axes(data + 1, state.translation_raw, state.translation);
            read_axes(data + 7, state.rotation_raw, state.rotation);
        } else {
            if (size < kSpaceMouseAxesReportSize) return false;
            read_axes(data + 1, state.translation_raw, state.translation);
        }
        return true;
    case kSpaceMouseReportRotation:
        if (size < kSpaceMouseAxesReportSize) return false;
        read_axes(data + 1, state.rotation_raw, state.rotation);
        return true;
    case kSpaceMouseReportButtons:
        if (size < kSpaceMouseButtonsReportSize) return false;
        state.buttons = read_u32_le(data + 1);
        return true;
    default:
        return false;
    }
}

bool is_spacemouse(uint16_t vendor, uint16_t product) noexcept {
    return find_product(vendor, product) != nullptr;
}

SpaceMouseLayout layout_for_product(uint16_t vendor, uint16_t product) noexcept {
    const ProductEntry* e = find_product(vendor, product);
    return e ? e->layout : SpaceMouseLayout::combined;
}

double spacemouse_shape_axis(double scaled, double dead_zone) noexcept {
    const double s = std::clamp(scaled, -1.0, 1.0);
    const double d = std::clamp(dead_zone, 0.0, 1.0);
    const double m = std::fabs(s);
    if (!(m > d) || d >= 1.0) return 0.0;  // also catches a NaN input
    return std::copysign((m - d) / (1.0 - d), s);
}

Pose integrate_spacemouse(const Pose& current, const SpaceMouseState& state, double dt_s,
                          const SpaceMouseMapping& mapping) noexcept {
    if (!std::isfinite(dt_s) || dt_s <= 0.0) return current;
    if (!std::isfinite(mapping.translation_gain_m_per_s) ||
        !std::isfinite(mapping.rotation_gain_rad_per_s) || !std::isfinite(mapping.dead_zone) ||
        !finite(mapping.translation_sign) || !finite(mapping.rotation_sign))
        return current;

    Vec3 v{0.0}, w{0.0};
    for (int i = 0; i < 3; ++i) {
        v[i] = mapping.translation_sign[i] * mapping.translation_gain_m_per_s *
               spacemouse_shape_axis(state.translation[i], mapping.dead_zone);
        w[i] = mapping.rotation_sign[i] * mapping.rotation_gain_rad_per_s *
               spacemouse_shape_axis(state.rotation[i], mapping.dead_zone);
    }

    Pose next = current;
    next.position += mapping.tool_frame ? current.orientation * (v * dt_s) : v * dt_s;
    // No twist leaves the orientation bit-for-bit alone: renormalising at rest would drift it.
    if (w == Vec3(0.0)) return next;
    const Quat dq = quat_from_rotation_vector(w * dt_s);
    next.orientation = glm::normalize(mapping.tool_frame ? current.orientation * dq
                                                         : dq * current.orientation);
    return next;
}

}  // namespace sulcus
