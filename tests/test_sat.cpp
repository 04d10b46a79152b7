// The fast separating-axis test (face extents from the model, edge pairs pruned on the Gauss map)
// against the plain one over every candidate axis.
#include "capsule_bounds.h"
#include "geometry.h"
#include "tool_placement.h"

#include "sulcus/content/primitives.h"
#include "sulcus/content/probes.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

namespace sulcus {

namespace test_sat {

// A one-piece tool's model and the piece placed at a pose: vertices, face planes, capsules.
struct PlacedTool {
    ModelBuild mb;
    const ModelTool* tool = nullptr;
    std::vector<Vec3> verts, normals;
    std::vector<double> offsets;
    Vec3 caps[kMaxToolPieces * (kToolCapsules + 1)];
    Quat q{1.0, 0.0, 0.0, 0.0};

    explicit PlacedTool(const TriMesh& mesh) : mb(build_model(mesh, {}, RendererSettings{})) {
        if (!mb.model) return;
        tool = &mb.model->tool;
        verts.resize(tool->mesh.vertices.size());
        normals.resize(tool->face_normals.size());
        offsets.resize(tool->face_normals.size());
    }
    void place(const Quat& rotation, const Vec3& p) {
        q = rotation;
        place_tool_vertices(*tool, q, p, verts.data());
        place_tool_planes(*tool, q, p, normals.data(), offsets.data());
        place_tool_capsule(*tool, q, p, caps);
    }
    // The piece's view: with the rotation (the fast separating-axis test) or not, with the
    // capsules or not.
    ConvexView view(bool fast, bool capsules = false) const {
        return tool_convex_view(*tool, 0, verts.data(), normals.data(), offsets.data(), fast ? &q : nullptr,
                                capsules ? caps : nullptr);
    }
};

}  // namespace test_sat

namespace {

using test_sat::PlacedTool;

// A triangle near the placed tool: around one of its vertices, vertices up to 0.05-1.05 `scale`
// off it along each axis.
void triangle_near_vertex(const PlacedTool& pt, std::mt19937& rng, std::uniform_real_distribution<double>& u,
                          double scale, Vec3& a, Vec3& b, Vec3& d) {
    const Vec3 c = pt.verts[size_t(rng() % pt.verts.size())];
    const double s = scale * (0.05 + 0.5 * (u(rng) + 1.0));
    a = c + s * Vec3(u(rng), u(rng), u(rng));
    b = c + s * Vec3(u(rng), u(rng), u(rng));
    d = c + s * Vec3(u(rng), u(rng), u(rng));
}

// The placed tool at a random orientation, moved up to 0.2 `scale` along each axis.
void place_at_random(PlacedTool& pt, std::mt19937& rng, std::uniform_real_distribution<double>& u, double scale) {
    const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
    pt.place(q, Vec3(u(rng) * scale * 0.2, u(rng) * scale * 0.2, u(rng) * scale * 0.2));
}

void compare_on(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int overlapping = 0, separated = 0;
    for (int t = 0; t < trials; ++t) {
        place_at_random(pt, rng, u, scale);
        const ConvexView slow = pt.view(false);
        const ConvexView fast = pt.view(true);
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
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

// The fast test's table of triangle normals along each triangle edge gives the edge-by-edge
// pruning's answer to the bit: the same separation, axis, kind and index.
void table_matches_edge_by_edge(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int overlapping = 0, by_edges = 0;
    for (int t = 0; t < trials; ++t) {
        place_at_random(pt, rng, u, scale);
        const ConvexView with_table = pt.view(true);
        ASSERT_NE(with_table.triangle_normals, nullptr);
        ASSERT_NE(with_table.edge_triangles, nullptr);
        ASSERT_EQ(with_table.triangle_count, int(pt.tool->pieces[0].triangle_count));
        ConvexView edge_by_edge = with_table;
        edge_by_edge.triangle_normals = nullptr;
        edge_by_edge.edge_triangles = nullptr;
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        const SatResult rt = separate_convex_triangle(with_table, a, b, d);
        const SatResult re = separate_convex_triangle(edge_by_edge, a, b, d);
        ASSERT_EQ(std::memcmp(&rt.separation, &re.separation, sizeof(double)), 0) << "trial " << t;
        ASSERT_EQ(std::memcmp(&rt.axis, &re.axis, sizeof(Vec3)), 0) << "trial " << t;
        ASSERT_EQ(rt.kind, re.kind) << "trial " << t;
        ASSERT_EQ(rt.index, re.index) << "trial " << t;
        overlapping += rt.separation <= 0.0;
        by_edges += rt.kind == 2;
    }
    // Both kinds of answer, and edge pairs among them.
    EXPECT_GT(overlapping, trials / 10);
    EXPECT_LT(overlapping, trials - trials / 10);
    EXPECT_GT(by_edges, 0);
}

TEST(FastSat, TriangleTableGivesTheEdgeByEdgeAnswerToTheBit) {
    table_matches_edge_by_edge(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), 2e-3, 2000, 11);
    table_matches_edge_by_edge(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 2000, 12);
    table_matches_edge_by_edge(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 2000, 13);
}

// Four face normals and four table rows at a time (AVX2) give the one-at-a-time answer to the bit:
// the same separation, axis, kind and index, over answers of every kind.
void four_at_a_time_match(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int kinds[3] = {0, 0, 0};
    for (int t = 0; t < trials; ++t) {
        place_at_random(pt, rng, u, scale);
        const ConvexView view = pt.view(true);
        ASSERT_GE(view.face_count, 4);
        ASSERT_GE(view.triangle_count, 4);
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        const SatResult r4 = separate_convex_triangle(view, a, b, d, true);
        const SatResult r1 = separate_convex_triangle(view, a, b, d, false);
        ASSERT_EQ(std::memcmp(&r4.separation, &r1.separation, sizeof(double)), 0) << "trial " << t;
        ASSERT_EQ(std::memcmp(&r4.axis, &r1.axis, sizeof(Vec3)), 0) << "trial " << t;
        ASSERT_EQ(r4.kind, r1.kind) << "trial " << t;
        ASSERT_EQ(r4.index, r1.index) << "trial " << t;
        ++kinds[r1.kind];
    }
    // The triangle's normal, face normals and edge pairs each decided some of the answers.
    EXPECT_GT(kinds[0], trials / 20);
    EXPECT_GT(kinds[1], trials / 20);
    EXPECT_GT(kinds[2], trials / 20);
}

TEST(FastSat, FourAtATimeGivesTheOneAtATimeAnswerToTheBit) {
    four_at_a_time_match(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), 2e-3, 2000, 21);
    four_at_a_time_match(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 2000, 22);
    four_at_a_time_match(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 2000, 23);
}

// The test stopped at the first axis whose gap reaches `enough` says what the whole test says
// about reaching it: under `enough`, the whole test's answer to the bit; at or over it, a gap of
// at least `enough` along the axis it gives (a real gap there) and no more than the separation.
// Over thresholds round the separation (just under, at, just over it, and far from it), for
// answers of every kind, on each probe tip and on a box.
void stopped_test_agrees(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int under = 0, stopped = 0, early = 0;
    for (int t = 0; t < trials; ++t) {
        place_at_random(pt, rng, u, scale);
        const ConvexView view = pt.view(true);
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        const SatResult full = separate_convex_triangle(view, a, b, d);
        const double s = full.separation;
        const double ulp = std::nextafter(s, 1e300) - s;
        for (const double enough : {s - 1e-4 * scale, s - ulp, s, s + ulp, s + 1e-4 * scale, -1e-3 * scale, 0.0}) {
            const SatResult r = separate_convex_triangle_until(view, a, b, d, enough);
            if (s < enough) {
                ++under;
                ASSERT_EQ(std::memcmp(&r.separation, &full.separation, sizeof(double)), 0) << "trial " << t;
                ASSERT_EQ(std::memcmp(&r.axis, &full.axis, sizeof(Vec3)), 0) << "trial " << t;
                ASSERT_EQ(r.kind, full.kind) << "trial " << t;
                ASSERT_EQ(r.index, full.index) << "trial " << t;
            } else {
                ++stopped;
                ASSERT_GE(r.separation, enough) << "trial " << t;
                ASSERT_LE(r.separation, s) << "trial " << t;
                EXPECT_NEAR(gap_along_axis(view, r.axis, a, b, d), r.separation, 1e-12 * scale) << "trial " << t;
                early += r.separation < s;
            }
        }
    }
    // Both answers come up often, and the test often stops before the best axis.
    EXPECT_GT(under, trials);
    EXPECT_GT(stopped, trials);
    EXPECT_GT(early, trials / 4);
}

TEST(FastSat, StoppedAtEnoughSaysWhatTheWholeTestSays) {
    stopped_test_agrees(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), 2e-3, 1500, 31);
    stopped_test_agrees(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 1500, 32);
    stopped_test_agrees(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 1500, 33);
}

// Placing the tool four vertices and four face planes at a time gives glm's q * v + p and
// n . p + offset to the bit, for every probe tip and odd counts (the last ones one at a time), at
// random poses.
TEST(ToolPlacement, FourAtATimeGivesGlmsAnswerToTheBit) {
    std::vector<TriMesh> meshes = {make_box(Vec3(1e-3, 2e-3, 0.5e-3))};
    for (ProbeKind kind : kAllProbeKinds) meshes.push_back(make_probe_tip_collision(kind));
    std::mt19937_64 rng(31);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int compared = 0;
    for (const TriMesh& mesh : meshes) {
        const ModelBuild mb = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(mb.model) << mb.error;
        const ModelTool& tool = mb.model->tool;
        std::vector<Vec3> verts(tool.mesh.vertices.size()), normals(tool.face_normals.size());
        std::vector<double> offsets(tool.face_normals.size());
        for (int trial = 0; trial < 200; ++trial) {
            const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
            const Vec3 p = 0.05 * Vec3(u(rng), u(rng), u(rng));
            place_tool_vertices(tool, q, p, verts.data());
            place_tool_planes(tool, q, p, normals.data(), offsets.data());
            for (size_t i = 0; i < verts.size(); ++i) {
                const Vec3 expected = q * tool.mesh.vertices[i] + p;
                ASSERT_EQ(std::memcmp(&verts[i], &expected, sizeof(Vec3)), 0) << "vertex " << i;
                ++compared;
            }
            for (size_t f = 0; f < normals.size(); ++f) {
                const Vec3 n = q * tool.face_normals[f];
                const double d = tool.face_offsets[f] + glm::dot(n, p);
                ASSERT_EQ(std::memcmp(&normals[f], &n, sizeof(Vec3)), 0) << "face " << f;
                ASSERT_EQ(std::memcmp(&offsets[f], &d, sizeof(double)), 0) << "face " << f;
                ++compared;
            }
        }
    }
    EXPECT_GT(compared, 10000);
}

// The guard takes the gap along one axis (the triangle's normal, the axis a pair's last test
// found) for the separation where it is enough: it must never exceed the separation, and along
// the test's own axis it must give the separation back.
TEST(SeparatingAxis, NoGapAlongAnAxisExceedsTheSeparation) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const double scale = 1e-3;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int overlapping = 0, normal_enough = 0;
    for (int t = 0; t < 3000; ++t) {
        pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng)) * 0.2 * scale);
        const ConvexView view = pt.view(true);
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        const SatResult sat = separate_convex_triangle(view, a, b, d);
        overlapping += sat.separation < 0.0;
        const Vec3 n = glm::normalize(glm::cross(b - a, d - a));
        const double normal = gap_along_axis(view, n, a, b, d);
        EXPECT_LE(normal, sat.separation + 1e-12 * scale) << "trial " << t;
        normal_enough += normal >= sat.separation - 1e-12 * scale;
        for (int k = 0; k < 8; ++k) {
            const Vec3 axis = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
            EXPECT_LE(gap_along_axis(view, axis, a, b, d), sat.separation + 1e-12 * scale) << "trial " << t;
        }
        EXPECT_NEAR(gap_along_axis(view, sat.axis, a, b, d), sat.separation, 1e-12 * scale) << "trial " << t;
    }
    EXPECT_GT(overlapping, 300);
    EXPECT_GT(normal_enough, 100);  // the triangle's normal is often the axis itself
}

