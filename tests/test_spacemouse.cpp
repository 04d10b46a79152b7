// SpaceMouse HID report parsing, the product table and the deflection-to-motion mapping.
// Report bytes are written out by hand from the layouts in docs/spacemouse.md: report ID first,
// then little-endian int16 axes (350 = 5E 01, -350 = A2 FE, 100 = 64 00, -100 = 9C FF,
// 175 = AF 00, -175 = 51 FF) or a little-endian uint32 button mask.
#include "sulcus/haptics/spacemouse.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace sulcus {
namespace {

// Split layout, report 1: x = 350, y = -100, z = 0.
constexpr uint8_t kSplitTranslation[] = {0x01, 0x5E, 0x01, 0x9C, 0xFF, 0x00, 0x00};
// Split layout, report 2: rx = -350, ry = 175, rz = -175.
constexpr uint8_t kSplitRotation[] = {0x02, 0xA2, 0xFE, 0xAF, 0x00, 0x51, 0xFF};
// Combined layout, report 1: x = 100, y = -350, z = 350, rx = 0, ry = -100, rz = 175.
constexpr uint8_t kCombined[] = {0x01, 0x64, 0x00, 0xA2, 0xFE, 0x5E, 0x01,
                                 0x00, 0x00, 0x9C, 0xFF, 0xAF, 0x00};
// Buttons: bits 0, 2 and 31.
constexpr uint8_t kButtons[] = {0x03, 0x05, 0x00, 0x00, 0x80};
// Out of the usual range: x = 32767, y = -32768, z = 351.
constexpr uint8_t kSplitBeyondFullScale[] = {0x01, 0xFF, 0x7F, 0x00, 0x80, 0x5F, 0x01};

// A state with every field set to something no test report carries.
SpaceMouseState sentinel_state() {
    SpaceMouseState s;
    for (int i = 0; i < 3; ++i) {
        s.translation_raw[i] = static_cast<int16_t>(11 + i);
        s.rotation_raw[i] = static_cast<int16_t>(-21 - i);
        s.translation[i] = 0.125 * (i + 1);
        s.rotation[i] = -0.25 * (i + 1);
    }
    s.buttons = 0xA5A5A5A5u;
    return s;
}

void expect_same(const SpaceMouseState& a, const SpaceMouseState& b) {
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(a.translation_raw[i], b.translation_raw[i]) << i;
        EXPECT_EQ(a.rotation_raw[i], b.rotation_raw[i]) << i;
        EXPECT_EQ(a.translation[i], b.translation[i]) << i;
        EXPECT_EQ(a.rotation[i], b.rotation[i]) << i;
    }
    EXPECT_EQ(a.buttons, b.buttons);
}

TEST(SpaceMouseReport, SplitTranslationReportSetsOnlyTranslation) {
    SpaceMouseState s = sentinel_state();
    const SpaceMouseState before = s;
    ASSERT_TRUE(parse_spacemouse_report(kSplitTranslation, sizeof kSplitTranslation,
                                        SpaceMouseLayout::split, s));
    EXPECT_EQ(s.translation_raw[0], 350);
    EXPECT_EQ(s.translation_raw[1], -100);
    EXPECT_EQ(s.translation_raw[2], 0);
    EXPECT_DOUBLE_EQ(s.translation.x, 1.0);
    EXPECT_DOUBLE_EQ(s.translation.y, -100.0 / 350.0);
    EXPECT_DOUBLE_EQ(s.translation.z, 0.0);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(s.rotation_raw[i], before.rotation_raw[i]);
        EXPECT_EQ(s.rotation[i], before.rotation[i]);
    }
    EXPECT_EQ(s.buttons, before.buttons);
}

