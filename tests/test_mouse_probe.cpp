// MouseProbeDriver: each input mapping against poses worked out by hand, the tip staying put
// under turns, the cursor-following drag, the fine modifier, and rejected (non-finite) input.
#include "sulcus/app/mouse_probe.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace sulcus {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kTol = 1e-15;  // metres or quaternion components: a few ulps of the values here

void expect_vec(const Vec3& got, const Vec3& want, double tol = kTol) {
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}

void expect_quat(const Quat& got, const Quat& want, double tol = kTol) {
    EXPECT_NEAR(got.w, want.w, tol);
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}

bool same_bits(const Pose& a, const Pose& b) { return std::memcmp(&a, &b, sizeof(Pose)) == 0; }

// The default camera: looking down -Z, +Y up, 0.1 mm per pixel.
ViewBasis front_view() { return ViewBasis{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, -1), 1e-4}; }
// Looking along +X from the -X side: right = +Z (right x up = -forward holds).
ViewBasis side_view() { return ViewBasis{Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0), 2e-5}; }

const Vec3 kHome(0.01, 0.02, 0.03);

TEST(MouseProbe, DragMovesTheTipInTheViewPlaneByMetresPerPixel) {
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.drag(10.0, 5.0, front_view()));
    // 10 px right: +1 mm along right; 5 px down: -0.5 mm along up.
    expect_vec(d.pose().position, Vec3(0.011, 0.0195, 0.03));
    EXPECT_EQ(d.pose().orientation, Quat(1, 0, 0, 0));

    // N pixels: N * metres_per_pixel along the right / up vectors of another view.
    const ViewBasis v = side_view();
    const int n = 37;
    Vec3 before = d.pose().position;
    ASSERT_TRUE(d.drag(n, 0.0, v));
    expect_vec(d.pose().position - before, v.right * (n * v.metres_per_pixel));
    before = d.pose().position;
    ASSERT_TRUE(d.drag(0.0, -n, v));  // cursor up
    expect_vec(d.pose().position - before, v.up * (n * v.metres_per_pixel));

    // Axes that are not unit length are normalised: the pixel size alone sets the distance.
    ViewBasis scaled = front_view();
    scaled.right *= 3.0;
    scaled.up *= 0.5;
    before = d.pose().position;
    ASSERT_TRUE(d.drag(4.0, -2.0, scaled));
    expect_vec(d.pose().position - before, Vec3(4e-4, 2e-4, 0.0));
}

TEST(MouseProbe, WheelMovesTheTipAlongTheViewDirection) {
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.wheel(2.0, front_view()));  // into the scene: -Z, 2 x 0.5 mm
    expect_vec(d.pose().position, Vec3(0.01, 0.02, 0.029));
    ASSERT_TRUE(d.wheel(-4.0, side_view()));  // toward the viewer on the side view: -X, 2 mm
    expect_vec(d.pose().position, Vec3(0.008, 0.02, 0.029));
    EXPECT_EQ(d.pose().orientation, Quat(1, 0, 0, 0));
}

TEST(MouseProbe, TiltTurnsAboutTheTipEndAsATrackball) {
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    // 100 px right at 0.005 rad/px: 0.5 rad about the view's up (+Y).
    ASSERT_TRUE(d.tilt(100.0, 0.0, front_view()));
    expect_quat(d.pose().orientation, Quat(std::cos(0.25), 0.0, std::sin(0.25), 0.0));
    EXPECT_EQ(d.pose().apply(Vec3(0.0)), kHome);  // the tip stays put
    // The side facing the viewer (+Z) swung toward screen right.
    expect_vec(d.pose().rotate(Vec3(0, 0, 1)), Vec3(std::sin(0.5), 0.0, std::cos(0.5)));

    // 100 px down: 0.5 rad about the view's right (+X); the handle (+Y) tips toward the viewer.
    d.set_pose(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.tilt(0.0, 100.0, front_view()));
    expect_quat(d.pose().orientation, Quat(std::cos(0.25), std::sin(0.25), 0.0, 0.0));
    EXPECT_EQ(d.pose().apply(Vec3(0.0)), kHome);
    expect_vec(d.pose().rotate(Vec3(0, 1, 0)), Vec3(0.0, std::cos(0.5), std::sin(0.5)));
    expect_vec(d.pose().rotate(Vec3(0, 0, 1)), Vec3(0.0, -std::sin(0.5), std::cos(0.5)));  // front goes down

    // Both at once: the turn about up after the turn about right (a = 0.1 rad, b = 0.2 rad):
    // (cos a/2, 0, sin a/2, 0) * (cos b/2, sin b/2, 0, 0).
    d.set_pose(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.tilt(20.0, 40.0, front_view()));
    const double ca = std::cos(0.05), sa = std::sin(0.05), cb = std::cos(0.1), sb = std::sin(0.1);
    expect_quat(d.pose().orientation, Quat(ca * cb, ca * sb, sa * cb, -sa * sb));
    EXPECT_EQ(d.pose().apply(Vec3(0.0)), kHome);
}

