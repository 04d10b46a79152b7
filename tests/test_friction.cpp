// Coulomb friction inside the configuration-based step: a block dragged along a surface with a
// known normal force feels mu N, sticks below the static limit, and switches between sticking
// and sliding once per change of motion, with a bounded force step at the switch.
#include "scene_helpers.h"

#include "sulcus/engine/exact_check.h"

#include <gtest/gtest.h>

namespace sulcus {
namespace {

using namespace test;

constexpr double kMuStatic = 0.5, kMuKinetic = 0.3;

std::unique_ptr<Model> block_on_plane(double mu_s, double mu_k, bool compliant = false) {
    ContactMaterial m;
    m.name = "surface";
    m.friction_static = mu_s;
    m.friction_kinetic = mu_k;
    if (compliant) {
        m.compliant = true;
        m.yield_curve = {{1.0, 1.0 / 2000.0}};
    }
    SceneObject plane = object("plane", make_box(Vec3(50 * mm, 1 * mm, 50 * mm), Vec3(0, -1 * mm, 0)));
    plane.material = 0;
    ModelBuild b = build_model(make_box(Vec3(1 * mm), Vec3(0, 1 * mm, 0)), {plane}, RendererSettings{}, {m});
    EXPECT_TRUE(b.model) << b.error;
    return std::move(b.model);
}

struct Drag {
    std::vector<StepResult> ticks;
    std::vector<Vec3> haptic;
};

// Press 1 mm into the plane (N = K 1 mm = 1 N), then drag along +x at `speed` m/s for `drag`
// ticks, then hold still.
Drag press_and_drag(const Model& model, double speed, int drag, int hold) {
    Drag d;
    State state = make_state(pose(Vec3(0, 0.2 * mm, 0)));
    const int press = 400;
    for (int i = 0; i <= press + drag + hold; ++i) {
        Vec3 h(0, 0.2 * mm - 1.2 * mm * std::min(1.0, double(i) / 200.0), 0);
        if (i > press) h.x = speed * 1e-3 * std::min(i - press, drag);
        d.ticks.push_back(step(model, state, pose(h)));
        d.haptic.push_back(h);
    }
    return d;
}

TEST(Friction, DraggedBlockFeelsMuTimesNormalForce) {
    auto model = block_on_plane(kMuStatic, kMuKinetic);
    ASSERT_TRUE(model->any_friction);
    const Drag d = press_and_drag(*model, 0.02, 1500, 500);
    const StepResult& sliding = d.ticks[400 + 1400];
    const double N = sliding.force_N.y;
    EXPECT_NEAR(N, 1.0, 1e-6);  // K * 1 mm, straight up
    EXPECT_NEAR(sliding.stats.normal_force_N, N, 1e-6);
    EXPECT_TRUE(sliding.stats.sliding);
    // Kinetic friction opposes the motion (-x) with mu_k N.
    EXPECT_NEAR(sliding.force_N.x, -kMuKinetic * N, 1e-6);
    EXPECT_NEAR(sliding.force_N.z, 0.0, 1e-9);

    // Before the static limit the block sticks: the force grows with the pull, up to mu_s N.
    double peak = 0.0;
    for (int i = 401; i < 400 + 1500; ++i) peak = std::max(peak, -d.ticks[size_t(i)].force_N.x);
    EXPECT_GT(peak, kMuKinetic * N + 0.1);
    EXPECT_LE(peak, kMuStatic * N + 1e-9);
    EXPECT_GE(peak, kMuStatic * N - 0.03);  // one tick of pull past the limit at most
    const StepResult& early = d.ticks[400 + 10];
    EXPECT_FALSE(early.stats.sliding);
    EXPECT_NEAR(early.force_N.x, -1000.0 * d.haptic[400 + 10].x, 1e-9);  // stuck where it was pressed

    // Held still after the drag: static friction holds the last (kinetic) pull.
    const StepResult& held = d.ticks.back();
    EXPECT_FALSE(held.stats.sliding);
    EXPECT_NEAR(held.force_N.x, -kMuKinetic * N, 1e-6);
}

TEST(Friction, StickSlipSwitchDoesNotChatter) {
    auto model = block_on_plane(kMuStatic, kMuKinetic);
    const Drag d = press_and_drag(*model, 0.02, 1500, 500);
    const double K = model->settings.haptic.stiffness_N_per_m;
    const double margin = model->settings.force_step_margin_m;
    int switches = 0, turns = 0;
    double worst_excess = -1e300, last_df = 0.0;
    for (size_t i = 401; i < d.ticks.size(); ++i) {
        const StepResult& a = d.ticks[i - 1];
        const StepResult& b = d.ticks[i];
        switches += a.stats.sliding != b.stats.sliding;
        const double step = glm::length(b.force_N - a.force_N);
        worst_excess = std::max(worst_excess, step - K * (glm::length(d.haptic[i] - d.haptic[i - 1]) + margin));
        // The tangential force rises to the static limit, falls to the kinetic one and stays:
        // its slope changes sign at most twice (rise, fall, flat), never back and forth.
        const double df = b.force_N.x - a.force_N.x;
        if (std::abs(df) > 1e-9) {
            if (last_df != 0.0 && (df > 0) != (last_df > 0)) ++turns;
            last_df = df;
        }
    }
    EXPECT_EQ(switches, 2);  // stick -> slide when the pull passes mu_s N, slide -> stick on stopping
    EXPECT_LE(turns, 1);
    EXPECT_LE(worst_excess, 1e-9);
}

TEST(Friction, FrictionlessAndCompliantSurfaces) {
    // mu = 0: no tangential force at all, and friction is not computed.
    auto smooth = block_on_plane(0.0, 0.0);
    EXPECT_FALSE(smooth->any_friction);
    const Drag s = press_and_drag(*smooth, 0.02, 500, 10);
    for (size_t i = 0; i < s.ticks.size(); ++i) ASSERT_NEAR(s.ticks[i].force_N.x, 0.0, 1e-12) << i;

    // On a compliant surface friction acts the same way: mu_k N while sliding, with the tool in
    // the surface by N / k.
    auto soft = block_on_plane(kMuStatic, kMuKinetic, true);
    const Drag d = press_and_drag(*soft, 0.02, 1500, 10);
    const StepResult& r = d.ticks[400 + 1400];
    const double N = r.force_N.y;
    EXPECT_TRUE(r.stats.sliding);
    EXPECT_NEAR(r.force_N.x, -kMuKinetic * N, 1e-6);
    EXPECT_NEAR(r.stats.soft_depth_m, N / 2000.0, 1e-9);
}

}  // namespace
}  // namespace sulcus
