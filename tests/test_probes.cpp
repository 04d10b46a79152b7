// Periodontal probes: marking tables, the convex collision tip and the drawn body.
#include "mesh_checks.h"

#include "sulcus/content/probes.h"

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <vector>

namespace sulcus {
namespace {

using test::winding_number;

constexpr double kMm = 1e-3;
constexpr double kUm = 1e-6;

double radial(const Vec3& p) { return std::hypot(p.x, p.z); }

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

double distance_to_surface(const TriMesh& m, const Vec3& p) {
    double best = 1e300;
    for (const auto& t : m.triangles)
        best = std::min(best, glm::length(p - closest_on_triangle(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]])));
    return best;
}

// How far p lies outside the closed mesh (0 when inside).
double outside_by(const TriMesh& m, const Vec3& p) {
    return winding_number(m, p) > 0.5 ? 0.0 : distance_to_surface(m, p);
}

// Vertices, edge midpoints and triangle centroids of a mesh.
std::vector<Vec3> surface_samples(const TriMesh& m, bool faces) {
    std::vector<Vec3> out = m.vertices;
    if (!faces) return out;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        out.push_back((a + b + c) / 3.0);
        out.push_back(0.5 * (a + b));
    }
    return out;
}

// Points where the mesh's edges cross the plane y = h.
std::vector<Vec3> section(const TriMesh& m, double h) {
    std::vector<Vec3> out;
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            const Vec3 &a = m.vertices[t[k]], &b = m.vertices[t[(k + 1) % 3]];
            if ((a.y - h) * (b.y - h) < 0) out.push_back(a + (b - a) * ((h - a.y) / (b.y - a.y)));
        }
    return out;
}

// The drawn working end's profile read from the mesh: (y, radius) of every full horizontal ring
// of at least `sides` vertices near the Y axis, and the pole.
std::vector<std::pair<double, double>> lathe_profile(const TriMesh& m, size_t sides) {
    std::map<double, std::vector<double>> rings;
    for (const Vec3& p : m.vertices)
        if (radial(p) < 2 * kMm) rings[p.y].push_back(radial(p));
    std::vector<std::pair<double, double>> out;
    for (const auto& [y, r] : rings)
        if (r.size() >= sides || (r.size() == 1 && r[0] == 0.0)) out.push_back({y, *std::max_element(r.begin(), r.end())});
    return out;
}

double profile_radius(const std::vector<std::pair<double, double>>& prof, double y) {
    for (size_t i = 0; i + 1 < prof.size(); ++i)
        if (prof[i].first <= y && y <= prof[i + 1].first) {
            const double f = (y - prof[i].first) / (prof[i + 1].first - prof[i].first);
            return prof[i].second + f * (prof[i + 1].second - prof[i].second);
        }
    return -1;  // outside the profile
}

struct ExpectedMarks {
    ProbeKind kind;
    std::vector<double> graduations_mm;
    std::vector<std::pair<double, double>> bands_mm;  // wide bands (> 0.5 mm)
    bool ball;
};

// The table of reference file §1.1 (and §1.2 for the ball).
const std::vector<ExpectedMarks>& expected() {
    static const std::vector<ExpectedMarks> e = {
        {ProbeKind::Williams, {1, 2, 3, 5, 7, 8, 9, 10}, {}, false},
        {ProbeKind::Unc15, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}, {{4, 5}, {9, 10}, {14, 15}}, false},
        {ProbeKind::Cpi, {3.5, 5.5, 8.5, 11.5}, {{3.5, 5.5}}, true},
        {ProbeKind::Marquis, {3, 6, 9, 12}, {{3, 6}, {9, 12}}, false},
        {ProbeKind::Nabers, {3, 6, 9, 12}, {{3, 6}, {9, 12}}, false},
    };
    return e;
}

class ProbeKindTest : public ::testing::TestWithParam<ProbeKind> {};

std::string kind_label(const ::testing::TestParamInfo<ProbeKind>& info) { return probe_kind_name(info.param); }

INSTANTIATE_TEST_SUITE_P(All, ProbeKindTest, ::testing::ValuesIn(kAllProbeKinds), kind_label);

