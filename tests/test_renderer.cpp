// The servo step against analytic answers: free motion, pressing, frictionless sliding,
// twisting, concave corners, convex edges (the local solution), thin plates, bad input and
// determinism.
#include "scene_helpers.h"
#include "sulcus/engine/exact_check.h"

#include <cstring>

using namespace sulcus;
using namespace sulcus::test;

namespace {

// A 10 mm cube tool and a floor whose top face is y = 0.
struct FloorScene {
    TriMesh tool = make_box(Vec3(5 * mm));
    TriMesh floor = make_box(Vec3(50 * mm, 10 * mm, 50 * mm), Vec3(0, -10 * mm, 0));
    std::unique_ptr<Model> model = model_of(tool, {object("floor", floor)});

    double penetration(const Pose& p) const {
        return exact_check(tool, p, {PlacedMesh{&floor, Pose{}}}, 0.0).penetration_m;
    }
};

bool same_bits(const Pose& a, const Pose& b) {
    return std::memcmp(&a.position, &b.position, sizeof(Vec3)) == 0 &&
           std::memcmp(&a.orientation, &b.orientation, sizeof(Quat)) == 0;
}

}  // namespace

TEST(Renderer, FreeMotionFollowsTheHapticToolExactly) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 20 * mm, 0)));
    for (int i = 0; i < 500; ++i) {
        const double t = i * 1e-3;
        const Pose h = pose(Vec3(3 * mm * std::sin(7 * t), 20 * mm + 2 * mm * std::cos(5 * t), mm * t),
                            axis_angle(Vec3(1, 1, 0), 0.8 * std::sin(3 * t)));
        const StepResult r = step(*s.model, st, h);
        EXPECT_EQ(r.status, StepStatus::Free);
        EXPECT_TRUE(same_bits(r.graphic, h)) << i;
        EXPECT_EQ(glm::length(r.force_N), 0.0);
        EXPECT_EQ(glm::length(r.torque_Nm), 0.0);
    }
}

TEST(Renderer, PressingOnAFloorStopsAtTheSurfaceWithForceKTimesDepth) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 6 * mm, 0)));
    StepResult r;
    // Descend 3 mm over 300 ticks: the last 2 mm are inside the floor.
    for (int i = 1; i <= 300; ++i) r = step(*s.model, st, pose(Vec3(0, 6 * mm - i * 0.01 * mm, 0)));
    EXPECT_EQ(r.status, StepStatus::Contact);
    EXPECT_NEAR(r.graphic.position.y, 5 * mm, 1e-9);
    EXPECT_LE(s.penetration(r.graphic), 1e-7);
    const double k = s.model->settings.haptic.stiffness_N_per_m;
    EXPECT_NEAR(r.force_N.y, k * 2 * mm, 1e-6);
    EXPECT_NEAR(r.force_N.x, 0.0, 1e-9);
    EXPECT_NEAR(r.force_N.z, 0.0, 1e-9);
    EXPECT_NEAR(glm::length(r.torque_Nm), 0.0, 1e-9);
    EXPECT_GE(r.contacts, 3);
}

TEST(Renderer, SlidesWithoutFrictionAlongTheSurface) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 5 * mm, 0)));
    for (int i = 1; i <= 1000; ++i) {
        // Pressed 1 mm into the floor, moving 10 mm along x and 4 mm along z.
        const Pose h = pose(Vec3(i * 0.01 * mm, 4 * mm, i * 0.004 * mm));
        const StepResult r = step(*s.model, st, h);
        EXPECT_NEAR(r.graphic.position.x, h.position.x, 1e-9) << i;
        EXPECT_NEAR(r.graphic.position.z, h.position.z, 1e-9) << i;
        EXPECT_NEAR(r.graphic.position.y, 5 * mm, 1e-9) << i;
        EXPECT_NEAR(r.force_N.x, 0.0, 1e-6) << i;
        EXPECT_NEAR(r.force_N.z, 0.0, 1e-6) << i;
        EXPECT_LE(s.penetration(r.graphic), 1e-7) << i;
    }
}

