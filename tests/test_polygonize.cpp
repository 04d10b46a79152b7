// The implicit-to-mesh path: closed manifold output, vertices on the zero set, topology kept,
// decimation within its error bound.
#include "sulcus/content/polygonize.h"
#include "decimate_detail.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>
#include <stdexcept>

namespace sulcus {
namespace {

double sphere(const Vec3& p, const Vec3& c, double r) { return glm::length(p - c) - r; }

double torus(const Vec3& p, double R, double r) {
    const double q = std::sqrt(p.x * p.x + p.z * p.z) - R;
    return std::sqrt(q * q + p.y * p.y) - r;
}

int euler_characteristic(const TriMesh& m) {
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
            edges.insert({std::min(a, b), std::max(a, b)});
        }
    return int(m.vertices.size()) - int(edges.size()) + int(m.triangles.size());
}

TEST(Polygonize, SphereIsClosedOutwardAndOnTheSurface) {
    const double r = 3e-3;
    const Vec3 c(0.2e-3, -0.1e-3, 0.05e-3);
    const TriMesh m = polygonize([&](const Vec3& p) { return sphere(p, c, r); },
                                 Aabb{Vec3(-4e-3), Vec3(4e-3)}, PolygonizeSettings{2e-4, 24});
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_EQ(euler_characteristic(m), 2);
    for (const Vec3& v : m.vertices) EXPECT_NEAR(glm::length(v - c), r, 0.011 * 2e-4 * 1.8);
    const double exact = 4.0 / 3.0 * M_PI * r * r * r;
    EXPECT_NEAR(mesh_volume(m), exact, 0.01 * exact);
}

TEST(Polygonize, TorusKeepsItsGenus) {
    const TriMesh m = polygonize([&](const Vec3& p) { return torus(p, 3e-3, 1e-3); },
                                 Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{2e-4, 24});
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_EQ(euler_characteristic(m), 0);
}

TEST(Polygonize, TwoSeparateSolidsGiveTwoShells) {
    auto f = [](const Vec3& p) {
        return std::min(sphere(p, Vec3(-3e-3, 0, 0), 1.5e-3), sphere(p, Vec3(3e-3, 0, 0), 1.5e-3));
    };
    const TriMesh m = polygonize(f, Aabb{Vec3(-6e-3), Vec3(6e-3)}, PolygonizeSettings{2.5e-4, 24});
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_EQ(euler_characteristic(m), 4);
}

TEST(Polygonize, ThinSlabFarFromTheCoarseCornersIsFound) {
    // A 0.3 mm plate: far thinner than a block, its surface must still be extracted whole.
    auto f = [](const Vec3& p) {
        const Vec3 q = glm::abs(p) - Vec3(3e-3, 0.15e-3, 3e-3);
        return glm::length(glm::max(q, Vec3(0.0))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    };
    const TriMesh m = polygonize(f, Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{1e-4, 24});
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_NEAR(mesh_volume(m), 6e-3 * 0.3e-3 * 6e-3, 0.05 * 6e-3 * 0.3e-3 * 6e-3);
}

TEST(Polygonize, SolidCutByTheBoxIsRejected) {
    EXPECT_THROW(polygonize([](const Vec3& p) { return sphere(p, Vec3(0.0), 5e-3); },
                            Aabb{Vec3(-4e-3), Vec3(4e-3)}, PolygonizeSettings{2e-4, 24}),
                 std::invalid_argument);
    EXPECT_THROW(polygonize([](const Vec3& p) { return sphere(p, Vec3(0.0), 1e-3); },
                            Aabb{Vec3(-4e-3), Vec3(4e-3)}, PolygonizeSettings{0.0, 24}),
                 std::invalid_argument);
}

TEST(Polygonize, OutputIsDeterministic) {
    auto f = [](const Vec3& p) { return torus(p, 3e-3, 1e-3); };
    const TriMesh a = polygonize(f, Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{3e-4, 24});
    const TriMesh b = polygonize(f, Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{3e-4, 24});
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    EXPECT_EQ(a.triangles, b.triangles);
    for (size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]);
}

TEST(Decimate, StaysClosedAndWithinTheErrorBound) {
    const double r = 3e-3;
    const TriMesh fine = polygonize([&](const Vec3& p) { return sphere(p, Vec3(0.0), r); },
                                    Aabb{Vec3(-4e-3), Vec3(4e-3)}, PolygonizeSettings{1.5e-4, 24});
    const double tol = 2e-5;
    const TriMesh coarse = decimate(fine, DecimateSettings{tol, 0, 0.5, 20.0});
    ASSERT_EQ(validate_mesh(coarse), "");
    EXPECT_EQ(euler_characteristic(coarse), 2);
    EXPECT_LT(coarse.triangles.size(), fine.triangles.size() / 3);
    // Vertices stay within the bound of the sphere (the fine mesh is itself within ~2 um of it).
    for (const Vec3& v : coarse.vertices) EXPECT_NEAR(glm::length(v), r, tol + 4e-6);
}

TEST(Decimate, StopsAtTheTargetCount) {
    const TriMesh fine = polygonize([&](const Vec3& p) { return torus(p, 3e-3, 1e-3); },
                                    Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{2e-4, 24});
    const TriMesh coarse = decimate(fine, DecimateSettings{1.0, 2000, 1.0, 20.0});
    ASSERT_EQ(validate_mesh(coarse), "");
    EXPECT_LE(coarse.triangles.size(), 2002u);
    EXPECT_EQ(euler_characteristic(coarse), 0);
}

// The decimater answers its topology check and halfedge lookup itself (the packaged library's own check is slowed by
// its asserts); the two must agree on every halfedge: on a closed mesh, on one with holes (boundary
// edges and vertices), on a tetrahedron (whose one-rings share all but the edge's own ends), and after
// collapses have left deleted edges and vertices behind.
TEST(Decimate, TopologyCheckAgreesWithOpenMeshOnEveryHalfedge) {
    const TriMesh torus_mesh = polygonize([&](const Vec3& p) { return torus(p, 3e-3, 1e-3); },
                                          Aabb{Vec3(-5e-3), Vec3(5e-3)}, PolygonizeSettings{5e-4, 24});
    TriMesh holed = torus_mesh;
    // Holes: drop every 40th triangle, and a run of neighbours so that some holes are large.
    std::vector<std::array<uint32_t, 3>> kept;
    for (size_t i = 0; i < holed.triangles.size(); ++i)
        if (i % 40 != 0 && (i < 100 || i > 130)) kept.push_back(holed.triangles[i]);
    holed.triangles = kept;
    TriMesh tetra;
    tetra.vertices = {Vec3(0.0), Vec3(1e-3, 0.0, 0.0), Vec3(0.0, 1e-3, 0.0), Vec3(0.0, 0.0, 1e-3)};
    tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

    for (const TriMesh* m : std::array<const TriMesh*, 3>{&torus_mesh, &holed, &tetra}) {
        const auto c = decimate_detail::compare_collapse_checks(*m, 60);
        EXPECT_EQ(c.disagreed, 0u);
        EXPECT_GT(c.compared, 0u);
        // Both answers occur, so the comparison is not of a constant.
        EXPECT_GT(c.allowed, 0u);
        EXPECT_LT(c.allowed, c.compared);
        EXPECT_GT(c.found, 0u);
        EXPECT_LT(c.found, c.found_compared);
    }
}

TEST(SmoothMinMax, MatchPlainMinMaxAwayFromTheSeam) {
    EXPECT_DOUBLE_EQ(smooth_min(1.0, 3.0, 0.5), 1.0);
    EXPECT_DOUBLE_EQ(smooth_max(1.0, 3.0, 0.5), 3.0);
    EXPECT_DOUBLE_EQ(smooth_min(1.0, 3.0, 0.0), 1.0);
    // At the seam the union grows (the blend adds material), the intersection shrinks.
    EXPECT_LT(smooth_min(1.0, 1.0, 0.5), 1.0);
    EXPECT_GT(smooth_max(1.0, 1.0, 0.5), 1.0);
    // Continuous across the blend boundary.
    EXPECT_NEAR(smooth_min(1.0, 1.5 - 1e-12, 0.5), smooth_min(1.0, 1.5, 0.5), 1e-9);
}

}  // namespace
}  // namespace sulcus