TEST(ProbeKindNames, ParseRoundTripAndRejectUnknown) {
    std::set<std::string> names;
    for (ProbeKind k : kAllProbeKinds) {
        ProbeKind back = k == ProbeKind::Williams ? ProbeKind::Nabers : ProbeKind::Williams;
        ASSERT_TRUE(parse_probe_kind(probe_kind_name(k), &back)) << probe_kind_name(k);
        EXPECT_EQ(back, k);
        names.insert(probe_kind_name(k));
    }
    EXPECT_EQ(names, (std::set<std::string>{"williams", "unc15", "cpi", "marquis", "nabers"}));
    for (const char* bad : {"", "Williams", "unc-15", "UNC15", "who", "nabers ", "probe", "michigan"}) {
        ProbeKind out = ProbeKind::Marquis;
        EXPECT_FALSE(parse_probe_kind(bad, &out)) << '"' << bad << '"';
        EXPECT_EQ(out, ProbeKind::Marquis) << "rejected name must leave the output alone";
    }
}

TEST_P(ProbeKindTest, CollisionTipIsAValidClosedMeshOfBoundedSize) {
    const TriMesh m = make_probe_tip_collision(GetParam());
    EXPECT_EQ(validate_mesh(m), "");
    EXPECT_GT(mesh_volume(m), 0.0);
    EXPECT_GE(m.vertices.size(), 30u);
    EXPECT_LE(m.vertices.size(), 250u);
    // The renderer takes it as its tool (its own convexity check); report the per-tick features.
    const ModelBuild built = build_model(m, {}, RendererSettings{});
    ASSERT_EQ(built.error, "");
    std::printf("[ %s ] collision: %zu vertices, %zu triangles, %zu face planes, %zu edges, length %.2f mm\n",
                probe_kind_name(GetParam()), m.vertices.size(), m.triangles.size(), built.model->tool.face_normals.size(),
                built.model->tool.edges.size(), probe_spec(GetParam()).collision_length_m / kMm);
}

// Connected components of a mesh (through shared vertices), as sets of triangle indices.
std::vector<std::vector<size_t>> components_of(const TriMesh& m) {
    std::vector<size_t> parent(m.vertices.size());
    for (size_t i = 0; i < parent.size(); ++i) parent[i] = i;
    auto find = [&](size_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    for (const auto& t : m.triangles) {
        parent[find(t[1])] = find(t[0]);
        parent[find(t[2])] = find(t[0]);
    }
    std::map<size_t, std::vector<size_t>> by_root;
    std::vector<size_t> order;
    for (size_t i = 0; i < m.triangles.size(); ++i) {
        const size_t r = find(m.triangles[i][0]);
        if (!by_root.count(r)) order.push_back(r);
        by_root[r].push_back(i);
    }
    std::vector<std::vector<size_t>> out;
    for (size_t r : order) out.push_back(by_root[r]);
    return out;
}

// Largest distance of a vertex in front of a face plane (<= 0 for a convex, outward mesh).
double convexity_violation(const TriMesh& m) {
    double worst = -1e300;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
        for (const Vec3& v : m.vertices) worst = std::max(worst, glm::dot(n, v - a));
    }
    return worst;
}

TEST_P(ProbeKindTest, CollisionPiecesAreClosedOutwardConvexAndAreTheMeshComponents) {
    const std::vector<TriMesh> pieces = make_probe_collision_pieces(GetParam());
    const TriMesh all = make_probe_collision(GetParam());
    ASSERT_GE(pieces.size(), 4u);  // tip, shank, ferrule, grip at least
    // The first piece is the working tip, unchanged.
    const TriMesh tip = make_probe_tip_collision(GetParam());
    EXPECT_EQ(pieces[0].vertices, tip.vertices);
    EXPECT_EQ(pieces[0].triangles, tip.triangles);
    size_t vertices = 0, triangles = 0;
    for (size_t k = 0; k < pieces.size(); ++k) {
        const TriMesh& p = pieces[k];
        EXPECT_EQ(validate_mesh(p), "") << "piece " << k;
        EXPECT_GT(mesh_volume(p), 0.0) << "piece " << k;
        EXPECT_LE(convexity_violation(p), 1e-12) << "piece " << k << " is not convex";
        EXPECT_EQ(components_of(p).size(), 1u) << "piece " << k;
        vertices += p.vertices.size();
        triangles += p.triangles.size();
    }
    // The scene's tool: the pieces, in order, as the connected components of one valid mesh.
    EXPECT_EQ(validate_mesh(all), "");
    EXPECT_EQ(all.vertices.size(), vertices);
    const auto comps = components_of(all);
    ASSERT_EQ(comps.size(), pieces.size());
    size_t first = 0;
    for (size_t k = 0; k < comps.size(); ++k) {
        EXPECT_EQ(comps[k].size(), pieces[k].triangles.size()) << k;
        EXPECT_EQ(comps[k].front(), first) << k;
        first += pieces[k].triangles.size();
    }
    // The tool reaches from the tip end to the end of the handle.
    double reach = 0;
    for (const Vec3& v : all.vertices) reach = std::max(reach, glm::length(v));
    EXPECT_GT(reach, 120 * kMm);
    std::string per_piece;
    for (const TriMesh& p : pieces) per_piece += " " + std::to_string(p.vertices.size());
    std::printf("[ %s ] collision: %zu pieces, %zu vertices, %zu triangles; vertices per piece:%s\n",
                probe_kind_name(GetParam()), pieces.size(), vertices, triangles, per_piece.c_str());
}