TEST(Renderer, TwistsFreelyAboutTheContactNormal) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 5 * mm, 0)));
    for (int i = 1; i <= 500; ++i) {
        const double a = i * 1e-3;  // up to 0.5 rad about +Y while pressed 1 mm in
        const StepResult r = step(*s.model, st, pose(Vec3(0, 4 * mm, 0), axis_angle(Vec3(0, 1, 0), a)));
        const Vec3 rv = glm::axis(r.graphic.orientation) * glm::angle(r.graphic.orientation);
        EXPECT_NEAR(rv.y, a, 1e-7) << i;
        EXPECT_NEAR(r.torque_Nm.y, 0.0, 1e-8) << i;
        EXPECT_LE(s.penetration(r.graphic), 1e-7) << i;
    }
}

TEST(Renderer, TiltingIntoTheFloorPivotsOnAnEdgeWithoutPenetrating) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 5 * mm, 0)));
    StepResult r;
    for (int i = 1; i <= 400; ++i) {
        const double a = i * 1e-3;  // roll about +Z while pressed in
        r = step(*s.model, st, pose(Vec3(0, 4.5 * mm, 0), axis_angle(Vec3(0, 0, 1), a)));
        EXPECT_LE(s.penetration(r.graphic), 1e-7) << i;
    }
    // A torque resists the roll and a force holds the tool up.
    EXPECT_GT(r.force_N.y, 0.0);
    EXPECT_LT(r.torque_Nm.z, 0.0);
}

TEST(Renderer, ConcaveCornerHoldsBothFaces) {
    // Floor y < 0 and a wall x > 0: the cube pushed into the corner.
    const TriMesh tool = make_box(Vec3(5 * mm));
    const std::vector<Vec2> ell = {{-50 * mm, -20 * mm}, {50 * mm, -20 * mm}, {50 * mm, 30 * mm},
                                   {0, 30 * mm},         {0, 0},              {-50 * mm, 0}};
    const TriMesh corner = make_extruded_polygon(ell, -30 * mm, 30 * mm);
    auto model = model_of(tool, {object("corner", corner)});
    State st = make_state(pose(Vec3(-8 * mm, 8 * mm, 0)));
    StepResult r;
    for (int i = 1; i <= 400; ++i) {
        const double f = i / 400.0;
        r = step(*model, st, pose(Vec3(-8 * mm + f * 5 * mm, 8 * mm - f * 5 * mm, 0)));
    }
    EXPECT_NEAR(r.graphic.position.x, -5 * mm, 1e-9);
    EXPECT_NEAR(r.graphic.position.y, 5 * mm, 1e-9);
    const double k = model->settings.haptic.stiffness_N_per_m;
    EXPECT_NEAR(r.force_N.x, -k * 2 * mm, 1e-6);
    EXPECT_NEAR(r.force_N.y, k * 2 * mm, 1e-6);
    EXPECT_GE(r.stats.regions, 1);
}

