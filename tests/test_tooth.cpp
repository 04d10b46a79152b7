// Procedural teeth: the anatomy table and numbering, the implicit field (sign, distance, CEJ,
// sites, furcations), and meshes measured against the table for every supported tooth.
#include "sulcus/content/tooth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace sulcus {
namespace {

constexpr double kMm = 1e-3;

// Extents of a mesh: height range, crown (y > 0) extents in x and z, and the extents of its cross
// section with the plane y = 0 (from the crossing points of its edges).
struct Extents {
    double y_min = 1e9, y_max = -1e9;
    double crown_x[2] = {1e9, -1e9}, crown_z[2] = {1e9, -1e9};
    double cervix_x[2] = {1e9, -1e9}, cervix_z[2] = {1e9, -1e9};
};

Extents measure(const TriMesh& m) {
    Extents e;
    for (const Vec3& v : m.vertices) {
        e.y_min = std::min(e.y_min, v.y);
        e.y_max = std::max(e.y_max, v.y);
        if (v.y > 0.0) {
            e.crown_x[0] = std::min(e.crown_x[0], v.x);
            e.crown_x[1] = std::max(e.crown_x[1], v.x);
            e.crown_z[0] = std::min(e.crown_z[0], v.z);
            e.crown_z[1] = std::max(e.crown_z[1], v.z);
        }
    }
    for (const auto& t : m.triangles)
        for (size_t k = 0; k < 3; ++k) {
            const Vec3 a = m.vertices[t[k]], b = m.vertices[t[(k + 1) % 3]];
            if ((a.y < 0.0) == (b.y < 0.0)) continue;
            const Vec3 p = a + (b - a) * (a.y / (a.y - b.y));
            e.cervix_x[0] = std::min(e.cervix_x[0], p.x);
            e.cervix_x[1] = std::max(e.cervix_x[1], p.x);
            e.cervix_z[0] = std::min(e.cervix_z[0], p.z);
            e.cervix_z[1] = std::max(e.cervix_z[1], p.z);
        }
    return e;
}

class EveryTooth : public ::testing::TestWithParam<int> {};

TEST_P(EveryTooth, MeshIsValidAndMatchesTheTable) {
    const int fdi = GetParam();
    const ToothDimensions& d = tooth_dimensions(fdi);
    const TriMesh m = make_tooth_mesh(fdi, ToothMeshSettings{2.5e-4, 0.0, 0});
    ASSERT_EQ(validate_mesh(m), "") << "tooth " << fdi;
    const Extents e = measure(m);
    const double tol = 0.15 * kMm;
    EXPECT_NEAR(e.y_max, d.crown_length_mm * kMm, 0.1 * kMm) << "crown length, tooth " << fdi;
    EXPECT_NEAR(-e.y_min, d.root_length_mm * kMm, tol) << "root length, tooth " << fdi;
    EXPECT_NEAR(e.crown_x[1] - e.crown_x[0], d.crown_md_mm * kMm, tol) << "crown MD, tooth " << fdi;
    EXPECT_NEAR(e.crown_z[1] - e.crown_z[0], d.crown_bl_mm * kMm, tol) << "crown BL, tooth " << fdi;
    EXPECT_NEAR(e.cervix_x[1] - e.cervix_x[0], d.cervix_md_mm * kMm, tol) << "cervix MD, tooth " << fdi;
    EXPECT_NEAR(e.cervix_z[1] - e.cervix_z[0], d.cervix_bl_mm * kMm, tol) << "cervix BL, tooth " << fdi;
}

TEST_P(EveryTooth, FieldIsNegativeOnTheAxisAndPositiveOutsideTheBounds) {
    const int fdi = GetParam();
    const ToothShape s(fdi);
    const ToothDimensions& d = s.dims();
    // The axis is inside from the bottom of the root (single root) or of the trunk up to the
    // crown; molar and premolar crowns are only sampled below their fossae.
    const bool occlusal_table = d.cls != ToothClass::CentralIncisor && d.cls != ToothClass::LateralIncisor &&
                                d.cls != ToothClass::Canine;
    const double y_lo = d.roots > 1 ? -0.9 * d.trunk_length_mm : -0.9 * d.root_length_mm;
    const double y_hi = (occlusal_table ? 0.6 : 0.95) * d.crown_length_mm;
    for (int i = 0; i <= 50; ++i) {
        const double y = (y_lo + (y_hi - y_lo) * i / 50.0) * kMm;
        EXPECT_LT(s.field(Vec3(0.0, y, 0.0)), 0.0) << "tooth " << fdi << " y " << y;
    }
    // Faces of the bounds, and of the bounds grown by 1 mm.
    for (double grow : {0.0, 1.0 * kMm}) {
        Aabb b = s.bounds();
        b.inflate(grow);
        const int n = 12;
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side)
                for (int i = 0; i <= n; ++i)
                    for (int j = 0; j <= n; ++j) {
                        Vec3 p;
                        p[axis] = side ? b.hi[axis] : b.lo[axis];
                        p[(axis + 1) % 3] = b.lo[(axis + 1) % 3] + (b.hi - b.lo)[(axis + 1) % 3] * i / n;
                        p[(axis + 2) % 3] = b.lo[(axis + 2) % 3] + (b.hi - b.lo)[(axis + 2) % 3] * j / n;
                        EXPECT_GT(s.field(p), 0.0) << "tooth " << fdi;
                    }
    }
}