// Distance from p to the union of closed convex pieces (0 inside one).
double distance_to_union(const std::vector<TriMesh>& pieces, const Vec3& p) {
    double best = 1e300;
    for (const TriMesh& m : pieces) {
        bool inside = true;
        for (const auto& t : m.triangles) {
            const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
            if (glm::dot(glm::cross(b - a, c - a), p - a) > 0) {
                inside = false;
                break;
            }
        }
        if (inside) return 0.0;
        best = std::min(best, distance_to_surface(m, p));
    }
    return best;
}

TEST_P(ProbeKindTest, CollisionPiecesFollowTheDrawnBodyAndHandle) {
    const ProbeSpec& spec = probe_spec(GetParam());
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    // The drawn steel body (tip, working end, shank) and handle; the marks are a few um proud.
    TriMesh drawn = node.parts[0].mesh;
    {
        const TriMesh& h = node.parts[1].mesh;
        const auto base = uint32_t(drawn.vertices.size());
        drawn.vertices.insert(drawn.vertices.end(), h.vertices.begin(), h.vertices.end());
        for (const auto& t : h.triangles) drawn.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    const std::vector<TriMesh> pieces = make_probe_collision_pieces(GetParam());
    // Every drawn vertex is covered by the collision within 0.05 mm...
    double worst_drawn = 0;
    Vec3 worst_at(0);
    for (const Vec3& v : drawn.vertices) {
        const double d = distance_to_union(pieces, v);
        if (d > worst_drawn) worst_drawn = d, worst_at = v;
    }
    EXPECT_LE(worst_drawn, 0.05 * kMm) << "drawn vertex at (" << worst_at.x / kMm << ", " << worst_at.y / kMm << ", "
                                       << worst_at.z / kMm << ") mm is not covered";
    // ...and no piece stands out of the drawn body by more than 0.05 mm (vertices, edge midpoints,
    // face centroids). The Nabers tip is the documented exception: its hull spans the arc's chord.
    double worst_piece = 0;
    for (size_t k = 0; k < pieces.size(); ++k) {
        const bool nabers_tip = k == 0 && spec.curve_radius_m > 0;
        for (const Vec3& p : surface_samples(pieces[k], !nabers_tip)) {
            const double w = winding_number(drawn, p);
            const double d = w > 0.5 ? 0.0 : distance_to_surface(drawn, p);
            worst_piece = std::max(worst_piece, d);
            EXPECT_LE(d, 0.05 * kMm) << "piece " << k << " at y = " << p.y / kMm << " mm";
        }
    }
    std::printf("[ %s ] drawn body uncovered by at most %.1f um; collision outside the drawing by at most %.1f um\n",
                probe_kind_name(GetParam()), worst_drawn / kUm, worst_piece / kUm);
}

TEST_P(ProbeKindTest, CollisionTipIsConvex) {
    const TriMesh m = make_probe_tip_collision(GetParam());
    double worst = -1e300;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
        for (const Vec3& v : m.vertices) worst = std::max(worst, glm::dot(n, v - a));
    }
    EXPECT_LE(worst, 1e-12) << "a vertex lies in front of a face plane";
}