// The gap along an axis by descent from the last axis's extreme vertices (a certified piece) is
// the scan's, whether the axes drift slowly (the guard's neighbouring triangles) or jump, and
// from any start, also one out of range.
TEST(SeparatingAxis, GapAlongAnAxisByDescentIsTheScans) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    ASSERT_TRUE(pt.tool->pieces[0].descend);
    const double scale = 1e-3;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int extremes[2] = {-1, 1000000};
    int moved = 0;
    Vec3 axis = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
    for (int t = 0; t < 3000; ++t) {
        if (t % 100 == 0) pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng)) * scale);
        const ConvexView view = pt.view(true);
        ASSERT_NE(view.neighbours, nullptr);
        // Mostly a small turn of the last axis, now and then a new one.
        axis = t % 7 == 0 ? glm::normalize(Vec3(u(rng), u(rng), u(rng)))
                          : glm::normalize(axis + 0.05 * Vec3(u(rng), u(rng), u(rng)));
        if (t % 500 == 0) extremes[0] = -5;  // a start out of range: the scan
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        const int before = extremes[0];
        EXPECT_EQ(gap_along_axis_by_descent(view, axis, a, b, d, extremes), gap_along_axis(view, axis, a, b, d))
            << "trial " << t;
        moved += extremes[0] != before;
    }
    EXPECT_GT(moved, 300);  // the starts were not already the answers
}