TEST(SpaceMouseReport, SplitRotationReportSetsOnlyRotation) {
    SpaceMouseState s = sentinel_state();
    const SpaceMouseState before = s;
    ASSERT_TRUE(parse_spacemouse_report(kSplitRotation, sizeof kSplitRotation,
                                        SpaceMouseLayout::split, s));
    EXPECT_EQ(s.rotation_raw[0], -350);
    EXPECT_EQ(s.rotation_raw[1], 175);
    EXPECT_EQ(s.rotation_raw[2], -175);
    EXPECT_DOUBLE_EQ(s.rotation.x, -1.0);
    EXPECT_DOUBLE_EQ(s.rotation.y, 0.5);
    EXPECT_DOUBLE_EQ(s.rotation.z, -0.5);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(s.translation_raw[i], before.translation_raw[i]);
        EXPECT_EQ(s.translation[i], before.translation[i]);
    }
    EXPECT_EQ(s.buttons, before.buttons);
}

TEST(SpaceMouseReport, CombinedReportSetsAllSixAxes) {
    SpaceMouseState s = sentinel_state();
    ASSERT_TRUE(parse_spacemouse_report(kCombined, sizeof kCombined, SpaceMouseLayout::combined, s));
    const int16_t t[3] = {100, -350, 350};
    const int16_t r[3] = {0, -100, 175};
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(s.translation_raw[i], t[i]) << i;
        EXPECT_EQ(s.rotation_raw[i], r[i]) << i;
        EXPECT_DOUBLE_EQ(s.translation[i], t[i] / 350.0) << i;
        EXPECT_DOUBLE_EQ(s.rotation[i], r[i] / 350.0) << i;
    }
    EXPECT_EQ(s.buttons, 0xA5A5A5A5u);
}

TEST(SpaceMouseReport, CombinedBytesReadAsSplitGiveTranslationOnly) {
    // A split-layout reader ignores bytes past the 7 it needs.
    SpaceMouseState s = sentinel_state();
    const SpaceMouseState before = s;
    ASSERT_TRUE(parse_spacemouse_report(kCombined, sizeof kCombined, SpaceMouseLayout::split, s));
    EXPECT_EQ(s.translation_raw[0], 100);
    EXPECT_EQ(s.translation_raw[1], -350);
    EXPECT_EQ(s.translation_raw[2], 350);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(s.rotation_raw[i], before.rotation_raw[i]);
}

TEST(SpaceMouseReport, RotationReportAcceptedInCombinedLayout) {
    SpaceMouseState s;
    ASSERT_TRUE(parse_spacemouse_report(kSplitRotation, sizeof kSplitRotation,
                                        SpaceMouseLayout::combined, s));
    EXPECT_EQ(s.rotation_raw[0], -350);
}

TEST(SpaceMouseReport, ButtonsReportSetsBitmask) {
    for (SpaceMouseLayout layout : {SpaceMouseLayout::split, SpaceMouseLayout::combined}) {
        SpaceMouseState s = sentinel_state();
        const SpaceMouseState before = s;
        ASSERT_TRUE(parse_spacemouse_report(kButtons, sizeof kButtons, layout, s));
        EXPECT_EQ(s.buttons, 0x80000005u);
        for (int i = 0; i < 3; ++i) {
            EXPECT_EQ(s.translation_raw[i], before.translation_raw[i]);
            EXPECT_EQ(s.rotation_raw[i], before.rotation_raw[i]);
        }
        // Release: all zero.
        const uint8_t released[] = {0x03, 0x00, 0x00, 0x00, 0x00};
        ASSERT_TRUE(parse_spacemouse_report(released, sizeof released, layout, s));
        EXPECT_EQ(s.buttons, 0u);
    }
}

TEST(SpaceMouseReport, ZeroReportsReturnToRest) {
    SpaceMouseState s = sentinel_state();
    const uint8_t zero_combined[13] = {0x01};
    ASSERT_TRUE(parse_spacemouse_report(zero_combined, sizeof zero_combined,
                                        SpaceMouseLayout::combined, s));
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(s.translation_raw[i], 0);
        EXPECT_EQ(s.rotation_raw[i], 0);
        EXPECT_EQ(s.translation[i], 0.0);
        EXPECT_EQ(s.rotation[i], 0.0);
    }
}