TEST_P(ProbeKindTest, CollisionTipEndIsTheLowestPointAtTheOrigin) {
    const TriMesh m = make_probe_tip_collision(GetParam());
    const auto lowest =
        std::min_element(m.vertices.begin(), m.vertices.end(), [](const Vec3& a, const Vec3& b) { return a.y < b.y; });
    EXPECT_EQ(lowest->y, 0.0);
    EXPECT_EQ(lowest->x, 0.0);
    EXPECT_EQ(lowest->z, 0.0);
    int at_floor = 0;
    for (const Vec3& v : m.vertices) at_floor += v.y < 1 * kUm;
    EXPECT_EQ(at_floor, 1) << "a single pole vertex meets a floor square to the probe";
}

TEST_P(ProbeKindTest, CollisionTipRadiusMatchesTheTip) {
    const ProbeSpec& spec = probe_spec(GetParam());
    const TriMesh m = make_probe_tip_collision(GetParam());
    const double R = 0.5 * spec.tip_diameter_m;
    // Cross-section at the height of the tip sphere's centre.
    const std::vector<Vec3> sec = section(m, R);
    ASSERT_GE(sec.size(), 24u);
    double lo = 1e300, hi = -1e300, hi_concave = -1e300;
    for (const Vec3& p : sec) {
        // The curved probe's hull leans out on the concave (+X) side toward its far end.
        if (spec.curve_radius_m > 0 && p.x > 0.1 * kMm) {
            hi_concave = std::max(hi_concave, radial(p));
            continue;
        }
        lo = std::min(lo, radial(p));
        hi = std::max(hi, radial(p));
    }
    EXPECT_NEAR(hi, R, 2 * kUm);
    EXPECT_NEAR(lo, R, 2.5 * kUm);
    if (spec.curve_radius_m > 0) {
        EXPECT_NEAR(hi_concave, R, 5 * kUm);
        std::printf("[ %s ] concave side at y=R: %.4f mm\n", probe_kind_name(GetParam()), hi_concave / kMm);
    }
    // Where the tip meets a flat floor (normal within 30 degrees of the axis), the support height
    // above the floor matches the sphere's: the polyhedral cap is inscribed, at most 10 um short
    // (12 sides and 3 cap rings: the tip's vertex count is a per-tick cost of the servo step).
    const Vec3 centre(0, R, 0);
    double worst = 0;
    for (int i = 0; i <= 30; i += 2)
        for (int j = 0; j < 36; ++j) {
            const double a = i * std::numbers::pi / 180, b = j * std::numbers::pi / 18;
            const Vec3 d(std::sin(a) * std::cos(b), -std::cos(a), std::sin(a) * std::sin(b));
            double h = -1e300;
            for (const Vec3& v : m.vertices) h = std::max(h, glm::dot(d, v - centre));
            EXPECT_LE(h, R + 1e-12);
            worst = std::max(worst, R - h);
        }
    EXPECT_LE(worst, 10 * kUm);
    std::printf("[ %s ] tip radius at y=R: %.4f..%.4f mm; floor support error <= %.2f um\n", probe_kind_name(GetParam()),
                lo / kMm, hi / kMm, worst / kUm);
}

