// The servo step allocates nothing after its first call on a thread (its scratch memory is a
// per-thread workspace): counted by replacing the global operator new in this executable.
#include "scene_helpers.h"

#include <atomic>
#include <cstdlib>
#include <new>
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