TEST(SpaceMouseReport, BeyondFullScaleKeepsRawAndClampsScaled) {
    SpaceMouseState s;
    ASSERT_TRUE(parse_spacemouse_report(kSplitBeyondFullScale, sizeof kSplitBeyondFullScale,
                                        SpaceMouseLayout::split, s));
    EXPECT_EQ(s.translation_raw[0], 32767);
    EXPECT_EQ(s.translation_raw[1], -32768);
    EXPECT_EQ(s.translation_raw[2], 351);
    EXPECT_EQ(s.translation.x, 1.0);
    EXPECT_EQ(s.translation.y, -1.0);
    EXPECT_EQ(s.translation.z, 1.0);
}

TEST(SpaceMouseReport, ShortReportsRejectedAndStateUntouched) {
    struct Case {
        const uint8_t* data;
        size_t size;
        SpaceMouseLayout layout;
    };
    const Case cases[] = {
        {kSplitTranslation, 6, SpaceMouseLayout::split},
        {kSplitTranslation, 1, SpaceMouseLayout::split},
        {kSplitRotation, 6, SpaceMouseLayout::split},
        {kSplitRotation, 6, SpaceMouseLayout::combined},
        {kCombined, 12, SpaceMouseLayout::combined},
        // A 7-byte report 1 is too short for a device that sends the combined layout.
        {kSplitTranslation, sizeof kSplitTranslation, SpaceMouseLayout::combined},
        {kButtons, 4, SpaceMouseLayout::split},
        {kButtons, 1, SpaceMouseLayout::combined},
        {kButtons, 0, SpaceMouseLayout::split},
        {nullptr, 13, SpaceMouseLayout::combined},
    };
    for (const Case& c : cases) {
        SpaceMouseState s = sentinel_state();
        EXPECT_FALSE(parse_spacemouse_report(c.data, c.size, c.layout, s)) << c.size;
        expect_same(s, sentinel_state());
    }
}

TEST(SpaceMouseReport, UnknownReportIdsRejectedAndStateUntouched) {
    for (uint8_t id : {uint8_t{0x00}, uint8_t{0x04}, uint8_t{0x17}, uint8_t{0xFF}}) {
        uint8_t report[13];
        std::memcpy(report, kCombined, sizeof report);
        report[0] = id;
        for (SpaceMouseLayout layout : {SpaceMouseLayout::split, SpaceMouseLayout::combined}) {
            SpaceMouseState s = sentinel_state();
            EXPECT_FALSE(parse_spacemouse_report(report, sizeof report, layout, s)) << int(id);
            expect_same(s, sentinel_state());
        }
    }
}

TEST(SpaceMouseProducts, TableGivesLayoutPerProduct) {
    const uint16_t split[] = {0xC603, 0xC605, 0xC606, 0xC621, 0xC623, 0xC625,
                              0xC626, 0xC627, 0xC628, 0xC629, 0xC62B};
    const uint16_t combined[] = {0xC62E, 0xC62F, 0xC631, 0xC632, 0xC633, 0xC635, 0xC652};
    for (uint16_t vendor : {kSpaceMouseVendorLogitech, kSpaceMouseVendor3Dconnexion}) {
        for (uint16_t p : split) {
            EXPECT_TRUE(is_spacemouse(vendor, p)) << std::hex << p;
            EXPECT_EQ(layout_for_product(vendor, p), SpaceMouseLayout::split) << std::hex << p;
        }
        for (uint16_t p : combined) {
            EXPECT_TRUE(is_spacemouse(vendor, p)) << std::hex << p;
            EXPECT_EQ(layout_for_product(vendor, p), SpaceMouseLayout::combined) << std::hex << p;
        }
    }
}

TEST(SpaceMouseProducts, UnknownDevicesAreNotSpaceMiceAndDefaultToCombined) {
    EXPECT_FALSE(is_spacemouse(0x046D, 0xC077));  // a Logitech product outside the list
    EXPECT_FALSE(is_spacemouse(0x256F, 0xC6FF));
    EXPECT_FALSE(is_spacemouse(0x0403, 0xC626));  // a listed PID under another vendor
    EXPECT_FALSE(is_spacemouse(0x0403, 0xCB48));  // Novint Falcon
    EXPECT_EQ(layout_for_product(0x0403, 0xC626), SpaceMouseLayout::combined);
    EXPECT_EQ(layout_for_product(0x256F, 0xC6FF), SpaceMouseLayout::combined);
}