// A piece of at most kScanVertices vertices (the probe's tip, of 50): the gap along an axis with
// the extremes at hand is every vertex's, four at a time, the same to the bit as one at a time,
// and the extremes are left as they were (no descent moved them).
TEST(SeparatingAxis, GapAlongAnAxisOfASmallPieceLooksAtEveryVertex) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    ASSERT_TRUE(pt.tool->pieces[0].descend);
    const double scale = 1e-3;
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int t = 0; t < 400; ++t) {
        if (t % 50 == 0) pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng)) * scale);
        const ConvexView view = pt.view(true);
        ASSERT_NE(view.neighbours, nullptr);
        ASSERT_LE(view.vertex_count, kScanVertices);
        const Vec3 axis = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        Vec3 a, b, d;
        triangle_near_vertex(pt, rng, u, scale, a, b, d);
        int extremes[2] = {0, 0};
        EXPECT_EQ(gap_along_axis(view, axis, a, b, d, extremes), gap_along_axis(view, axis, a, b, d)) << "trial " << t;
        EXPECT_EQ(extremes[0], 0) << "trial " << t;
        EXPECT_EQ(extremes[1], 0) << "trial " << t;
    }
}

// A triangle vertex deeper inside the polytope than -floor puts their separation below floor.
TEST(SeparatingAxis, AVertexDeepInsideBoundsTheSeparation) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const double scale = 1e-3;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int deep = 0, shallow = 0, rejecting = -1;
    for (int t = 0; t < 3000; ++t) {
        pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng)) * 0.2 * scale);
        const ConvexView view = pt.view(true);
        // A vertex pulled part of the way from a tool vertex towards the tool's centre.
        Vec3 centre(0.0);
        for (int v = 0; v < view.vertex_count; ++v) centre += view.vertices[v] / double(view.vertex_count);
        const Vec3 corner = view.vertices[size_t(rng() % size_t(view.vertex_count))];
        const Vec3 a = corner + 0.5 * (u(rng) + 1.0) * (centre - corner);
        const double s = scale * (0.05 + 0.5 * (u(rng) + 1.0));
        const Vec3 b = a + s * Vec3(u(rng), u(rng), u(rng)), d = a + s * Vec3(u(rng), u(rng), u(rng));
        const double floor = -scale * 0.1 * (u(rng) + 1.0);
        const double separation = separate_convex_triangle(view, a, b, d).separation;
        // The face that last rejected a vertex, tried first, changes no answer.
        EXPECT_EQ(vertex_deep_inside(view, a, b, d, floor, &rejecting), vertex_deep_inside(view, a, b, d, floor))
            << "trial " << t;
        if (vertex_deep_inside(view, a, b, d, floor)) {
            ++deep;
            EXPECT_LT(separation, floor) << "trial " << t;
        } else if (separation < 0.0 && separation >= floor) {
            ++shallow;  // overlapping, but less than -floor: not deep
        }
    }
    EXPECT_GT(deep, 300);
    EXPECT_GT(shallow, 100);
}

}  // namespace
}  // namespace sulcus