TEST_P(EveryTooth, CejCurveRisesByTheTableCurvature) {
    const int fdi = GetParam();
    const ToothShape s(fdi);
    const ToothDimensions& d = s.dims();
    const double facial = s.cej_height(0.5 * M_PI), lingual = s.cej_height(-0.5 * M_PI);
    EXPECT_NEAR(facial, 0.0, 1e-12);
    EXPECT_NEAR(lingual, 0.0, 1e-12);
    EXPECT_NEAR(s.cej_height(0.0) - facial, d.cej_curve_mesial_mm * kMm, 1e-9);
    EXPECT_NEAR(s.cej_height(M_PI) - facial, d.cej_curve_distal_mm * kMm, 1e-9);
    for (double th = -M_PI; th <= M_PI; th += 0.1) {
        EXPECT_NEAR(s.cej_height(th), s.cej_height(th + 2.0 * M_PI), 1e-12);
        // Continuous: small steps change little.
        EXPECT_LT(std::abs(s.cej_height(th + 1e-4) - s.cej_height(th)), 1e-6);
    }
}

TEST_P(EveryTooth, SitesLieInTheirQuadrants) {
    const ToothShape s(GetParam());
    EXPECT_DOUBLE_EQ(s.site_angle(Site::B), 0.5 * M_PI);
    EXPECT_DOUBLE_EQ(s.site_angle(Site::L), -0.5 * M_PI);
    const double mb = s.site_angle(Site::MB), db = s.site_angle(Site::DB);
    const double ml = s.site_angle(Site::ML), dl = s.site_angle(Site::DL);
    EXPECT_GT(mb, 0.1);
    EXPECT_LT(mb, 0.5 * M_PI - 0.1);
    EXPECT_GT(db, 0.5 * M_PI + 0.1);
    EXPECT_LT(db, M_PI - 0.1);
    EXPECT_LT(ml, -0.1);
    EXPECT_GT(ml, -0.5 * M_PI + 0.1);
    EXPECT_LT(dl, -0.5 * M_PI - 0.1);
    EXPECT_GT(dl, -M_PI + 0.1);
}

TEST_P(EveryTooth, FurcationEntrancesOpenBetweenTheRoots) {
    const int fdi = GetParam();
    const ToothShape s(fdi);
    const ToothDimensions& d = s.dims();
    const auto furcations = s.furcations();
    std::set<FurcationSide> sides;
    for (const auto& f : furcations) sides.insert(f.side);
    if (d.roots == 1) {
        EXPECT_TRUE(furcations.empty());
        return;
    }
    if (d.roots == 3)
        EXPECT_EQ(sides, (std::set<FurcationSide>{FurcationSide::B, FurcationSide::M, FurcationSide::D}));
    else if (d.upper)
        EXPECT_EQ(sides, (std::set<FurcationSide>{FurcationSide::M, FurcationSide::D}));
    else
        EXPECT_EQ(sides, (std::set<FurcationSide>{FurcationSide::B, FurcationSide::L}));
    ASSERT_EQ(furcations.size(), sides.size());
    for (const auto& f : furcations) {
        EXPECT_NEAR(f.roof_height, -d.trunk_length_mm * kMm, 0.3 * kMm) << "tooth " << fdi;
        EXPECT_NEAR(f.entrance.y, f.roof_height, 1e-12);
        EXPECT_NEAR(glm::length(f.inward), 1.0, 1e-12);
        EXPECT_EQ(f.inward.y, 0.0);
        EXPECT_GT(f.width, 0.1 * kMm) << "tooth " << fdi;
        EXPECT_LT(f.width, 3.0 * kMm) << "tooth " << fdi;
        // Below the roof a ray into the entrance runs between the roots, in free space...
        for (double depth : {0.3, 0.6, 1.0})
            for (double s_mm = 0.0; s_mm <= 1.5; s_mm += 0.1) {
                const Vec3 p = f.entrance + f.inward * (s_mm * kMm) - Vec3(0.0, depth * kMm, 0.0);
                EXPECT_GT(s.field(p), 0.0) << "tooth " << fdi << " side " << int(f.side) << " depth " << depth
                                           << " s " << s_mm;
            }
        // ...while just above the roof the same path is inside the trunk.
        const Vec3 above = f.entrance + f.inward * (1.0 * kMm) + Vec3(0.0, 0.5 * kMm, 0.0);
        EXPECT_LT(s.field(above), 0.0) << "tooth " << fdi;
    }
}