TEST(Renderer, ConvexEdgeGivesTheLocalSolution) {
    // A step: top face y = 0 for x < 0, falling to y = -20 mm. The haptic tool moves from above
    // the top face to below and beyond the edge; the graphic tool must come round the edge (over
    // it, then down), never through it, and end at the haptic pose once that is free. With the
    // paper's box the tool cannot turn (the haptic tool does not), so its centre stays above the
    // top face until it is past the edge; without the box it may roll round the edge.
    const TriMesh tool = make_box(Vec3(2 * mm));
    const std::vector<Vec2> step_profile = {{-40 * mm, -40 * mm}, {40 * mm, -40 * mm}, {40 * mm, -20 * mm},
                                            {0, -20 * mm},        {0, 0},              {-40 * mm, 0}};
    const TriMesh solid = make_extruded_polygon(step_profile, -20 * mm, 20 * mm);
    for (const LocalBox box : {LocalBox::None, LocalBox::Paper}) {
        RendererSettings settings;
        settings.local_box = box;
        auto model = model_of(tool, {object("step", solid)}, settings);
        State st = make_state(pose(Vec3(-6 * mm, 2 * mm, 0)));
        StepResult r;
        const int n = 2000;
        for (int i = 1; i <= n; ++i) {
            const double f = static_cast<double>(i) / n;
            // Press 1 mm into the top, then head for a point beside the wall, 10 mm down.
            const Pose h = pose(Vec3(-6 * mm + f * 10 * mm, 1 * mm - f * 11 * mm, 0));
            r = step(*model, st, h);
            const double pen = exact_check(tool, r.graphic, {PlacedMesh{&solid, Pose{}}}, 0.0).penetration_m;
            ASSERT_LE(pen, 1e-7) << i;
            // Never on the far side of the top face or the wall.
            EXPECT_FALSE(r.graphic.position.x < 0.0 && r.graphic.position.y < 0.0) << i;
            if (box == LocalBox::Paper && r.graphic.position.y < 2 * mm - 1e-7) {
                EXPECT_GE(r.graphic.position.x, 2 * mm - 1e-7) << i;
            }
        }
        for (int i = 0; i < 50; ++i) r = step(*model, st, pose(Vec3(4 * mm, -10 * mm, 0)));
        EXPECT_NEAR(r.graphic.position.x, 4 * mm, 1e-9);
        EXPECT_NEAR(r.graphic.position.y, -10 * mm, 1e-9);
    }
}

// The force-continuity box holds the tool short of the floor it presses on. Within the contact
// distance of it the tool is in contact (as the step counts contacts) and stays where the box
// holds it, the force continuous; further off, touching nothing, it is released onto the floor.
TEST(Renderer, AToolHeldWithinTheContactDistanceIsNotReleased) {
    FloorScene s;
    RendererSettings settings;
    settings.force_step_margin_m = 0.3e-6;  // the box lets the tool move 0.17 um a tick
    auto model = model_of(s.tool, {object("floor", s.floor)}, settings);
    const double room = settings.force_step_margin_m / std::sqrt(3.0);
    const Pose haptic = pose(Vec3(0, 4 * mm, 0));  // pressing 1 mm into the floor, not moving
    for (const double above : {0.5e-6, 5e-6}) {
        State st = make_state(pose(Vec3(0, 5 * mm + above, 0)));
        st.last_haptic = haptic;
        const StepResult r = step(*model, st, haptic);
        const double gap = r.graphic.position.y - 5 * mm;
        EXPECT_LE(s.penetration(r.graphic), 1e-7) << above;
        if (above < settings.contact_distance_m) {
            EXPECT_FALSE(r.stats.released) << above;
            EXPECT_EQ(r.status, StepStatus::Contact) << above;
            EXPECT_NEAR(gap, above - room, 1e-12) << above;
        } else {
            EXPECT_TRUE(r.stats.released) << above;
            EXPECT_EQ(r.status, StepStatus::Contact) << above;
            EXPECT_LE(std::abs(gap), 2 * settings.constraint_tol_m) << above;
        }
    }
}