namespace sulcus {
namespace {

// The capsule chain's lower bound never exceeds the exact distance (it only ever skips work).
void capsule_bound_holds(const TriMesh& tool_mesh, double scale, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const ModelTool& tool = *pt.tool;
    const std::vector<Vec3>& verts = pt.verts;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto* tris = piece_triangles(tool, 0);
    int useful = 0;
    for (int t = 0; t < 3000; ++t) {
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        pt.place(q, Vec3(u(rng) * scale, u(rng) * scale, u(rng) * scale));
        const ConvexView with = pt.view(true, true);
        const ConvexView without = pt.view(true);
        const Vec3 c = verts[size_t(rng() % verts.size())] + 0.2 * scale * Vec3(u(rng), u(rng), u(rng));
        const double s = 0.3 * scale;
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        const double exact = distance_convex_triangle_by_faces(without, tris, int(tool.mesh.triangles.size()), a, b, d);
        const double lower = capsule_lower_bound(with, a, b, d);
        EXPECT_LE(lower, exact + 1e-12 * scale) << "trial " << t;
        useful += lower > 0.5 * exact && exact > 0.0;
        // With the bound in place the distance is still exact when it matters (below the cutoff).
        EXPECT_NEAR(distance_convex_triangle(with, tris, int(tool.mesh.triangles.size()), a, b, d, 1e300), exact,
                    1e-12 * scale);
        EXPECT_NEAR(distance_convex_triangle(without, tris, int(tool.mesh.triangles.size()), a, b, d), exact, 1e-13);
    }
    EXPECT_GT(useful, 100);  // the bound is not vacuous
}

TEST(CapsuleBound, NeverExceedsTheExactDistance) {
    capsule_bound_holds(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 6);
    capsule_bound_holds(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 7);
}

// The bound measures only the capsules the triangle's sphere leaves in question; its least is the
// least over every capsule's exact distance, to the bit, for triangles beside, across and far
// from the chain.
TEST(CapsuleBound, IsTheLeastOverEveryCapsule) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int spared = 0;
    for (int t = 0; t < 20000; ++t) {
        const double scale = 1e-3;
        pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng)) * scale);
        const ConvexView view = pt.view(true, true);
        ASSERT_GT(view.capsule_count, 1);
        const Vec3 c = pt.verts[size_t(rng() % pt.verts.size())] + (t % 3 == 0 ? 5.0 : 0.3) * scale *
                                                                      Vec3(u(rng), u(rng), u(rng));
        const double s = (t % 4 == 0 ? 2.0 : 0.1) * scale;
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        double every = 1e300;
        int under = 0;
        for (int k = 0; k < view.capsule_count; ++k) {
            const double dk = segment_triangle_distance(view.capsule[k], view.capsule[k + 1], a, b, d) -
                              view.capsule_radii[k];
            every = std::min(every, dk);
        }
        const TriangleSphere ts = triangle_sphere(a, b, d);
        for (int k = 0; k < view.capsule_count; ++k)
            under += capsule_sphere_lower(view.capsule[k], view.capsule[k + 1], view.capsule_radii[k], ts) <
                     every + 1e-9;
        const double bound = capsule_lower_bound(view, a, b, d);
        ASSERT_EQ(std::memcmp(&bound, &every, sizeof(double)), 0) << "trial " << t << ": " << bound << " " << every;
        spared += under < view.capsule_count;
    }
    EXPECT_GT(spared, 10000);  // most triangles leave some capsule unmeasured
}

// The tangent bound on a capsule's distance to a triangle is never above the exact distance (the
// segment's to the triangle less the radius), never below the sphere's bound by more than its
// nanometre of room, and for a small triangle beside the capsule (a gingiva triangle beside the
// probe) within a few micrometres of the distance, where the sphere's bound is off by about the
// triangle's size.
TEST(CapsuleBound, TangentBoundIsBelowTheDistanceAndAboveTheSphere) {
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double scale = 1e-3;
    int beside = 0, tight = 0, sphere_tight = 0;
    for (int t = 0; t < 50000; ++t) {
        const Vec3 p0 = scale * Vec3(u(rng), u(rng), u(rng)), p1 = p0 + 2.0 * scale * Vec3(u(rng), u(rng), u(rng));
        const double r = 0.25 * scale * (1.0 + u(rng));
        // A triangle at a random place, or a small one beside the axis (one in four).
        const bool small = t % 4 == 0;
        const double s = (small ? 0.05 : (t % 2 == 0 ? 2.0 : 0.3)) * scale;
        Vec3 c = scale * Vec3(u(rng), u(rng), u(rng)) * 2.0;
        if (small) {
            const Vec3 d = p1 - p0;
            const Vec3 side = glm::normalize(glm::cross(d, Vec3(u(rng), u(rng), u(rng))));
            c = p0 + 0.5 * (1.0 + u(rng)) * d + side * (r + 0.1 * scale * (1.5 + u(rng)));
        }
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   e = c + s * Vec3(u(rng), u(rng), u(rng));
        const TriangleSphere ts = triangle_sphere(a, b, e);
        const double exact = segment_triangle_distance(p0, p1, a, b, e) - r;
        const double tangent = capsule_tangent_lower(p0, p1, r, ts, a, b, e);
        const double sphere = capsule_sphere_lower(p0, p1, r, ts);
        ASSERT_LE(tangent, exact) << "trial " << t;
        ASSERT_GE(tangent, sphere - 2e-9) << "trial " << t;
        if (small && exact > 0.0) {
            ++beside;
            tight += exact - tangent < 5e-6;
            sphere_tight += exact - sphere < 5e-6;
        }
    }
    EXPECT_GT(beside, 10000);
    EXPECT_GT(tight, beside * 9 / 10);         // the tangent bound is tight beside the capsule
    EXPECT_LT(sphere_tight, beside / 10);      // where the sphere's is not
}