std::vector<int> all_teeth() { return supported_teeth(); }
INSTANTIATE_TEST_SUITE_P(Teeth, EveryTooth, ::testing::ValuesIn(all_teeth()),
                         [](const ::testing::TestParamInfo<int>& info) { return std::to_string(info.param); });

// Vertex normals of a mesh (area-weighted), for stepping off its surface.
std::vector<Vec3> vertex_normals(const TriMesh& m) {
    std::vector<Vec3> n(m.vertices.size(), Vec3(0.0));
    for (const auto& t : m.triangles) {
        const Vec3 a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
        const Vec3 fn = glm::cross(b - a, c - a);
        for (uint32_t v : t) n[v] += fn;
    }
    for (Vec3& v : n) v = glm::normalize(v);
    return n;
}

// Distance from p to triangle abc (closest point by regions).
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return glm::length(ap);
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return glm::length(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return glm::length(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denom = 1.0 / (va + vb + vc);
    return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

// Unsigned distance from p to the mesh, looking only at triangles near p (within reach).
double mesh_distance(const TriMesh& m, const Vec3& p, double reach) {
    double best = reach;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const Vec3 lo = glm::min(a, glm::min(b, c)) - Vec3(best), hi = glm::max(a, glm::max(b, c)) + Vec3(best);
        if (p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x || p.y > hi.y || p.z > hi.z) continue;
        best = std::min(best, point_triangle_distance(p, a, b, c));
    }
    return best;
}

TEST(ToothField, IsCloseToTheSignedDistanceNearTheSurface) {
    for (int fdi : {11, 13, 14, 16, 36}) {
        const ToothShape s(fdi);
        const TriMesh m = make_tooth_mesh(fdi, ToothMeshSettings{1.5e-4, 0.0, 0});
        const std::vector<Vec3> n = vertex_normals(m);
        int checked = 0;
        for (size_t i = 0; i < m.vertices.size(); i += 211) {
            for (double off : {-0.2 * kMm, 0.2 * kMm}) {
                const Vec3 p = m.vertices[i] + n[i] * off;
                const double f = s.field(p);
                // The distance to the (fine) mesh stands for the true distance; narrow gaps such
                // as furcations make it smaller than the offset.
                const double dist = mesh_distance(m, p, 1.0 * kMm);
                // Same sign as the offset, and within a factor of two of the distance.
                EXPECT_GT(f / off, 0.0) << "tooth " << fdi << " vertex " << i;
                EXPECT_GT(std::abs(f), 0.5 * dist) << "tooth " << fdi << " vertex " << i;
                EXPECT_LT(std::abs(f), 2.0 * dist) << "tooth " << fdi << " vertex " << i;
                ++checked;
            }
        }
        EXPECT_GT(checked, 400);
    }
}

TEST(ToothField, LeftAndRightTeethShareTheirShape) {
    for (int i = 1; i <= 7; ++i)
        for (int q : {1, 3}) {
            const ToothShape right_side((q == 1 ? 10 : 40) + i), left_side((q == 1 ? 20 : 30) + i);
            const Aabb b = right_side.bounds();
            EXPECT_EQ(b.lo, left_side.bounds().lo);
            EXPECT_EQ(b.hi, left_side.bounds().hi);
            for (int k = 0; k < 200; ++k) {
                const Vec3 t(std::fmod(k * 0.618, 1.0), std::fmod(k * 0.414, 1.0), std::fmod(k * 0.732, 1.0));
                const Vec3 p = b.lo + (b.hi - b.lo) * t;
                EXPECT_EQ(right_side.field(p), left_side.field(p));
            }
        }
}

TEST(ToothMesh, VisualPresetIsInItsTriangleBudget) {
    for (int fdi : {36}) {
        const TriMesh m = make_tooth_mesh(fdi, tooth_visual_settings());
        ASSERT_EQ(validate_mesh(m), "") << "tooth " << fdi;
        EXPECT_GE(m.triangles.size(), 5000u) << "tooth " << fdi;
        EXPECT_LE(m.triangles.size(), 20000u) << "tooth " << fdi;
    }
}

TEST(ToothTable, UnsupportedNumbersThrow) {
    for (int fdi : {0, 10, 18, 28, 38, 48, 51, 85, 19, 99, -11}) {
        EXPECT_FALSE(is_supported_tooth(fdi)) << fdi;
        EXPECT_THROW(tooth_dimensions(fdi), std::invalid_argument) << fdi;
        EXPECT_THROW(ToothShape{fdi}, std::invalid_argument) << fdi;
        EXPECT_THROW(make_tooth_mesh(fdi, ToothMeshSettings{}), std::invalid_argument) << fdi;
    }
    EXPECT_EQ(supported_teeth().size(), 28u);
    for (int fdi : supported_teeth()) EXPECT_TRUE(is_supported_tooth(fdi));
}

TEST(ToothTable, MirroredTeethShareTheirRow) {
    for (int i = 1; i <= 7; ++i)
        for (auto [a, b] : {std::pair{10 + i, 20 + i}, std::pair{30 + i, 40 + i}}) {
            const ToothDimensions &x = tooth_dimensions(a), &y = tooth_dimensions(b);
            EXPECT_EQ(x.fdi, a);
            EXPECT_EQ(y.fdi, b);
            EXPECT_EQ(x.cls, y.cls);
            EXPECT_EQ(x.crown_length_mm, y.crown_length_mm);
            EXPECT_EQ(x.root_length_mm, y.root_length_mm);
            EXPECT_EQ(x.crown_md_mm, y.crown_md_mm);
            EXPECT_EQ(x.cervix_bl_mm, y.cervix_bl_mm);
            EXPECT_EQ(x.roots, y.roots);
        }
    // Spot checks against the source table.
    EXPECT_EQ(tooth_dimensions(11).crown_md_mm, 8.5);
    EXPECT_EQ(tooth_dimensions(11).cej_curve_mesial_mm, 3.5);
    EXPECT_EQ(tooth_dimensions(16).roots, 3);
    EXPECT_EQ(tooth_dimensions(14).roots, 2);
    EXPECT_EQ(tooth_dimensions(36).crown_md_mm, 11.0);
    EXPECT_EQ(tooth_dimensions(36).roots, 2);
    EXPECT_EQ(tooth_dimensions(45).roots, 1);
}

TEST(ToothTable, UniversalNumbers) {
    EXPECT_EQ(universal_number(11), 8);
    EXPECT_EQ(universal_number(21), 9);
    EXPECT_EQ(universal_number(18), 1);
    EXPECT_EQ(universal_number(28), 16);
    EXPECT_EQ(universal_number(38), 17);
    EXPECT_EQ(universal_number(36), 19);
    EXPECT_EQ(universal_number(31), 24);
    EXPECT_EQ(universal_number(41), 25);
    EXPECT_EQ(universal_number(46), 30);
    EXPECT_EQ(universal_number(48), 32);
    EXPECT_EQ(universal_number(51), 0);
    EXPECT_EQ(universal_number(0), 0);
    EXPECT_EQ(universal_number(19), 0);
    std::set<int> seen;
    for (int q = 1; q <= 4; ++q)
        for (int i = 1; i <= 8; ++i) seen.insert(universal_number(10 * q + i));
    EXPECT_EQ(seen.size(), 32u);
    EXPECT_EQ(*seen.begin(), 1);
    EXPECT_EQ(*seen.rbegin(), 32);
}

TEST(ToothTable, SiteNamesRoundTrip) {
    const char* names[] = {"MB", "B", "DB", "ML", "L", "DL"};
    for (size_t i = 0; i < kAllSites.size(); ++i) {
        EXPECT_STREQ(site_name(kAllSites[i]), names[i]);
        Site s = Site::B;
        ASSERT_TRUE(parse_site(names[i], &s));
        EXPECT_EQ(s, kAllSites[i]);
    }
    Site s = Site::MB;
    EXPECT_FALSE(parse_site("P", &s));
    EXPECT_FALSE(parse_site("mb", &s));
    EXPECT_FALSE(parse_site("", &s));
    EXPECT_EQ(s, Site::MB);
}

}  // namespace
}  // namespace sulcus