// A state from scaled deflections (the parser's scaling is tested above).
SpaceMouseState deflected(const Vec3& t, const Vec3& r) {
    SpaceMouseState s;
    s.translation = t;
    s.rotation = r;
    return s;
}

Pose some_pose() {
    Pose p;
    p.position = Vec3(0.01, -0.02, 0.03);
    p.orientation = glm::normalize(Quat(0.9, 0.1, -0.3, 0.2));
    return p;
}

TEST(SpaceMouseMotion, DeadZoneHoldsStill) {
    const SpaceMouseMapping m;
    // 7 counts on every axis, just inside the default 8-count dead zone, both signs.
    const double d = 7.0 / kSpaceMouseFullScale;
    const SpaceMouseState s = deflected(Vec3(d, -d, d), Vec3(-d, d, -d));
    const Pose start = some_pose();
    Pose p = start;
    for (int i = 0; i < 1000; ++i) p = integrate_spacemouse(p, s, 1e-3, m);
    EXPECT_EQ(p.position, start.position);
    EXPECT_EQ(p.orientation.w, start.orientation.w);
    EXPECT_EQ(p.orientation.x, start.orientation.x);
    EXPECT_EQ(p.orientation.y, start.orientation.y);
    EXPECT_EQ(p.orientation.z, start.orientation.z);
    // Just outside the dead zone it moves.
    const double out = 9.0 / kSpaceMouseFullScale;
    const Pose moved = integrate_spacemouse(start, deflected(Vec3(out, 0, 0), Vec3(0)), 1e-3, m);
    EXPECT_GT(moved.position.x, start.position.x);
}

TEST(SpaceMouseMotion, ShapingIsContinuousAndReachesFullScale) {
    const double d = 0.1;
    EXPECT_EQ(spacemouse_shape_axis(0.1, d), 0.0);
    EXPECT_NEAR(spacemouse_shape_axis(0.1 + 1e-9, d), 0.0, 1e-8);
    EXPECT_DOUBLE_EQ(spacemouse_shape_axis(1.0, d), 1.0);
    EXPECT_DOUBLE_EQ(spacemouse_shape_axis(-1.0, d), -1.0);
    EXPECT_DOUBLE_EQ(spacemouse_shape_axis(0.55, d), 0.5);
    EXPECT_DOUBLE_EQ(spacemouse_shape_axis(-0.55, d), -0.5);
    EXPECT_EQ(spacemouse_shape_axis(std::nan(""), d), 0.0);
}

TEST(SpaceMouseMotion, SteadyPushMovesAtDocumentedGain) {
    const SpaceMouseMapping m;
    ASSERT_DOUBLE_EQ(m.translation_gain_m_per_s, 0.05);
    const Pose start = some_pose();
    // Full push along +x for 1 s in 1 ms ticks: 0.05 m along world x, nothing else.
    Pose p = start;
    const SpaceMouseState full = deflected(Vec3(1.0, 0.0, 0.0), Vec3(0.0));
    for (int i = 0; i < 1000; ++i) p = integrate_spacemouse(p, full, 1e-3, m);
    EXPECT_NEAR(p.position.x - start.position.x, 0.05, 1e-12);
    EXPECT_NEAR(p.position.y, start.position.y, 1e-15);
    EXPECT_NEAR(p.position.z, start.position.z, 1e-15);
    EXPECT_NEAR(glm::dot(p.orientation, start.orientation), 1.0, 1e-15);

    // Half push on -z: gain · (0.5 − d) / (1 − d) per second.
    const double d = m.dead_zone;
    p = integrate_spacemouse(start, deflected(Vec3(0.0, 0.0, -0.5), Vec3(0.0)), 0.5, m);
    EXPECT_NEAR(p.position.z - start.position.z, -0.5 * 0.05 * (0.5 - d) / (1.0 - d), 1e-15);

    // A sign flip in the mapping reverses the axis.
    SpaceMouseMapping flipped = m;
    flipped.translation_sign = Vec3(-1.0, 1.0, 1.0);
    p = integrate_spacemouse(start, full, 0.1, flipped);
    EXPECT_NEAR(p.position.x - start.position.x, -0.005, 1e-15);
}

