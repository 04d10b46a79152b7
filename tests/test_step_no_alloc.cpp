// The servo step allocates nothing after its first call on a thread (its scratch memory is a
// per-thread workspace): counted by replacing the global operator new in this executable.
#include "scene_helpers.h"
#include "sulcus/engine/scene_file.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include "allocation_counter.h"

using namespace sulcus;
using namespace sulcus::test;

TEST(StepAllocation, NoHeapAllocationAfterTheFirstStep) {
    // A cube pressed into an L-shaped solid, sliding over a convex edge into a concave corner,
    // turning: every stage of the step runs.
    const std::vector<Vec2> ell = {{-20 * mm, -20 * mm}, {20 * mm, -20 * mm}, {20 * mm, 10 * mm},
                                   {10 * mm, 10 * mm},   {10 * mm, 0},        {-20 * mm, 0}};
    auto model = model_of(make_box(Vec3(2 * mm)), {object("ell", make_extruded_polygon(ell, -10 * mm, 10 * mm))});
    State st = make_state(pose(Vec3(-10 * mm, 3 * mm, 0)));
    step(*model, st, pose(Vec3(-10 * mm, 3 * mm, 0)));  // warm-up: the workspace is made here
    const long before = sulcus::test::heap_allocations();
    int contact = 0;
    for (int i = 1; i <= 3000; ++i) {
        const double f = i / 3000.0;
        const Pose h = pose(Vec3(-10 * mm + f * 24 * mm, 1 * mm - f * 1.5 * mm, 0),
                            axis_angle(Vec3(0, 1, 0.3), 0.4 * f));
        const StepResult r = step(*model, st, h);
        if (r.status == StepStatus::Contact) ++contact;
    }
    EXPECT_EQ(sulcus::test::heap_allocations() - before, 0);
    EXPECT_GT(contact, 1000);
    // The counter does count: a vector allocates once.
    const long probe = sulcus::test::heap_allocations();
    std::vector<double> v(static_cast<size_t>(contact));
    EXPECT_EQ(sulcus::test::heap_allocations() - probe, 1);
    EXPECT_EQ(v.size(), static_cast<size_t>(contact));
}

TEST(StepAllocation, NoHeapAllocationWithPiecesCompliantZonesAndFriction) {
    // A two-piece tool (tip and a bent-off shank) pressed into a compliant slab with a stiffening
    // region and friction, dragged along it: the slack variables, the friction solve and the
    // per-piece tests all run.
    TriMesh tool = make_box(Vec3(0.25 * mm, 5 * mm, 0.25 * mm), Vec3(0, 5 * mm, 0));
    const TriMesh shank = make_box(Vec3(3 * mm, 0.5 * mm, 0.25 * mm), Vec3(2.75 * mm, 9.5 * mm, 0));
    const uint32_t base = uint32_t(tool.vertices.size());
    tool.vertices.insert(tool.vertices.end(), shank.vertices.begin(), shank.vertices.end());
    for (const auto& t : shank.triangles) tool.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    ContactMaterial gum;
    gum.name = "gum";
    gum.compliant = true;
    gum.yield_curve = {{1.0, 1.0 / 400.0}};
    gum.friction_static = 0.5;
    gum.friction_kinetic = 0.4;
    ContactMaterial floor = gum;
    floor.name = "floor";
    floor.yield_curve = {{0.25, 0.5e-3}, {0.5, 1.0e-3}, {1.0, 1.25e-3}};
    SceneObject slab = object("slab", make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0, -2 * mm, 0)));
    slab.material = 0;
    MaterialRegion region;
    region.material = 1;
    region.center = Vec3(0.0);
    region.radius_m = 5 * mm;
    slab.regions.push_back(region);
    ModelBuild b = build_model(tool, {slab}, RendererSettings{}, {gum, floor});
    ASSERT_TRUE(b.model) << b.error;
    ASSERT_TRUE(b.model->any_compliant && b.model->any_friction);
    State st = make_state(pose(Vec3(0, 0.2 * mm, 0)));
    step(*b.model, st, pose(Vec3(0, 0.2 * mm, 0)));  // warm-up
    const long before = sulcus::test::heap_allocations();
    int soft = 0;
    for (int i = 1; i <= 3000; ++i) {
        const double f = i / 3000.0;
        const Pose h = pose(Vec3(f * 8 * mm, 0.2 * mm - std::min(1.0, 3 * f) * 1.5 * mm, 0));
        const StepResult r = step(*b.model, st, h);
        soft += r.stats.soft_zones > 0;
    }
    EXPECT_EQ(sulcus::test::heap_allocations() - before, 0);
    EXPECT_GT(soft, 1000);
}

// The bundled quadrant case (built by the build into <build>/cases/) stepped along its whole
// probing trajectory: every site probed down to a compliant floor with friction, on the full
// meshes. Not one heap allocation after the warm-up step.
TEST(StepAllocation, NoHeapAllocationOverTheBundledQuadrantProbing) {
    const std::string path = std::string(SULCUS_BINARY_DIR) + "/cases/quadrant_44_47/scene.json";
    ASSERT_TRUE(std::filesystem::exists(path))
        << path << " is missing: the build makes it (cmake --build <build> --target bundled_cases)";
    const SceneLoad load = load_scene(path);
    ASSERT_TRUE(load.ok()) << load.errors.front();
    const SceneFile& scene = load.scene;
    ASSERT_GE(scene.trajectory.size(), 2u);
    ModelBuild b = build_model(scene, RendererSettings{});
    ASSERT_TRUE(b.model) << b.error;

    // Every tick's haptic pose, sampled before counting.
    const double t0 = scene.trajectory.front().t, t1 = scene.trajectory.back().t;
    const long n = long(std::floor((t1 - t0) * scene.rate_hz + 1e-9)) + 1;
    std::vector<Pose> ticks;
    ticks.reserve(size_t(n));
    size_t cursor = 0;
    for (long i = 0; i < n; ++i) ticks.push_back(sample_trajectory(scene.trajectory, t0 + double(i) / scene.rate_hz, cursor));
    ASSERT_GT(ticks.size(), 30000u);

    State st = make_state(ticks.front());
    step(*b.model, st, ticks.front());  // warm-up: the workspace is made here
    long contact = 0, soft = 0, friction = 0;
    const auto start = std::chrono::steady_clock::now();
    const long before = sulcus::test::heap_allocations();
    for (const Pose& h : ticks) {
        const StepResult r = step(*b.model, st, h);
        contact += r.contacts > 0;
        soft += r.stats.soft_zones > 0;
        friction += r.stats.friction_static_limit_N > 0.0;
    }
    const long allocations = sulcus::test::heap_allocations() - before;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(allocations, 0) << "over " << ticks.size() << " ticks";
    // It really probed: long in contact, into the compliant floor, with friction.
    EXPECT_GT(contact, 2000);
    EXPECT_GT(soft, 0);
    EXPECT_GT(friction, 0);
    std::printf("%zu ticks in %.1f s: %ld in contact, %ld with soft zones, %ld with friction\n", ticks.size(), seconds,
                contact, soft, friction);
}