// The tapered capsules hold the probe's tip: their tangent bound is never above the exact
// distance from the piece to a triangle, and, on a tapering tip, for small triangles beside it (a
// gingiva triangle beside the probe in a pocket) it falls short of that distance by clearly less
// than the capsules' own tangent bound does. A taper is never wider than its capsule.
void taper_bound_holds(ProbeKind kind, unsigned seed) {
    PlacedTool pt(make_probe_tip_collision(kind));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const ToolPiece& piece = pt.tool->pieces[0];
    ASSERT_EQ(piece.capsule_count, kToolCapsules);
    int tapered = 0;
    for (int k = 0; k < kToolCapsules; ++k) {
        EXPECT_LE(piece.taper_radii_m[size_t(k)][0], piece.capsule_radii_m[size_t(k)]);
        EXPECT_LE(piece.taper_radii_m[size_t(k)][1], piece.capsule_radii_m[size_t(k)]);
        tapered += std::min(piece.taper_radii_m[size_t(k)][0], piece.taper_radii_m[size_t(k)][1]) <
                   0.9 * piece.capsule_radii_m[size_t(k)];
    }
    EXPECT_GE(tapered, 1);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto* tris = piece_triangles(*pt.tool, 0);
    int beside = 0;
    double slack_taper = 0.0, slack_capsule = 0.0;
    for (int t = 0; t < 4000; ++t) {
        pt.place(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))), 1e-3 * Vec3(u(rng), u(rng), u(rng)));
        const ConvexView view = pt.view(true, true);
        const ConvexView plain = pt.view(true);
        // A small triangle beside the piece: off a vertex, outwards from the axis.
        const Vec3 v = pt.verts[size_t(rng() % pt.verts.size())];
        const Vec3 axis = glm::normalize(view.capsule[kToolCapsules] - view.capsule[0]);
        const Vec3 on_axis = view.capsule[0] + glm::dot(v - view.capsule[0], axis) * axis;
        const Vec3 out = glm::length(v - on_axis) > 0.0 ? glm::normalize(v - on_axis) : Vec3(1.0, 0.0, 0.0);
        const bool small = t % 2 == 0;
        const Vec3 c = v + out * (small ? 0.1e-3 * (1.2 + u(rng)) : 0.5e-3 * (1.0 + u(rng))) +
                       (small ? 0.02e-3 : 0.3e-3) * Vec3(u(rng), u(rng), u(rng));
        const double s = small ? 0.04e-3 : 0.5e-3;
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        const TriangleSphere ts = triangle_sphere(a, b, d);
        double taper = 1e300, capsule = 1e300;
        for (int k = 0; k < view.capsule_count; ++k) {
            taper = std::min(taper, taper_tangent_lower(view.capsule[k], view.capsule[k + 1],
                                                        piece.taper_radii_m[size_t(k)][0],
                                                        piece.taper_radii_m[size_t(k)][1], ts, a, b, d));
            capsule = std::min(capsule, capsule_tangent_lower(view.capsule[k], view.capsule[k + 1],
                                                              view.capsule_radii[k], ts, a, b, d));
        }
        const double exact =
            distance_convex_triangle_by_faces(plain, tris, int(pt.tool->mesh.triangles.size()), a, b, d);
        ASSERT_LE(taper, exact) << "trial " << t;
        if (small && exact > 0.0) {
            ++beside;
            slack_taper += exact - taper;
            slack_capsule += exact - capsule;
        }
    }
    EXPECT_GT(beside, 1000);
    // By how much the bounds fall short of the distance, summed: Williams 36.5 against 71.8 µm a
    // triangle on average, Nabers (short and curved, the taper helps less) 81.8 against 105.5 µm.
    EXPECT_LT(slack_taper, 0.9 * slack_capsule);
}