TEST_P(ProbeKindTest, MarkingsMatchTheReferenceTable) {
    const ProbeSpec& spec = probe_spec(GetParam());
    const ExpectedMarks* e = nullptr;
    for (const ExpectedMarks& x : expected())
        if (x.kind == GetParam()) e = &x;
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(spec.kind, GetParam());
    EXPECT_EQ(spec.ball_tip, e->ball);
    EXPECT_DOUBLE_EQ(spec.tip_diameter_m, 0.5 * kMm);
    ASSERT_EQ(spec.graduations_m.size(), e->graduations_mm.size());
    for (size_t i = 0; i < spec.graduations_m.size(); ++i)
        EXPECT_NEAR(spec.graduations_m[i] / kMm, e->graduations_mm[i], 1e-12) << i;

    // Every drawn mark is a thin ring centred on a graduation or a band between two of them; every
    // graduation is drawn (a ring centre or a band edge); the wide bands are the table's.
    auto is_grad = [&](double m) {
        return std::any_of(spec.graduations_m.begin(), spec.graduations_m.end(),
                           [&](double g) { return std::abs(g - m) < 1e-12; });
    };
    std::vector<std::pair<double, double>> bands;
    std::set<double> drawn;
    for (const ProbeMark& mk : spec.marks) {
        ASSERT_LT(mk.from_m, mk.to_m);
        EXPECT_EQ(mk.material, kProbeMarkBlack);
        EXPECT_LE(mk.to_m, spec.working_length_m);
        if (mk.to_m - mk.from_m > 0.5 * kMm) {
            EXPECT_TRUE(is_grad(mk.from_m) && is_grad(mk.to_m)) << mk.from_m / kMm;
            bands.push_back({mk.from_m / kMm, mk.to_m / kMm});
            drawn.insert(std::round(mk.from_m / kMm * 1e6));
            drawn.insert(std::round(mk.to_m / kMm * 1e6));
        } else {
            const double c = 0.5 * (mk.from_m + mk.to_m);
            EXPECT_TRUE(is_grad(c)) << c / kMm;
            drawn.insert(std::round(c / kMm * 1e6));
        }
    }
    for (double g : spec.graduations_m) EXPECT_TRUE(drawn.count(std::round(g / kMm * 1e6))) << g / kMm << " mm not drawn";
    ASSERT_EQ(bands.size(), e->bands_mm.size());
    for (size_t i = 0; i < bands.size(); ++i) {
        EXPECT_NEAR(bands[i].first, e->bands_mm[i].first, 1e-12);
        EXPECT_NEAR(bands[i].second, e->bands_mm[i].second, 1e-12);
    }
    // Marks do not overlap.
    for (size_t i = 0; i + 1 < spec.marks.size(); ++i) EXPECT_LT(spec.marks[i].to_m, spec.marks[i + 1].from_m);
    // The collision tip covers the first graduation the probe is read at (Nabers: 3 mm, Hamp's
    // class threshold) and, on straight probes, every mark.
    EXPECT_GE(spec.collision_length_m + 1e-12, spec.graduations_m.front());
    if (spec.curve_radius_m == 0) {
        EXPECT_GE(spec.collision_length_m, spec.marks.back().to_m);
    }
}

TEST(ProbeMarkings, WilliamsSkipsFourAndSixMillimetres) {
    for (double g : probe_spec(ProbeKind::Williams).graduations_m) {
        EXPECT_GT(std::abs(g - 4 * kMm), 0.5 * kMm);
        EXPECT_GT(std::abs(g - 6 * kMm), 0.5 * kMm);
    }
}

TEST_P(ProbeKindTest, VisualPartsAreClosedOutwardAndFinite) {
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    EXPECT_EQ(node.name, std::string("probe ") + probe_kind_name(GetParam()));
    ASSERT_GE(node.parts.size(), 3u);  // body, handle, marks
    for (size_t i = 0; i < node.parts.size(); ++i) {
        const TriMesh& m = node.parts[i].mesh;
        ASSERT_FALSE(m.triangles.empty()) << i;
        for (const Vec3& v : m.vertices) ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
        double min_area = 1e300;
        for (const auto& t : m.triangles)
            min_area = std::min(min_area, 0.5 * glm::length(glm::cross(m.vertices[t[1]] - m.vertices[t[0]],
                                                                        m.vertices[t[2]] - m.vertices[t[0]])));
        EXPECT_GT(min_area, 1e-15) << "part " << i << ": degenerate triangle";
        EXPECT_EQ(validate_mesh(m), "") << "part " << i;
        EXPECT_GT(mesh_volume(m), 0.0) << "part " << i;
        ASSERT_GE(node.parts[i].material, 0);
        ASSERT_LT(size_t(node.parts[i].material), asset.materials.size());
    }
    EXPECT_EQ(asset.materials[size_t(node.parts[0].material)].name, "probe steel");
    EXPECT_EQ(asset.materials[size_t(node.parts.back().material)].name, "probe mark black");
    // The tip end is the lowest point of the drawn body too.
    double min_y = 1e300;
    for (const Vec3& v : node.parts[0].mesh.vertices) min_y = std::min(min_y, v.y);
    EXPECT_EQ(min_y, 0.0);
    // A second probe in the same asset reuses the materials.
    const size_t materials = asset.materials.size();
    make_probe_node(ProbeKind::Williams, asset);
    EXPECT_EQ(asset.materials.size(), materials);
}

