// The app's headless view math: the orbit camera, the sextant presets and the force history the
// plots draw.
#include "desktop/camera.h"
#include "desktop/force_history.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace sulcus;
using namespace sulcus::desktop;

TEST(AppView, SextantOfEveryTooth) {
    EXPECT_EQ(sextant_of(18), 1);
    EXPECT_EQ(sextant_of(14), 1);
    EXPECT_EQ(sextant_of(13), 2);
    EXPECT_EQ(sextant_of(11), 2);
    EXPECT_EQ(sextant_of(23), 2);
    EXPECT_EQ(sextant_of(24), 3);
    EXPECT_EQ(sextant_of(38), 4);
    EXPECT_EQ(sextant_of(33), 5);
    EXPECT_EQ(sextant_of(43), 5);
    EXPECT_EQ(sextant_of(44), 6);
    EXPECT_EQ(sextant_of(47), 6);
    EXPECT_EQ(sextant_of(9), 0);
    EXPECT_EQ(sextant_of(49), 0);
}

TEST(AppView, CameraBasisIsRightHandedAndLooksAtTheTarget) {
    OrbitCamera c;
    c.target = Vec3(0.01, 0.02, -0.03);
    c.yaw_rad = 0.7;
    c.pitch_rad = 0.4;
    c.distance_m = 0.05;
    EXPECT_NEAR(glm::length(c.eye() - c.target), 0.05, 1e-15);
    EXPECT_NEAR(glm::length(glm::cross(c.right(), c.up()) + c.forward()), 0.0, 1e-12);  // r x u = -f
    EXPECT_NEAR(glm::dot(c.right(), Vec3(0, 1, 0)), 0.0, 1e-12);                        // no roll
    // The view matrix puts the target on the axis, in front (-Z in eye space).
    const glm::dvec4 t = c.view() * glm::dvec4(c.target, 1.0);
    EXPECT_NEAR(t.x, 0.0, 1e-12);
    EXPECT_NEAR(t.y, 0.0, 1e-12);
    EXPECT_NEAR(t.z, -0.05, 1e-12);
}

TEST(AppView, MetresPerPixelAtTheTarget) {
    OrbitCamera c;
    c.distance_m = 0.1;
    c.fov_y_rad = 2.0 * std::atan(0.5);  // the view is exactly one distance tall
    EXPECT_NEAR(c.metres_per_pixel(c.target, 1000.0), 0.1 / 1000.0, 1e-15);
}

TEST(AppView, PanMovesTheTargetWithTheCursor) {
    OrbitCamera c;
    c.yaw_rad = 0.3;
    const Vec3 before = c.target;
    const double m = c.metres_per_pixel(c.target, 800.0);
    c.pan(10.0, 0.0, 800.0);
    // Dragging right moves the scene right: the target goes left by 10 pixels' worth.
    EXPECT_NEAR(glm::length(c.target - (before - 10.0 * m * c.right())), 0.0, 1e-15);
}

TEST(AppView, OrbitPitchStopsShortOfThePoles) {
    OrbitCamera c;
    c.orbit(0.0, 1e6);
    EXPECT_LT(c.pitch_rad, 0.5 * std::numbers::pi);
    EXPECT_TRUE(std::isfinite(c.right().x));
    c.orbit(0.0, -2e6);
    EXPECT_GT(c.pitch_rad, -0.5 * std::numbers::pi);
}

TEST(AppView, SextantViewLooksAtItsTeethFromBuccalOrLingual) {
    std::vector<ToothSpot> teeth = {
        {44, Vec3(-0.018, 0, -0.012), glm::normalize(Vec3(-0.86, 0, 0.51))},
        {46, Vec3(-0.025, 0, -0.026), glm::normalize(Vec3(-0.93, 0, 0.38))},
        {11, Vec3(-0.004, 0.022, 0.01), Vec3(0, 0, 1)},
    };
    OrbitCamera cam;
    ASSERT_TRUE(sextant_view(teeth, 6, false, cam));
    // Target between 44 and 46; the eye on their buccal side and above them (lower jaw).
    EXPECT_NEAR(cam.target.x, -0.0215, 1e-12);
    const Vec3 to_eye = cam.eye() - cam.target;
    EXPECT_GT(glm::dot(to_eye, Vec3(-0.9, 0, 0.45)), 0.0);
    EXPECT_GT(to_eye.y, 0.0);
    ASSERT_TRUE(sextant_view(teeth, 6, true, cam));
    EXPECT_LT(glm::dot(cam.eye() - cam.target, Vec3(-0.9, 0, 0.45)), 0.0);
    // An upper sextant is seen from below.
    ASSERT_TRUE(sextant_view(teeth, 2, false, cam));
    EXPECT_LT((cam.eye() - cam.target).y, 0.0);
    // No tooth in sextant 3.
    EXPECT_FALSE(sextant_view(teeth, 3, false, cam));
}

TEST(AppView, ForceHistoryKeepsTheLatestAndItsPeaks) {
    ForceHistory h(100);
    for (int i = 0; i < 250; ++i) h.push({i * 1e-3, float(i == 240 ? 0.9 : 0.1), 0.0f});
    ASSERT_EQ(h.size(), 100u);
    EXPECT_DOUBLE_EQ(h.at(0).time_s, 150e-3);
    EXPECT_DOUBLE_EQ(h.latest()->time_s, 249e-3);
    std::vector<float> lo, hi;
    // 100 ms into 4 columns: the peak at 240 ms stays in its column however few pixels there are.
    h.envelope(0.249, 0.1, 4, false, lo, hi);
    ASSERT_EQ(hi.size(), 4u);
    EXPECT_FLOAT_EQ(hi[3], 0.9f);
    EXPECT_FLOAT_EQ(lo[3], 0.1f);
    EXPECT_FLOAT_EQ(hi[0], 0.1f);
    // An empty slice is NaN (nothing drawn), not zero.
    h.envelope(1.0, 0.1, 4, false, lo, hi);
    EXPECT_TRUE(std::isnan(hi[0]));
}

TEST(AppView, ForceHistoryTimeAboveAThreshold) {
    ForceHistory h(1000);
    // 1 kHz; 0.3 N from 100 to 199 ms.
    for (int i = 0; i < 500; ++i) h.push({i * 1e-3, float(i >= 100 && i < 200 ? 0.3 : 0.1), 0.0f});
    EXPECT_NEAR(h.time_above(0.499, 1.0, 0.25), 0.100, 1e-9);
    EXPECT_NEAR(h.time_above(0.499, 1.0, 0.35), 0.0, 1e-12);
}