TEST(MouseProbe, InsertKeysMoveAlongTheProbesOwnShaftTowardTheTip) {
    // Probe turned 90 degrees about +Z: its +Y (toward the handle) points along world -X, so
    // insertion (-Y) is world +X.
    const Quat q = glm::angleAxis(kPi / 2, Vec3(0, 0, 1));
    MouseProbeDriver d(Pose{kHome, q});
    ASSERT_TRUE(d.key_insert(3.0));
    expect_vec(d.pose().position, Vec3(0.0103, 0.02, 0.03));
    ASSERT_TRUE(d.key_insert(-1.0));  // withdraw
    expect_vec(d.pose().position, Vec3(0.0102, 0.02, 0.03));
    EXPECT_EQ(d.pose().orientation, q);
}

TEST(MouseProbe, RotateKeysTurnAboutTheShaftFiveDegreesPerStep) {
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.key_rotate(2.0));  // 10 degrees about +Y
    const double h = 5.0 * kPi / 180.0;
    expect_quat(d.pose().orientation, Quat(std::cos(h), 0.0, std::sin(h), 0.0));
    EXPECT_EQ(d.pose().position, kHome);

    // About the probe's own axis, wherever it points: the shaft keeps its direction, the tip its place.
    const Quat q = glm::angleAxis(kPi / 2, Vec3(0, 0, 1));
    d.set_pose(Pose{kHome, q});
    ASSERT_TRUE(d.key_rotate(1.0));
    expect_quat(d.pose().orientation, q * Quat(std::cos(h / 2), 0.0, std::sin(h / 2), 0.0));
    expect_vec(d.pose().rotate(Vec3(0, 1, 0)), Vec3(-1.0, 0.0, 0.0));
    EXPECT_EQ(d.pose().position, kHome);
}

TEST(MouseProbe, FineModifierScalesEveryMotionByATenth) {
    const ViewBasis v = front_view();
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.drag(10.0, 0.0, v, true));
    expect_vec(d.pose().position, kHome + Vec3(1e-4, 0.0, 0.0));
    ASSERT_TRUE(d.wheel(1.0, v, true));
    expect_vec(d.pose().position, kHome + Vec3(1e-4, 0.0, -0.5e-4));
    ASSERT_TRUE(d.key_insert(1.0, true));  // identity: insertion is -Y
    expect_vec(d.pose().position, kHome + Vec3(1e-4, -1e-5, -0.5e-4));

    const Vec3 p = d.pose().position;
    ASSERT_TRUE(d.tilt(100.0, 0.0, v, true));  // 0.05 rad
    expect_quat(d.pose().orientation, Quat(std::cos(0.025), 0.0, std::sin(0.025), 0.0));
    d.set_pose(Pose{p, Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.key_rotate(1.0, true));  // 0.5 degree
    const double h = 0.25 * kPi / 180.0;
    expect_quat(d.pose().orientation, Quat(std::cos(h), 0.0, std::sin(h), 0.0));
    EXPECT_EQ(d.pose().position, p);
}