TEST_P(ProbeKindTest, DrawnHandleHasTheStatedSize) {
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    const TriMesh& h = node.parts[1].mesh;
    // Length along the handle axis and largest cross-section, from the mesh alone.
    double longest = 0;
    for (const Vec3& a : h.vertices)
        for (const Vec3& b : h.vertices) longest = std::max(longest, glm::length(a - b));
    EXPECT_GT(longest, 100 * kMm);
    EXPECT_LT(longest, 125 * kMm);
}

TEST_P(ProbeKindTest, CollisionTipLiesInsideTheDrawnWorkingEnd) {
    const ProbeSpec& spec = probe_spec(GetParam());
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    const TriMesh& body = node.parts[0].mesh;
    const TriMesh tip = make_probe_tip_collision(GetParam());
    if (spec.curve_radius_m == 0) {
        // Lathe check: every collision vertex within the drawn ring radius at its height.
        const auto prof = lathe_profile(body, 48);
        ASSERT_GE(prof.size(), 5u);
        for (const Vec3& v : tip.vertices) {
            const double r = profile_radius(prof, v.y);
            ASSERT_GE(r, 0) << "collision vertex beyond the straight working end at y = " << v.y / kMm << " mm";
            EXPECT_LE(radial(v), r + 0.02 * kMm) << "y = " << v.y / kMm << " mm";
        }
    }
    // Mesh check: vertices (all kinds) and face samples (straight) inside the closed body.
    double worst_vertex = 0, worst_face = 0;
    for (const Vec3& p : tip.vertices) worst_vertex = std::max(worst_vertex, outside_by(body, p));
    for (const Vec3& p : surface_samples(tip, true)) worst_face = std::max(worst_face, outside_by(body, p));
    EXPECT_LE(worst_vertex, 0.02 * kMm);
    if (spec.curve_radius_m == 0) {
        EXPECT_LE(worst_face, 0.02 * kMm);
    } else {
        // The hull's chords across the concave side of the arc (documented in docs/probes.md).
        const double theta = spec.collision_length_m / spec.curve_radius_m;
        EXPECT_LE(worst_face, spec.curve_radius_m * (1 - std::cos(0.5 * theta)));
    }
    std::printf("[ %s ] collision outside the drawn body by at most: vertices %.2f um, faces %.2f um\n",
                probe_kind_name(GetParam()), worst_vertex / kUm, worst_face / kUm);
}

TEST_P(ProbeKindTest, DrawnMarksSitAtTheTablePositionsProudOfTheBody) {
    const ProbeSpec& spec = probe_spec(GetParam());
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    const TriMesh& body = node.parts[0].mesh;
    const TriMesh& marks = node.parts.back().mesh;
    // Distance along the centreline of each mark vertex, by projection on a fine polyline.
    std::vector<Vec3> line;
    for (int i = 0; i <= 2000; ++i) line.push_back(probe_centreline(spec, spec.working_length_m * i / 2000.0));
    std::vector<double> lo(spec.marks.size(), 1e300), hi(spec.marks.size(), -1e300);
    int outer = 0;
    for (const Vec3& v : marks.vertices) {
        size_t best = 0;
        for (size_t i = 1; i < line.size(); ++i)
            if (glm::length(v - line[i]) < glm::length(v - line[best])) best = i;
        const double u = spec.working_length_m * double(best) / 2000.0;
        const double tol = spec.working_length_m / 2000.0;
        bool found = false;
        for (size_t k = 0; k < spec.marks.size(); ++k)
            if (u >= spec.marks[k].from_m - tol && u <= spec.marks[k].to_m + tol) {
                lo[k] = std::min(lo[k], u);
                hi[k] = std::max(hi[k], u);
                found = true;
            }
        ASSERT_TRUE(found) << "mark vertex at " << u / kMm << " mm belongs to no mark";
        // Outer-wall vertices stand proud of the drawn body.
        if (glm::length(v - line[best]) > probe_body_radius(spec, u)) {
            ++outer;
            const double d = distance_to_surface(body, v);
            EXPECT_GE(d, 0.6 * kProbeMarkProud_m);
            EXPECT_LE(d, 1.5 * kProbeMarkProud_m);
            EXPECT_LT(winding_number(body, v), 0.5);
        }
    }
    EXPECT_EQ(size_t(outer), marks.vertices.size() / 2) << "half the vertices are on the outer walls";
    for (size_t k = 0; k < spec.marks.size(); ++k) {
        EXPECT_NEAR(lo[k], spec.marks[k].from_m, spec.working_length_m / 2000.0 + 1e-9) << k;
        EXPECT_NEAR(hi[k], spec.marks[k].to_m, spec.working_length_m / 2000.0 + 1e-9) << k;
    }
}

