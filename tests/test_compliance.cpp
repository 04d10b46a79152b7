// Compliant materials as soft constraints inside the step's QP: the tool enters a compliant
// object by exactly force / stiffness (or along a stiffening yield curve), never enters a rigid
// one, and the force stays continuous across rigid / compliant switches. Scenes that use no
// compliance or friction compute none.
#include "scene_helpers.h"

#include "sulcus/engine/exact_check.h"

#include <gtest/gtest.h>

namespace sulcus {
namespace {

using namespace test;

ContactMaterial linear(const std::string& name, double k_N_per_m) {
    ContactMaterial m;
    m.name = name;
    m.compliant = true;
    m.yield_curve = {{1.0, 1.0 / k_N_per_m}};
    return m;
}

// The "healthy" pocket-floor curve of the bundled cases: force N, depth m.
ContactMaterial stiffening() {
    ContactMaterial m;
    m.name = "floor";
    m.compliant = true;
    m.yield_curve = {{0.25, 0.05e-3}, {0.5, 0.08e-3}, {1.0, 0.12e-3}};
    return m;
}

std::unique_ptr<Model> build(const TriMesh& tool, const std::vector<SceneObject>& objects,
                             const std::vector<ContactMaterial>& materials, const RendererSettings& s = {}) {
    ModelBuild b = build_model(tool, objects, s, materials);
    EXPECT_TRUE(b.model) << b.error;
    return std::move(b.model);
}

// A 2 mm cube with its bottom face at the tool origin.
TriMesh cube() { return make_box(Vec3(1 * mm), Vec3(0, 1 * mm, 0)); }

SceneObject slab(int material, const Vec3& centre = Vec3(0, -1 * mm, 0), double half_x = 10 * mm) {
    SceneObject o = object("slab", make_box(Vec3(half_x, 1 * mm, 10 * mm), centre));
    o.material = material;
    return o;
}

TEST(Compliance, YieldCurveBecomesSpringsInSeries) {
    ModelMaterial m;
    ASSERT_EQ(material_from_curve(stiffening(), m), "");
    EXPECT_TRUE(m.compliant);
    EXPECT_EQ(m.springs, 3);
    // The curve's own points, between them and past the last (last slope).
    EXPECT_NEAR(material_depth(m, 0.25), 0.05e-3, 1e-15);
    EXPECT_NEAR(material_depth(m, 0.5), 0.08e-3, 1e-15);
    EXPECT_NEAR(material_depth(m, 1.0), 0.12e-3, 1e-15);
    EXPECT_NEAR(material_depth(m, 0.125), 0.025e-3, 1e-15);
    EXPECT_NEAR(material_depth(m, 0.75), 0.10e-3, 1e-15);
    EXPECT_NEAR(material_depth(m, 2.0), 0.20e-3, 1e-15);
    EXPECT_EQ(material_depth(m, 0.0), 0.0);

    ContactMaterial soft = stiffening();
    soft.yield_curve = {{0.25, 0.05e-3}, {0.5, 0.2e-3}};  // softens at 0.25 N
    EXPECT_NE(material_from_curve(soft, m).find("softens"), std::string::npos);
    ModelMaterial lin;
    ASSERT_EQ(material_from_curve(linear("gum", 400.0), lin), "");
    EXPECT_EQ(lin.springs, 1);
    EXPECT_NEAR(material_depth(lin, 0.2), 0.2 / 400.0, 1e-15);
}

// A cube pressed into a compliant slab: equilibrium K_t (d - s) = k s, and the depth the exact
// check measures is force / k.
TEST(Compliance, EnteredByExactlyForceOverStiffness) {
    for (double k : {200.0, 1000.0, 5000.0}) {
        SCOPED_TRACE(k);
        const std::vector<SceneObject> objects = {slab(0)};
        auto model = build(cube(), objects, {linear("gum", k)});
        ASSERT_TRUE(model->any_compliant);
        const std::vector<PlacedMesh> placed = {PlacedMesh{&objects[0].mesh, objects[0].pose}};
        State state = make_state(pose(Vec3(0, 0.5 * mm, 0)));
        StepResult r;
        const double d = 1 * mm;  // the haptic tool goes this far below the surface
        for (int i = 0; i <= 1000; ++i) {
            const double y = 0.5 * mm - (0.5 * mm + d) * std::min(1.0, i / 500.0);
            r = step(*model, state, pose(Vec3(0, y, 0)));
            ASSERT_NE(r.status, StepStatus::Held) << "tick " << i;
        }
        const double K = model->settings.haptic.stiffness_N_per_m;
        const double force = glm::length(r.force_N);
        const double depth = exact_check(cube(), r.graphic, placed, 0.0).penetration_m;
        EXPECT_NEAR(depth, force / k, 1e-6);
        EXPECT_NEAR(r.stats.soft_depth_m, force / k, 1e-9);
        EXPECT_NEAR(depth, K * d / (K + k), 1e-6);
        EXPECT_GT(r.force_N.y, 0.0);
        EXPECT_EQ(r.stats.soft_zones, 1);
    }
}

// Along a stiffening curve the depth follows the curve at every force on the way in.
// Two compliant slabs side by side: the state knows how deep the tool is in each object, so the
// next tick looks behind the surface of the one it is in, and not behind the other's.
TEST(Compliance, StateKnowsHowDeepEachObjectGivesWay) {
    const std::vector<SceneObject> objects = {slab(0, Vec3(-6 * mm, -1 * mm, 0), 5 * mm),
                                              slab(1, Vec3(6 * mm, -1 * mm, 0), 5 * mm)};
    auto model = build(cube(), objects, {linear("gum", 1000.0), linear("firm", 4000.0)});
    ASSERT_TRUE(model);
    const double K = model->settings.haptic.stiffness_N_per_m;
    State state = make_state(pose(Vec3(-6 * mm, 0.5 * mm, 0)));
    auto press = [&](double x, int ticks) {
        StepResult r;
        for (int i = 0; i <= ticks; ++i) {
            const double y = 0.5 * mm - 1.0 * mm * std::min(1.0, i / (0.5 * ticks));
            r = step(*model, state, pose(Vec3(x, y, 0)));
            EXPECT_NE(r.status, StepStatus::Held) << "tick " << i;
        }
        return r;
    };
    StepResult r = press(-6 * mm, 600);
    ASSERT_EQ(r.status, StepStatus::Contact);
    ASSERT_EQ(state.soft.count, 1);
    EXPECT_EQ(state.soft.object[0], 0);
    EXPECT_EQ(state.soft.depth_m[0], r.stats.soft_depth_m);
    EXPECT_EQ(state.soft.of(1), 0.0);
    const double force = glm::length(r.force_N);
    EXPECT_NEAR(state.soft.of(0), force / 1000.0, 1e-6);
    EXPECT_NEAR(force, K * (0.5 * mm - state.soft.of(0)), 1e-6 * K);  // the haptic tool 0.5 mm in

    // Lifted clear: in nothing.
    for (int i = 0; i < 400; ++i) r = step(*model, state, pose(Vec3(-6 * mm, 0.5 * mm * std::min(1.0, i / 200.0), 0)));
    EXPECT_EQ(r.status, StepStatus::Free);
    EXPECT_EQ(state.soft.count, 0);

    // Over the other slab and into it: only that one, by its own stiffness.
    for (int i = 0; i <= 400; ++i) r = step(*model, state, pose(Vec3(-6 * mm + 12 * mm * std::min(1.0, i / 300.0), 0.5 * mm, 0)));
    r = press(6 * mm, 600);
    ASSERT_EQ(r.status, StepStatus::Contact);
    ASSERT_EQ(state.soft.count, 1);
    EXPECT_EQ(state.soft.object[0], 1);
    EXPECT_NEAR(state.soft.of(1), glm::length(r.force_N) / 4000.0, 1e-6);
}

TEST(Compliance, DepthFollowsTheYieldCurve) {
    const std::vector<SceneObject> objects = {slab(0)};
    auto model = build(cube(), objects, {stiffening()});
    ModelMaterial m;
    ASSERT_EQ(material_from_curve(stiffening(), m), "");
    const std::vector<PlacedMesh> placed = {PlacedMesh{&objects[0].mesh, objects[0].pose}};
    State state = make_state(pose(Vec3(0, 0.1 * mm, 0)));
    int checked = 0;
    double worst = 0.0, worst_exact = 0.0;
    // 1 mm/s: slow against the step's catch-up, so every tick is at equilibrium.
    for (int i = 0; i <= 1500; ++i) {
        const double y = 0.1 * mm - 1e-6 * i;  // to 1.4 mm below the surface: about 1.3 N
        const StepResult r = step(*model, state, pose(Vec3(0, y, 0)));
        const double force = glm::length(r.force_N);
        if (force < 1e-3) continue;
        worst = std::max(worst, std::abs(r.stats.soft_depth_m - material_depth(m, force)));
        worst_exact = std::max(worst_exact,
                               std::abs(exact_check(cube(), r.graphic, placed, 0.0).penetration_m - material_depth(m, force)));
        ++checked;
    }
    EXPECT_GT(checked, 1000);
    EXPECT_LE(worst, 1e-9);
    EXPECT_LE(worst_exact, 1e-6);
}

// And on the way out: the floor pushes the tool back as the hand draws back, so the depth follows
// the curve down again (the tool is held away from a haptic tool still deeper than it, which only
// the springs' energy lets it go). Drawn back at 1 mm/s along the stiffening curve, and at 40 mm/s
// (40 um a tick) out of a soft linear one: every tick at equilibrium, the force falling steadily.
TEST(Compliance, DepthFollowsTheCurveAsTheHandDrawsBack) {
    struct Run {
        ContactMaterial material;
        double rate_m_per_tick;
    };
    for (const Run& run : {Run{stiffening(), 1e-6}, Run{linear("gum", 500.0), 40e-6}}) {
        SCOPED_TRACE(run.rate_m_per_tick);
        const std::vector<SceneObject> objects = {slab(0)};
        auto model = build(cube(), objects, {run.material});
        ModelMaterial m;
        ASSERT_EQ(material_from_curve(run.material, m), "");
        const std::vector<PlacedMesh> placed = {PlacedMesh{&objects[0].mesh, objects[0].pose}};
        State state = make_state(pose(Vec3(0, 0.1 * mm, 0)));
        // In to 1.3 mm below the surface at 1 mm/s, held, then out at the run's rate.
        for (int i = 0; i <= 1400; ++i) step(*model, state, pose(Vec3(0, 0.1 * mm - 1e-6 * i, 0)));
        const double deepest = 0.1 * mm - 1400e-6;
        StepResult r;
        for (int i = 0; i < 100; ++i) r = step(*model, state, pose(Vec3(0, deepest, 0)));
        const double pressed = glm::length(r.force_N);
        ASSERT_GT(pressed, 0.4);
        int checked = 0;
        double worst = 0.0, worst_exact = 0.0, rise = 0.0, last = pressed;
        for (int i = 1; deepest + run.rate_m_per_tick * i < 0.1 * mm; ++i) {
            r = step(*model, state, pose(Vec3(0, deepest + run.rate_m_per_tick * i, 0)));
            ASSERT_NE(r.status, StepStatus::Held) << "tick " << i;
            const double force = glm::length(r.force_N);
            rise = std::max(rise, force - last);
            last = force;
            if (force < 1e-3) continue;
            worst = std::max(worst, std::abs(r.stats.soft_depth_m - material_depth(m, force)));
            worst_exact = std::max(
                worst_exact, std::abs(exact_check(cube(), r.graphic, placed, 0.0).penetration_m - material_depth(m, force)));
            ++checked;
        }
        EXPECT_GT(checked, 20);
        EXPECT_LE(worst, 1e-9);
        EXPECT_LE(worst_exact, 1e-6);
        EXPECT_LE(rise, 1e-9);  // never up again on the way out: no tick held back and let go at the next
        EXPECT_EQ(r.status, StepStatus::Free);
    }
}

// Slid from a rigid slab onto a compliant one while pressing: no penetration of the rigid one,
// the expected depth in the compliant one, and a force step bounded by the force-continuity
// limit at the switch.
TEST(Compliance, ForceContinuousAcrossRigidToCompliant) {
    std::vector<SceneObject> objects = {slab(-1, Vec3(-10 * mm, -1 * mm, 0), 10 * mm),
                                        slab(0, Vec3(10 * mm, -1 * mm, 0), 10 * mm)};
    objects[0].name = "rigid";
    objects[1].name = "soft";
    const double k = 500.0;
    auto model = build(cube(), objects, {linear("gum", k)});
    const std::vector<PlacedMesh> rigid = {PlacedMesh{&objects[0].mesh, objects[0].pose}};
    const double K = model->settings.haptic.stiffness_N_per_m;
    const double margin = model->settings.force_step_margin_m;
    State state = make_state(pose(Vec3(-5 * mm, 0.2 * mm, 0)));
    Vec3 last_force(0.0), last_h(-5 * mm, 0.2 * mm, 0);
    double worst_step_excess = -1e300, worst_pen = 0.0;
    StepResult r;
    const int press = 300, slide = 2000, hold = 300;
    for (int i = 0; i <= press + slide + hold; ++i) {
        Vec3 h(-5 * mm, 0.2 * mm - 0.7 * mm * std::min(1.0, double(i) / press), 0);
        if (i > press) h.x = -5 * mm + 10 * mm * std::min(1.0, double(i - press) / slide);  // 5 mm/s
        r = step(*model, state, pose(h));
        ASSERT_TRUE(std::isfinite(r.force_N.x) && std::isfinite(r.force_N.y));
        if (i > 0)
            worst_step_excess = std::max(worst_step_excess,
                                         glm::length(r.force_N - last_force) - K * (glm::length(h - last_h) + margin));
        worst_pen = std::max(worst_pen, exact_check(cube(), r.graphic, rigid, 0.0).penetration_m);
        last_force = r.force_N;
        last_h = h;
    }
    EXPECT_LE(worst_step_excess, 1e-9);
    EXPECT_LE(worst_pen, 1e-6);
    // On the compliant slab at the end: 0.5 mm pressed splits as K (d - s) = k s.
    EXPECT_NEAR(r.stats.soft_depth_m, K * 0.5 * mm / (K + k), 1e-6);
}

// What a scene does not use costs nothing: declaring a rigid frictionless material, or a compliant
// one no object takes, changes no bit of the result, and the step reports no compliance or
// friction work.
TEST(Compliance, ScenesComputeOnlyWhatTheyUse) {
    auto plain = build(cube(), {slab(-1)}, {});
    ContactMaterial rigid;
    rigid.name = "enamel";
    auto declared = build(cube(), {slab(0)}, {rigid, linear("unused", 300.0)});
    EXPECT_FALSE(plain->any_compliant);
    EXPECT_FALSE(plain->any_friction);
    EXPECT_FALSE(declared->any_compliant);
    EXPECT_FALSE(declared->any_friction);
    State a = make_state(pose(Vec3(0, 0.3 * mm, 0))), b = a;
    for (int i = 0; i <= 600; ++i) {
        const Pose h = pose(Vec3(1e-6 * i, 0.3 * mm - 1e-6 * i, 0), axis_angle(Vec3(0, 0, 1), 1e-4 * i));
        const StepResult ra = step(*plain, a, h);
        const StepResult rb = step(*declared, b, h);
        ASSERT_EQ(ra.graphic.position, rb.graphic.position) << i;
        ASSERT_EQ(ra.graphic.orientation, rb.graphic.orientation) << i;
        ASSERT_EQ(ra.force_N, rb.force_N) << i;
        EXPECT_EQ(rb.stats.soft_zones, 0);
        EXPECT_EQ(rb.stats.normal_force_N, 0.0);  // friction never looked at the contacts
    }
    EXPECT_EQ(a.active_count > 0, true);
}

}  // namespace
}  // namespace sulcus