TEST(MouseProbe, NonFiniteInputIsIgnoredAndCounted) {
    MouseProbeDriver d(Pose{kHome, glm::angleAxis(0.3, glm::normalize(Vec3(1, 2, 3)))});
    const Pose before = d.pose();
    ViewBasis bad_pixel = front_view();
    bad_pixel.metres_per_pixel = kNan;
    ViewBasis zero_right = front_view();
    zero_right.right = Vec3(0.0);
    ViewBasis nan_forward = front_view();
    nan_forward.forward.y = kNan;

    EXPECT_FALSE(d.drag(kNan, 1.0, front_view()));
    EXPECT_FALSE(d.drag(1.0, std::numeric_limits<double>::infinity(), front_view()));
    EXPECT_FALSE(d.drag(1.0, 1.0, bad_pixel));
    EXPECT_FALSE(d.drag(1.0, 1.0, zero_right));
    EXPECT_FALSE(d.wheel(kNan, front_view()));
    EXPECT_FALSE(d.wheel(1.0, nan_forward));
    EXPECT_FALSE(d.tilt(kNan, 0.0, front_view()));
    EXPECT_FALSE(d.tilt(1.0, 1.0, zero_right));
    EXPECT_FALSE(d.key_insert(kNan));
    EXPECT_FALSE(d.key_rotate(-std::numeric_limits<double>::infinity()));
    EXPECT_FALSE(d.set_pose(Pose{Vec3(kNan), Quat(1, 0, 0, 0)}));
    EXPECT_FALSE(d.set_pose(Pose{Vec3(0.0), Quat(0, 0, 0, 0)}));
    EXPECT_FALSE(d.reset(Pose{Vec3(0.0), Quat(kNan, 0, 0, 0)}));
    EXPECT_TRUE(same_bits(d.pose(), before));
    EXPECT_EQ(d.rejected_inputs(), 13u);

    // And the driver still works afterwards.
    ASSERT_TRUE(d.drag(1.0, 0.0, front_view()));
    expect_vec(d.pose().position, kHome + Vec3(1e-4, 0.0, 0.0));
}

TEST(MouseProbe, KeepsTheQuaternionUnitOverManyTurns) {
    MouseProbeDriver d(Pose{kHome, Quat(1, 0, 0, 0)});
    ViewBasis v = side_view();
    for (int i = 0; i < 20000; ++i) {
        d.tilt(std::sin(0.37 * i) * 13.0, std::cos(0.11 * i) * 7.0, v, i % 3 == 0);
        d.key_rotate(i % 5 == 0 ? 1.0 : -0.7, i % 2 == 0);
        ASSERT_NEAR(glm::length(d.pose().orientation), 1.0, 1e-14) << "input " << i;
    }
    EXPECT_EQ(d.pose().position, kHome);  // only turns: the tip never moved
}

TEST(MouseProbe, SetPoseNormalisesAndResetSetsHome) {
    MouseProbeDriver d;
    ASSERT_TRUE(d.set_pose(Pose{Vec3(0.001, 0.0, 0.0), Quat(0.0, 0.0, 2.0, 0.0)}));
    EXPECT_EQ(d.pose().orientation, Quat(0.0, 0.0, 1.0, 0.0));
    d.drag(5.0, 5.0, front_view());
    const Pose home{Vec3(0.0, 0.005, 0.0), glm::angleAxis(0.2, Vec3(1, 0, 0))};
    ASSERT_TRUE(d.reset(home));
    EXPECT_TRUE(same_bits(d.pose(), home));
    EXPECT_TRUE(same_bits(d.home(), home));
}

TEST(MouseProbe, BoundsKeepTheTipInsideTheBox) {
    MouseProbeDriver d(Pose{Vec3(0.0), Quat(1, 0, 0, 0)});
    ASSERT_TRUE(d.set_bounds(Vec3(-0.01), Vec3(0.01)));
    d.drag(1000.0, -50.0, front_view());  // 10 cm right, 5 mm up
    EXPECT_EQ(d.pose().position, Vec3(0.01, 0.005, 0.0));
    d.wheel(-100.0, front_view());  // 5 cm toward the viewer
    EXPECT_EQ(d.pose().position, Vec3(0.01, 0.005, 0.01));
    d.clear_bounds();
    d.drag(1000.0, 0.0, front_view());
    EXPECT_NEAR(d.pose().position.x, 0.11, kTol);
}

}  // namespace
}  // namespace sulcus
