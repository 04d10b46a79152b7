// The fast separating-axis test (face extents from the model, edge pairs pruned on the Gauss map)
// against the plain one over every candidate axis.
#include "geometry.h"
#include "tool_placement.h"

#include "sulcus/content/primitives.h"
#include "sulcus/content/probes.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <random>

namespace sulcus {
namespace {

void compare_on(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
    const ModelBuild mb = build_model(tool_mesh, {}, RendererSettings{});
    ASSERT_TRUE(mb.model) << mb.error;
    const ModelTool& tool = mb.model->tool;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vec3> verts(tool.mesh.vertices.size()), normals(tool.face_normals.size());
    std::vector<double> offsets(tool.face_normals.size());
    int overlapping = 0, separated = 0;
    for (int t = 0; t < trials; ++t) {
        Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 p(u(rng) * scale * 0.2, u(rng) * scale * 0.2, u(rng) * scale * 0.2);
        place_tool_vertices(tool, q, p, verts.data());
        place_tool_planes(tool, q, p, normals.data(), offsets.data());
        ConvexView slow = tool_convex_view(tool, 0, verts.data(), normals.data(), offsets.data(), nullptr);
        ConvexView fast = tool_convex_view(tool, 0, verts.data(), normals.data(), offsets.data(), &q);
        // A triangle near the tool: around a random tool vertex.
        const Vec3 c = verts[size_t(rng() % verts.size())];
        const double s = scale * (0.05 + 0.5 * (u(rng) + 1.0));
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        const SatResult rs = separate_convex_triangle(slow, a, b, d);
        const SatResult rf = separate_convex_triangle(fast, a, b, d);
        ASSERT_EQ(rs.separation > 0.0, rf.separation > 0.0) << "trial " << t;
        if (rs.separation <= 0.0) {
            ++overlapping;
            // Overlap: the least overlap is on an axis both keep.
            EXPECT_NEAR(rf.separation, rs.separation, 1e-12 * scale) << "trial " << t;
        } else {
            ++separated;
            EXPECT_LE(rf.separation, rs.separation + 1e-12 * scale) << "trial " << t;
        }
    }
    EXPECT_GT(overlapping, trials / 10);
    EXPECT_GT(separated, trials / 10);
}

TEST(FastSat, AgreesWithTheFullTestOnABox) { compare_on(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), 2e-3, 3000, 1); }

TEST(FastSat, AgreesWithTheFullTestOnProbeTips) {
    compare_on(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 3000, 2);
    compare_on(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 3000, 3);
}

}  // namespace
}  // namespace sulcus

namespace sulcus {
namespace {

// The capsule chain's lower bound never exceeds the exact distance (it only ever skips work).
void capsule_bound_holds(const TriMesh& tool_mesh, double scale, unsigned seed) {
    const ModelBuild mb = build_model(tool_mesh, {}, RendererSettings{});
    ASSERT_TRUE(mb.model) << mb.error;
    const ModelTool& tool = mb.model->tool;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vec3> verts(tool.mesh.vertices.size()), normals(tool.face_normals.size());
    std::vector<double> offsets(tool.face_normals.size());
    Vec3 caps[kMaxToolPieces * (kToolCapsules + 1)];
    const auto* tris = piece_triangles(tool, 0);
    int useful = 0;
    for (int t = 0; t < 3000; ++t) {
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 p(u(rng) * scale, u(rng) * scale, u(rng) * scale);
        place_tool_vertices(tool, q, p, verts.data());
        place_tool_planes(tool, q, p, normals.data(), offsets.data());
        place_tool_capsule(tool, q, p, caps);
        const ConvexView with = tool_convex_view(tool, 0, verts.data(), normals.data(), offsets.data(), &q, caps);
        const ConvexView without = tool_convex_view(tool, 0, verts.data(), normals.data(), offsets.data(), &q);
        const Vec3 c = verts[size_t(rng() % verts.size())] + 0.2 * scale * Vec3(u(rng), u(rng), u(rng));
        const double s = 0.3 * scale;
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        const double exact = distance_convex_triangle(without, tris, int(tool.mesh.triangles.size()), a, b, d);
        const double lower = capsule_lower_bound(with, a, b, d);
        EXPECT_LE(lower, exact + 1e-12 * scale) << "trial " << t;
        useful += lower > 0.5 * exact && exact > 0.0;
        // With the bound in place the distance is still exact when it matters (below the cutoff).
        EXPECT_NEAR(distance_convex_triangle(with, tris, int(tool.mesh.triangles.size()), a, b, d, 1e300), exact,
                    1e-12 * scale);
    }
    EXPECT_GT(useful, 100);  // the bound is not vacuous
}

TEST(CapsuleBound, NeverExceedsTheExactDistance) {
    capsule_bound_holds(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 6);
    capsule_bound_holds(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 7);
}

TEST(CapsuleBound, OnlyLongToolsUseCapsules) {
    const ModelBuild box = build_model(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), {}, RendererSettings{});
    ASSERT_TRUE(box.model);
    EXPECT_EQ(box.model->tool.pieces[0].capsule_count, 0);
    const ModelBuild probe = build_model(make_probe_tip_collision(ProbeKind::Williams), {}, RendererSettings{});
    ASSERT_TRUE(probe.model);
    EXPECT_EQ(probe.model->tool.pieces[0].capsule_count, kToolCapsules);
}

}  // namespace
}  // namespace sulcus