TEST(SpaceMouseMotion, RotationComposesAsUnitQuaternion) {
    const SpaceMouseMapping m;
    ASSERT_DOUBLE_EQ(m.rotation_gain_rad_per_s, 1.0);
    // Full twist about z for 1 s: 1 rad about world z.
    Pose p;
    const SpaceMouseState twist = deflected(Vec3(0.0), Vec3(0.0, 0.0, 1.0));
    for (int i = 0; i < 1000; ++i) {
        p = integrate_spacemouse(p, twist, 1e-3, m);
        ASSERT_NEAR(glm::length(p.orientation), 1.0, 1e-14);
    }
    const Quat expected = glm::angleAxis(1.0, Vec3(0.0, 0.0, 1.0));
    EXPECT_NEAR(std::fabs(glm::dot(p.orientation, expected)), 1.0, 1e-12);
    EXPECT_EQ(p.position, Vec3(0.0));

    // A steady oblique twist from a tilted start: stays unit over a long run and equals one
    // rotation by the total rotation vector applied on the left (world frame).
    const Pose start = some_pose();
    const Vec3 r(0.7, -0.4, 0.3);
    const SpaceMouseState oblique = deflected(Vec3(0.0), r);
    p = start;
    for (int i = 0; i < 5000; ++i) p = integrate_spacemouse(p, oblique, 1e-3, m);
    EXPECT_NEAR(glm::length(p.orientation), 1.0, 1e-14);
    Vec3 w;
    for (int i = 0; i < 3; ++i) w[i] = spacemouse_shape_axis(r[i], m.dead_zone);
    const Quat total = glm::angleAxis(5.0 * glm::length(w), glm::normalize(w));
    EXPECT_NEAR(std::fabs(glm::dot(p.orientation, total * start.orientation)), 1.0, 1e-12);
}

TEST(SpaceMouseMotion, ToolFrameMovesAlongTheToolAxes) {
    SpaceMouseMapping m;
    m.tool_frame = true;
    Pose start;
    start.orientation = glm::angleAxis(0.5 * M_PI, Vec3(0.0, 0.0, 1.0));  // tool x = world y
    const Pose p = integrate_spacemouse(start, deflected(Vec3(1.0, 0.0, 0.0), Vec3(0.0)), 1.0, m);
    EXPECT_NEAR(p.position.x, 0.0, 1e-15);
    EXPECT_NEAR(p.position.y, 0.05, 1e-15);
    // A twist about the tool's x is a twist about world y here.
    const Pose q = integrate_spacemouse(start, deflected(Vec3(0.0), Vec3(1.0, 0.0, 0.0)), 0.3, m);
    const Quat expected = glm::angleAxis(0.3, Vec3(0.0, 1.0, 0.0)) * start.orientation;
    EXPECT_NEAR(std::fabs(glm::dot(q.orientation, expected)), 1.0, 1e-14);
}

TEST(SpaceMouseMotion, BadTimeStepOrMappingLeavesPoseUnchanged) {
    const Pose start = some_pose();
    const SpaceMouseState s = deflected(Vec3(1.0), Vec3(1.0));
    SpaceMouseMapping m;
    for (double dt : {0.0, -1e-3, std::nan(""), HUGE_VAL}) {
        const Pose p = integrate_spacemouse(start, s, dt, m);
        EXPECT_EQ(p.position, start.position) << dt;
        EXPECT_EQ(p.orientation, start.orientation) << dt;
    }
    m.translation_gain_m_per_s = std::nan("");
    const Pose p = integrate_spacemouse(start, s, 1e-3, m);
    EXPECT_EQ(p.position, start.position);
    EXPECT_EQ(p.orientation, start.orientation);
}

}  // namespace
}  // namespace sulcus