TEST_P(ProbeKindTest, NodeExtrasDescribeTheProbe) {
    const ProbeSpec& spec = probe_spec(GetParam());
    Asset asset;
    const AssetNode node = make_probe_node(GetParam(), asset);
    EXPECT_EQ(node.extras.at("probe"), probe_kind_name(GetParam()));
    EXPECT_EQ(node.extras.at("tip_diameter_m").get<double>(), spec.tip_diameter_m);
    std::vector<double> marks_mm = node.extras.at("marks_mm").get<std::vector<double>>();
    ASSERT_EQ(marks_mm.size(), spec.graduations_m.size());
    for (size_t i = 0; i < marks_mm.size(); ++i) EXPECT_NEAR(marks_mm[i] * kMm, spec.graduations_m[i], 1e-15);
    EXPECT_EQ(node.extras.at("bands_mm").size(), spec.marks.size());
    // The collision mesh (every piece) travels with the node, exactly.
    const TriMesh tip = make_probe_collision(GetParam());
    const auto& c = node.extras.at("collision");
    EXPECT_EQ(c.at("pieces").get<size_t>(), make_probe_collision_pieces(GetParam()).size());
    ASSERT_EQ(c.at("vertices_m").size(), tip.vertices.size());
    ASSERT_EQ(c.at("triangles").size(), tip.triangles.size());
    for (size_t i = 0; i < tip.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) EXPECT_EQ(c.at("vertices_m")[i][k].get<double>(), tip.vertices[i][k]);
}

TEST(ProbeShape, CpiBallIsWiderThanTheNeckBehindIt) {
    const ProbeSpec& spec = probe_spec(ProbeKind::Cpi);
    Asset asset;
    const auto prof = lathe_profile(make_probe_node(ProbeKind::Cpi, asset).parts[0].mesh, 48);
    double ball = 0, neck = 1e300;
    for (const auto& [y, r] : prof) {
        if (y <= spec.tip_diameter_m) ball = std::max(ball, r);
        if (y > 0.5 * spec.tip_diameter_m && y < 1 * kMm) neck = std::min(neck, r);
    }
    EXPECT_NEAR(ball, 0.5 * spec.tip_diameter_m, 0.5 * kUm);  // rings near, not at, the equator
    EXPECT_LT(neck, ball - 0.01 * kMm);
}

TEST(ProbeShape, NabersWorkingEndIsAnArcThatTheMarksFollow) {
    const ProbeSpec& spec = probe_spec(ProbeKind::Nabers);
    ASSERT_GT(spec.curve_radius_m, 0);
    // Three points on the centreline past the straight tip lie on a circle of the stated radius.
    const Vec3 a = probe_centreline(spec, 1 * kMm), b = probe_centreline(spec, 7 * kMm), c = probe_centreline(spec, 13 * kMm);
    const double ab = glm::length(b - a), bc = glm::length(c - b), ca = glm::length(a - c);
    const double circum = ab * bc * ca / (2 * glm::length(glm::cross(b - a, c - a)));
    EXPECT_NEAR(circum, spec.curve_radius_m, 1e-9);
    EXPECT_GT(c.x, 1 * kMm) << "curves toward +X in the XY plane";
    EXPECT_EQ(c.z, 0.0);
    // Marks follow the curve: the far band's end ring is centred on the curve.
    Asset asset;
    const AssetNode node = make_probe_node(ProbeKind::Nabers, asset);
    const TriMesh& marks = node.parts.back().mesh;
    const Vec3 end = probe_centreline(spec, 12 * kMm);
    int near_end = 0;
    for (const Vec3& v : marks.vertices)
        near_end += std::abs(glm::length(v - end) - probe_body_radius(spec, 12 * kMm) - kProbeMarkProud_m) < 1e-9;
    EXPECT_EQ(near_end, 48);
}

}  // namespace
}  // namespace sulcus