TEST(CapsuleBound, TaperHoldsTheProbeAndBoundsItCloser) {
    taper_bound_holds(ProbeKind::Williams, 21);
    taper_bound_holds(ProbeKind::Nabers, 22);
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

namespace sulcus {
namespace {

// GJK's bounds bracket the exact distance (triangles of the polytope against the triangle), meet
// it within their tolerance, and say 0 exactly when the separating-axis test finds an overlap.
void gjk_brackets_the_distance(const TriMesh& tool_mesh, double scale, unsigned seed) {
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const ModelTool& tool = *pt.tool;
    const std::vector<Vec3>& verts = pt.verts;
    const std::vector<Vec3>& normals = pt.normals;
    const std::vector<double>& offsets = pt.offsets;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto* tris = piece_triangles(tool, 0);
    int separated = 0, overlapping = 0, touching_close = 0;
    long warm_iterations = 0, cold_iterations = 0;
    GjkSimplex last;
    for (int t = 0; t < 3000; ++t) {
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        pt.place(q, Vec3(u(rng) * scale, u(rng) * scale, u(rng) * scale));
        const ConvexView view = pt.view(true);
        // Triangles of every size near a tool vertex, some lying on a tool face at a tiny gap.
        const Vec3 c = verts[size_t(rng() % verts.size())] + 0.2 * scale * Vec3(u(rng), u(rng), u(rng));
        const double s = scale * std::pow(10.0, -2.0 + 2.0 * (u(rng) + 1.0) / 2.0);
        Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
             d = c + s * Vec3(u(rng), u(rng), u(rng));
        if (t % 5 == 0) {
            // Flat on face f, 1e-9..1e-5 m off it.
            const int f = int(rng() % tool.face_normals.size());
            const Vec3 n = normals[size_t(f)];
            const double gap = std::pow(10.0, -9.0 + 4.0 * (u(rng) + 1.0) / 2.0);
            for (Vec3* x : {&a, &b, &d}) *x += (offsets[size_t(f)] + gap - glm::dot(n, *x)) * n;
        }
        const double exact = distance_convex_triangle_by_faces(view, tris, int(tool.mesh.triangles.size()), a, b, d);
        const DistanceBounds g = convex_triangle_distance(verts.data(), int(verts.size()), a, b, d);
        ASSERT_LE(g.lower, exact + 1e-13) << "trial " << t;
        ASSERT_GE(g.upper, exact - 1e-13) << "trial " << t;
        if (exact > 0.0) {
            ++separated;
            EXPECT_NEAR(g.lower, exact, 1e-12) << "trial " << t;
            touching_close += exact < 1e-6;
        } else {
            ++overlapping;
            EXPECT_EQ(g.lower, 0.0) << "trial " << t;
        }
        // A cutoff stops it early with a lower bound of at least the cutoff, or the distance.
        const DistanceBounds cut = convex_triangle_distance(verts.data(), int(verts.size()), a, b, d, 0.5 * exact);
        EXPECT_LE(cut.lower, exact + 1e-13);
        EXPECT_GE(cut.lower, std::min(0.5 * exact, g.lower) - 1e-13);
        // Warm-started from any simplex - the same pair's own, the last trial's (another pose and
        // triangle), or indices made up, some out of range - the bounds are as good as cold.
        GjkSimplex junk;
        junk.count = uint8_t(rng() % 5);
        for (int i = 0; i < 4; ++i) {
            junk.tri[i] = uint8_t(rng() % 4);
            junk.poly[i] = uint16_t(rng() % (verts.size() + 3));
        }
        for (const GjkSimplex* warm : {&g.simplex, static_cast<const GjkSimplex*>(&last), static_cast<const GjkSimplex*>(&junk)}) {
            const DistanceBounds w = convex_triangle_distance(verts.data(), int(verts.size()), a, b, d, 1e300, 1e-13,
                                                              64, nullptr, warm);
            ASSERT_LE(w.lower, exact + 1e-13) << "trial " << t;
            ASSERT_GE(w.upper, exact - 1e-13) << "trial " << t;
            if (exact > 0.0) EXPECT_NEAR(w.lower, exact, 1e-12) << "trial " << t;
            else EXPECT_EQ(w.lower, 0.0) << "trial " << t;
        }
        // Its own simplex settles the same pair at once.
        if (g.simplex.count > 0) {
            const DistanceBounds again = convex_triangle_distance(verts.data(), int(verts.size()), a, b, d, 1e300,
                                                                  1e-13, 64, nullptr, &g.simplex);
            EXPECT_LE(again.iterations, std::max(g.iterations, 2)) << "trial " << t;
            warm_iterations += again.iterations;
            cold_iterations += g.iterations;
        }
        last = g.simplex;
    }
    EXPECT_LT(warm_iterations, cold_iterations);
    EXPECT_GT(separated, 300);
    EXPECT_GT(overlapping, 300);
    EXPECT_GT(touching_close, 50);
}

// With no iterations, the last search's direction and simplex taken at a nearby pose still
// bracket the distance there, and tightly for a small motion: the gap along the direction below,
// the nearer of the direction's point and the simplex's closest point above. A made-up simplex
// or none still gives bounds that hold.
TEST(Gjk, WithoutIterationsTheLastDirectionAndSimplexBracketTheDistance) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const ModelTool& tool = *pt.tool;
    const auto* tris = piece_triangles(tool, 0);
    const double scale = 1e-3;
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int separated = 0, tight = 0;
    for (int t = 0; t < 2000; ++t) {
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 p(u(rng) * scale, u(rng) * scale, u(rng) * scale);
        pt.place(q, p);
        const Vec3 c = pt.verts[size_t(rng() % pt.verts.size())] + 0.05 * scale * Vec3(u(rng), u(rng), u(rng));
        const double s = scale * std::pow(10.0, -2.0 + 1.5 * (u(rng) + 1.0) / 2.0);
        const Vec3 a = c + s * Vec3(u(rng), u(rng), u(rng)), b = c + s * Vec3(u(rng), u(rng), u(rng)),
                   d = c + s * Vec3(u(rng), u(rng), u(rng));
        const DistanceBounds before =
            convex_triangle_distance(pt.view(true), a, b, d, 1e300, 1e-13, 64, nullptr, nullptr);
        // A motion of up to 10 um and 1 mrad.
        const double step = 1e-5 * (u(rng) + 1.0) / 2.0;
        pt.place(glm::normalize(Quat(1.0, 5e-4 * u(rng), 5e-4 * u(rng), 5e-4 * u(rng)) * q),
                 p + step * glm::normalize(Vec3(u(rng), u(rng), u(rng))));
        const ConvexView view = pt.view(true);
        const double exact = distance_convex_triangle_by_faces(view, tris, int(tool.mesh.triangles.size()), a, b, d);
        const Vec3* hint = glm::dot(before.direction, before.direction) > 0.0 ? &before.direction : nullptr;
        const DistanceBounds quick = convex_triangle_distance(view, a, b, d, 1e300, 1e-13, 0, hint, &before.simplex);
        ASSERT_LE(quick.lower, exact + 1e-13) << "trial " << t;
        ASSERT_GE(quick.upper, exact) << "trial " << t;
        if (exact > 0.0) {
            ++separated;
            tight += quick.upper - quick.lower <= 1e-5;
        }
        GjkSimplex junk;
        junk.count = uint8_t(rng() % 5);
        for (int i = 0; i < 4; ++i) {
            junk.tri[i] = uint8_t(rng() % 4);
            junk.poly[i] = uint16_t(rng() % (pt.verts.size() + 3));
        }
        for (const GjkSimplex* warm : {static_cast<const GjkSimplex*>(&junk), static_cast<const GjkSimplex*>(nullptr)}) {
            const DistanceBounds w = convex_triangle_distance(view, a, b, d, 1e300, 1e-13, 0, nullptr, warm);
            ASSERT_LE(w.lower, exact + 1e-13) << "trial " << t;
            ASSERT_GE(w.upper, exact) << "trial " << t;
        }
    }
    EXPECT_GT(separated, 500);
    EXPECT_GT(tight, separated * 95 / 100);  // within 10 um (most within 1 um)
}

// The check of a separation against a floor: whatever it returns is a lower bound on the
// separation (the distance when apart, the overlap's negative by the separating-axis test when
// not), its upper bound holds, and a floor under the separation of a pair that has moved a little
// since the search that gave the hint is met. A floor below zero (an overlap allowed) is met
// along the hint by a pair resting in contact, with no search: the case the guard's check at a
// new pose is about.
TEST(Gjk, TheSeparationCheckBoundsTheSeparationAndMeetsAFloorUnderIt) {
    PlacedTool pt(make_probe_tip_collision(ProbeKind::Williams));
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    const ModelTool& tool = *pt.tool;
    const auto* tris = piece_triangles(tool, 0);
    const int face_count = int(pt.normals.size());
    const double scale = 1e-3;
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int apart = 0, met = 0, resting = 0, resting_at_once = 0;
    for (int t = 0; t < 3000; ++t) {
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 p(u(rng) * scale, u(rng) * scale, u(rng) * scale);
        pt.place(q, p);
        // Every third trial a triangle lying on a face plane of the tool within +-0.1 um (the tool
        // resting on it, or just into it), else one near a vertex.
        Vec3 a, b, d;
        const bool on_face = t % 3 == 0;
        if (on_face) {
            const int f = int(rng() % uint32_t(face_count));
            const Vec3 n = pt.normals[size_t(f)];
            const Vec3 c = pt.verts[size_t(rng() % pt.verts.size())];
            const double s = 0.05 * scale;
            a = c + s * Vec3(u(rng), u(rng), u(rng));
            b = c + s * Vec3(u(rng), u(rng), u(rng));
            d = c + s * Vec3(u(rng), u(rng), u(rng));
            const double height = 1e-7 * u(rng);
            for (Vec3* x : {&a, &b, &d}) *x += (pt.offsets[size_t(f)] + height - glm::dot(n, *x)) * n;
        } else {
            const Vec3 c = pt.verts[size_t(rng() % pt.verts.size())] + 0.05 * scale * Vec3(u(rng), u(rng), u(rng));
            const double s = scale * std::pow(10.0, -2.0 + 1.5 * (u(rng) + 1.0) / 2.0);
            a = c + s * Vec3(u(rng), u(rng), u(rng));
            b = c + s * Vec3(u(rng), u(rng), u(rng));
            d = c + s * Vec3(u(rng), u(rng), u(rng));
        }
        const DistanceBounds before = convex_triangle_distance(pt.view(true), a, b, d, 1e300, 1e-13, 64, nullptr, nullptr);
        // A motion of up to 0.1 um and 10 urad since.
        const double step = 1e-7 * (u(rng) + 1.0) / 2.0;
        pt.place(glm::normalize(Quat(1.0, 5e-6 * u(rng), 5e-6 * u(rng), 5e-6 * u(rng)) * q),
                 p + step * glm::normalize(Vec3(u(rng), u(rng), u(rng))));
        const ConvexView view = pt.view(true);
        const double distance = distance_convex_triangle_by_faces(view, tris, int(tool.mesh.triangles.size()), a, b, d);
        const double separation = distance > 0.0 ? distance : separate_convex_triangle(view, a, b, d).separation;
        const Vec3* hint = glm::dot(before.direction, before.direction) > 0.0 ? &before.direction : nullptr;
        const GjkSimplex* warm = before.simplex.count > 0 ? &before.simplex : nullptr;
        for (const double floor : {separation - 1e-9, separation - 1e-6, separation + 1e-9, -1e-7}) {
            for (const int iterations : {0, 64}) {
                const DistanceBounds r = convex_triangle_separation(view, a, b, d, floor, -1e300, hint, warm, iterations);
                ASSERT_LE(r.separation, separation + 1e-13) << "trial " << t << " floor " << floor;
                ASSERT_GE(r.upper, distance - 1e-13) << "trial " << t << " floor " << floor;
                if (iterations > 0 && distance > 1e-8 && floor <= separation - 1e-9) {
                    // Apart: the search goes on to the distance, which meets the floor.
                    ++apart;
                    met += r.separation >= floor;
                }
            }
            // Given up once the distance is known under a bound: it is under it.
            const DistanceBounds g = convex_triangle_separation(view, a, b, d, floor, floor, hint, warm);
            ASSERT_LE(g.separation, separation + 1e-13) << "trial " << t;
            if (g.separation < floor) {
                EXPECT_GE(g.upper, distance - 1e-13) << "trial " << t;
            }
        }
        if (on_face && hint && separation >= -5e-8) {
            ++resting;
            resting_at_once +=
                convex_triangle_separation(view, a, b, d, -1e-7, -1e300, hint, warm, 0).separation >= -1e-7;
        }
    }
    EXPECT_GT(apart, 2000);
    EXPECT_EQ(met, apart);
    EXPECT_GT(resting, 300);
    EXPECT_GT(resting_at_once, resting * 9 / 10);
}

// piece_compliant_bound4 gives each of its four triangles the bound piece_compliant_bound gives it,
// to the bit (memcmp): over the probe tips' pieces with capsules at random poses, with triangles
// of 5 um to 0.55 mm round a tool vertex (apart from the capsules and overlapping them, in every
// mix across the four), far ones, and ones whose sphere is centred on a capsule point (the tangent
// bound's own fallback there).
void bound4_matches(const TriMesh& tool_mesh, double scale, int trials, unsigned seed) {
#if defined(__AVX2__)
    PlacedTool pt(tool_mesh);
    ASSERT_TRUE(pt.mb.model) << pt.mb.error;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int with_capsules = 0, apart = 0, overlapping = 0, mixed = 0, centred = 0;
    for (size_t k = 0; k < pt.tool->pieces.size(); ++k) {
        const ToolPiece& piece = pt.tool->pieces[k];
        if (piece.capsule_count == 0) continue;
        ++with_capsules;
        for (int t = 0; t < trials; ++t) {
            place_at_random(pt, rng, u, scale);
            const CapsuleLine line = capsule_line(piece, pt.caps + k * (kToolCapsules + 1));
            Vec3 corner[4][3];
            TriangleSphere sphere[4];
            for (int lane = 0; lane < 4; ++lane) {
                Vec3& a = corner[lane][0];
                Vec3& b = corner[lane][1];
                Vec3& d = corner[lane][2];
                triangle_near_vertex(pt, rng, u, scale, a, b, d);
                const int kind = int(rng() % 8);
                if (kind == 0) {
                    // Far off.
                    const Vec3 away = 20.0 * scale * Vec3(u(rng), u(rng), u(rng));
                    a += away, b += away, d += away;
                } else if (kind == 1) {
                    // Small.
                    const double shrink = 0.01;
                    b = a + shrink * (b - a), d = a + shrink * (d - a);
                }
                sphere[lane] = triangle_sphere(a, b, d);
                if (kind == 2) {
                    sphere[lane].centre = line.axis[rng() % (piece.capsule_count + 1)];
                    sphere[lane].centre_norm_m = glm::length(sphere[lane].centre);
                    ++centred;
                }
            }
            const TriangleSphere* spheres[4];
            const Vec3* corners[4][3];
            for (int lane = 0; lane < 4; ++lane) {
                spheres[lane] = &sphere[lane];
                for (int m = 0; m < 3; ++m) corners[lane][m] = &corner[lane][m];
            }
            double four[4];
            piece_compliant_bound4(piece, line, spheres, corners, four);
            int lanes_apart = 0;
            for (int lane = 0; lane < 4; ++lane) {
                const double one = piece_compliant_bound(piece, line, sphere[lane], corner[lane][0], corner[lane][1],
                                                         corner[lane][2]);
                ASSERT_EQ(std::memcmp(&one, &four[lane], sizeof one), 0)
                    << "piece " << k << ", trial " << t << ", lane " << lane << ": " << one << " against " << four[lane];
                lanes_apart += one > 0.0;
            }
            apart += lanes_apart;
            overlapping += 4 - lanes_apart;
            mixed += lanes_apart > 0 && lanes_apart < 4;
        }
    }
    EXPECT_GT(with_capsules, 0);
    EXPECT_GT(apart, trials);
    EXPECT_GT(overlapping, trials / 4);
    EXPECT_GT(mixed, trials / 10);
    EXPECT_GT(centred, trials / 10);
#else
    (void)tool_mesh, (void)scale, (void)trials, (void)seed;
    GTEST_SKIP() << "built without AVX2: there is no four-wide bound";
#endif
}

TEST(CapsuleBounds, FourAtATimeGiveEachTriangleItsOwnBoundToTheBit) {
    bound4_matches(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 3000, 21);
    bound4_matches(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 3000, 22);
}

TEST(Gjk, BoundsBracketTheExactDistanceOnABox) { gjk_brackets_the_distance(make_box(Vec3(1e-3, 2e-3, 0.5e-3)), 2e-3, 8); }

TEST(Gjk, BoundsBracketTheExactDistanceOnProbeTips) {
    gjk_brackets_the_distance(make_probe_tip_collision(ProbeKind::Williams), 1e-3, 9);
    gjk_brackets_the_distance(make_probe_tip_collision(ProbeKind::Nabers), 1e-3, 10);
}

}  // namespace
}  // namespace sulcus