// The same scene turned as a whole gives the same motion turned (the default step works in the
// tool's frame); the paper's box, on the world axes, does not have this property.
TEST(Renderer, RigidMotionOfTheWholeSceneChangesNothing) {
    const TriMesh tool = make_box(Vec3(1 * mm, 3 * mm, 0.5 * mm));
    const std::vector<Vec2> step_profile = {{-40 * mm, -40 * mm}, {40 * mm, -40 * mm}, {40 * mm, -20 * mm},
                                            {0, -20 * mm},        {0, 0},              {-40 * mm, 0}};
    const TriMesh solid = make_extruded_polygon(step_profile, -20 * mm, 20 * mm);
    const Quat turn = axis_angle(Vec3(1, 2, 3), 0.7);
    const Vec3 shift(10 * mm, -20 * mm, 5 * mm);
    const Pose placed{shift, turn};
    auto plain = model_of(tool, {object("step", solid)});
    auto turned = model_of(tool, {object("step", solid, placed)});
    const Quat lean = axis_angle(Vec3(0, 0, 1), 0.4);
    State a = make_state(pose(Vec3(-6 * mm, 4 * mm, 0), lean));
    State b = make_state(Pose{placed.apply(Vec3(-6 * mm, 4 * mm, 0)), turn * lean});
    double worst = 0.0;
    for (int i = 1; i <= 1500; ++i) {
        const double f = i / 1500.0;
        const Vec3 p(-6 * mm + f * 9 * mm, 2.5 * mm - f * 6 * mm, 0.5 * mm * f);
        const StepResult ra = step(*plain, a, pose(p, lean));
        const StepResult rb = step(*turned, b, Pose{placed.apply(p), turn * lean});
        worst = std::max(worst, glm::length(placed.apply(ra.graphic.position) - rb.graphic.position));
        worst = std::max(worst, glm::length(turn * ra.force_N - rb.force_N) / 1000.0);
    }
    EXPECT_LT(worst, 1e-9);
}

TEST(Renderer, ThinPlateStruckAtOneMetrePerSecondHolds) {
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh plate = make_box(Vec3(20 * mm, 0.025 * mm, 20 * mm));
    auto model = model_of(tool, {object("plate", plate)});
    State st = make_state(pose(Vec3(0, 10 * mm, 0)));
    StepResult r;
    for (int i = 1; i <= 30; ++i) {
        r = step(*model, st, pose(Vec3(0, 10 * mm - i * 1 * mm, 0)));  // 1 mm per tick
        EXPECT_GE(r.graphic.position.y, 2.525 * mm - 1e-7) << i;
    }
    EXPECT_NEAR(r.graphic.position.y, 2.525 * mm, 1e-9);
    EXPECT_NEAR(r.force_N.y, 1000.0 * (2.525 * mm + 20 * mm), 1e-5);
}

TEST(Renderer, BadHapticInputKeepsTheLastPoseAndAFiniteForce) {
    FloorScene s;
    State st = make_state(pose(Vec3(0, 5 * mm, 0)));
    step(*s.model, st, pose(Vec3(0, 4 * mm, 0)));
    const Pose before = st.graphic;
    const double nan = std::nan("");
    for (const Pose& bad : {pose(Vec3(nan, 0, 0)), pose(Vec3(0, 0, 0), Quat(nan, 0, 0, 0)),
                            pose(Vec3(0, 0, 0), Quat(2, 0, 0, 0)), pose(Vec3(1e308 * 10, 0, 0))}) {
        const StepResult r = step(*s.model, st, bad);
        EXPECT_EQ(r.status, StepStatus::BadInput);
        EXPECT_TRUE(same_bits(r.graphic, before));
        EXPECT_TRUE(std::isfinite(r.force_N.x) && std::isfinite(r.force_N.y) && std::isfinite(r.force_N.z));
    }
}

TEST(Renderer, StepsAreDeterministic) {
    FloorScene s;
    auto run = [&] {
        State st = make_state(pose(Vec3(0, 6 * mm, 0)));
        std::vector<StepResult> out;
        for (int i = 1; i <= 600; ++i) {
            const double t = i * 1e-3;
            out.push_back(step(*s.model, st, pose(Vec3(4 * mm * std::sin(3 * t), 4.5 * mm, 2 * mm * t),
                                                  axis_angle(Vec3(0.2, 1, 0.1), 0.3 * t))));
        }
        return out;
    };
    const auto a = run(), b = run();
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_TRUE(same_bits(a[i].graphic, b[i].graphic)) << i;
        EXPECT_EQ(std::memcmp(&a[i].force_N, &b[i].force_N, sizeof(Vec3)), 0) << i;
        EXPECT_EQ(a[i].status, b[i].status);
    }
}
