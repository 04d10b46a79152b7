// Procedural primitives are valid solids with their analytic volumes, and the bundled paper scenes
// are exactly what the generator writes, load cleanly and start without penetration.
#include "sulcus/content/paper_scenes.h"
#include "sulcus/content/primitives.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/scene_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace sulcus {
namespace {

constexpr double kMm = 1e-3;

// Closed and consistently oriented, counted here directly: every directed edge once, its reverse once.
bool edges_pair_up(const TriMesh& m) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (const auto& t : m.triangles)
        for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        if (count != 1) return false;
        const auto rev = directed.find({edge.second, edge.first});
        if (rev == directed.end() || rev->second != 1) return false;
    }
    return true;
}

// Signed volume by the divergence theorem, computed here rather than trusted to the engine.
double volume_of(const TriMesh& m) {
    double six = 0.0;
    for (const auto& t : m.triangles)
        six += glm::dot(m.vertices[t[0]], glm::cross(m.vertices[t[1]], m.vertices[t[2]]));
    return six / 6.0;
}

void expect_valid_solid(const TriMesh& m, double analytic_volume) {
    EXPECT_EQ(validate_mesh(m), "");
    EXPECT_EQ(check_closed_outward(m), "");
    EXPECT_TRUE(edges_pair_up(m));
    EXPECT_NEAR(volume_of(m), analytic_volume, 1e-12 * analytic_volume + 1e-18);
    EXPECT_NEAR(mesh_volume(m), analytic_volume, 1e-9 * analytic_volume);
}

double shoelace(const std::vector<Vec2>& p) {
    double a = 0.0;
    for (size_t i = 0; i < p.size(); ++i) {
        const Vec2 &u = p[i], &v = p[(i + 1) % p.size()];
        a += u.x * v.y - v.x * u.y;
    }
    return 0.5 * a;
}

TEST(Primitives, BoxIsClosedOutwardWithAnalyticVolume) {
    const Vec3 half(1.0, 2.0, 3.5);
    const TriMesh m = make_box(half, Vec3(0.3, -0.2, 7.0));
    EXPECT_EQ(m.vertices.size(), 8u);
    EXPECT_EQ(m.triangles.size(), 12u);
    expect_valid_solid(m, 8.0 * half.x * half.y * half.z);
}

TEST(Primitives, CavityBoxVolumeIsOuterMinusInnerAndInnerShellFacesTheCavity) {
    const Vec3 outer(20 * kMm, 15 * kMm, 20 * kMm), inner(12 * kMm, 5.5 * kMm, 12 * kMm);
    const Vec3 centre(1 * kMm, -2 * kMm, 0.5 * kMm);
    const TriMesh m = make_box_with_cavity(outer, inner, centre);
    expect_valid_solid(m, 8.0 * (outer.x * outer.y * outer.z - inner.x * inner.y * inner.z));
    // Inner-shell triangles (all vertices inside the outer box) have normals pointing at the centre.
    int inner_triangles = 0;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const bool on_inner = std::abs(a.x) < outer.x && std::abs(b.x) < outer.x && std::abs(c.x) < outer.x;
        if (!on_inner) continue;
        ++inner_triangles;
        const Vec3 n = glm::cross(b - a, c - a);
        EXPECT_LT(glm::dot(n, (a + b + c) / 3.0 - centre), 0.0);
    }
    EXPECT_EQ(inner_triangles, 12);
}

TEST(Primitives, CavityMustFitStrictlyInside) {
    EXPECT_THROW(make_box_with_cavity(Vec3(1.0), Vec3(1.0, 0.5, 0.5)), std::invalid_argument);
    EXPECT_THROW(make_box_with_cavity(Vec3(1.0), Vec3(0.5), Vec3(0.6, 0, 0)), std::invalid_argument);
    EXPECT_THROW(make_box(Vec3(1.0, 0.0, 1.0)), std::invalid_argument);
}

TEST(Primitives, ExtrudedConcavePolygonsAreClosedWithAreaTimesHeight) {
    const std::vector<std::vector<Vec2>> polygons{
        {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 2}, {0, 2}},                                   // L
        {{-30, -20}, {30, -20}, {30, 10}, {20, 10}, {20, -10}, {0, -10}, {0, 0}, {-30, 0}},  // step
        {{0, 0}, {6, 0}, {6, 3}, {5, 1}, {4, 3}, {3, 1}, {2, 3}, {1, 1}, {0, 3}},             // comb
        {{0, 0}, {2, 0}, {4, 0}, {4, 2}, {0, 2}},                                           // straight vertex
    };
    for (const auto& poly : polygons) {
        const auto tris = triangulate_polygon(poly);
        EXPECT_EQ(tris.size(), poly.size() - 2);
        double area = 0.0;
        for (const auto& t : tris) {
            const double a2 = (poly[t[1]].x - poly[t[0]].x) * (poly[t[2]].y - poly[t[0]].y) -
                              (poly[t[2]].x - poly[t[0]].x) * (poly[t[1]].y - poly[t[0]].y);
            EXPECT_GT(a2, 0.0);
            area += 0.5 * a2;
        }
        EXPECT_NEAR(area, shoelace(poly), 1e-12);
        EXPECT_DOUBLE_EQ(polygon_signed_area(poly), shoelace(poly));
        expect_valid_solid(make_extruded_polygon(poly, -0.5, 1.5), 2.0 * shoelace(poly));
    }
}

TEST(Primitives, ExtrusionRejectsClockwiseAndSelfIntersectingPolygons) {
    const std::vector<Vec2> clockwise{{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    const std::vector<Vec2> bow_tie{{0, 0}, {1, 1}, {1, 0}, {0, 1}};
    const std::vector<Vec2> repeated{{0, 0}, {1, 0}, {1, 0}, {0, 1}};
    EXPECT_THROW(make_extruded_polygon(clockwise, 0, 1), std::invalid_argument);
    EXPECT_THROW(make_extruded_polygon(bow_tie, 0, 1), std::invalid_argument);
    EXPECT_THROW(make_extruded_polygon(repeated, 0, 1), std::invalid_argument);
    EXPECT_THROW(make_extruded_polygon({{0, 0}, {1, 0}, {0, 1}}, 1, 1), std::invalid_argument);
}

TEST(Primitives, WedgeHasSharpApexAndAnalyticVolume) {
    const double angle = 30.0 * std::numbers::pi / 180.0, height = 20 * kMm, half_length = 20 * kMm;
    const TriMesh m = make_wedge(angle, height, half_length, Vec3(0, 0, 0));
    const double half_width = height * std::tan(0.5 * angle);
    expect_valid_solid(m, half_width * height * 2.0 * half_length);
    double top = -1.0;
    for (const Vec3& v : m.vertices) top = std::max(top, v.y);
    EXPECT_EQ(top, 0.0);
}

TEST(Primitives, OutputIsDeterministic) {
    const std::vector<Vec2> poly{{0, 0}, {6, 0}, {6, 3}, {5, 1}, {4, 3}, {3, 1}, {2, 3}, {1, 1}, {0, 3}};
    const TriMesh a = make_extruded_polygon(poly, 0, 1), b = make_extruded_polygon(poly, 0, 1);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.triangles, b.triangles);
}

TEST(Primitives, OverlapTestSeparatesTouchingFromPenetrating) {
    const TriMesh plate = make_box(Vec3(20 * kMm, 0.025 * kMm, 20 * kMm));
    const TriMesh cube = make_box(Vec3(2.5 * kMm));
    const Pose id;
    auto at_y = [](double y) { return Pose{Vec3(0, y, 0), Quat(1, 0, 0, 0)}; };
    EXPECT_FALSE(tool_overlaps_object(plate, id, cube, at_y(2.525 * kMm), 1e-9));  // resting on top
    EXPECT_FALSE(tool_overlaps_object(plate, id, cube, at_y(3 * kMm), 1e-9));      // above
    EXPECT_TRUE(tool_overlaps_object(plate, id, cube, at_y(0.0), 1e-9));           // plate through the cube
    // A sharp apex poking into the cube without any cube vertex inside the wedge.
    const TriMesh ridge = make_wedge(30.0 * std::numbers::pi / 180.0, 20 * kMm, 20 * kMm);
    EXPECT_TRUE(tool_overlaps_object(ridge, id, cube, at_y(2 * kMm), 1e-9));
}

std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

TEST(PaperScenes, BundledFilesMatchTheGenerator) {
    const std::filesystem::path out = std::filesystem::path(SULCUS_BINARY_DIR) / "test_primitives_paper_scenes";
    std::filesystem::remove_all(out);
    std::string error;
    ASSERT_TRUE(write_paper_scenes(out.string(), &error)) << error;
    const std::filesystem::path bundled = std::filesystem::path(SULCUS_SOURCE_DIR) / "content/assets/scenes/paper";
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(out)) {
        ++files;
        const auto name = entry.path().filename();
        ASSERT_TRUE(std::filesystem::exists(bundled / name)) << name << " is not bundled";
        EXPECT_EQ(slurp(entry.path()), slurp(bundled / name)) << name << " differs: rerun make_paper_scenes";
    }
    EXPECT_GT(files, 0);
}

TEST(PaperScenes, EveryBundledSceneLoadsAndStartsWithoutPenetration) {
    const std::filesystem::path bundled = std::filesystem::path(SULCUS_SOURCE_DIR) / "content/assets/scenes/paper";
    for (const std::string& name : paper_scene_names()) {
        SCOPED_TRACE(name);
        const SceneLoad load = load_scene((bundled / (name + ".json")).string());
        ASSERT_TRUE(load.ok()) << load.errors.front();
        const SceneFile& s = load.scene;
        EXPECT_TRUE(s.warnings.empty());
        ASSERT_GE(s.trajectory.size(), 2u);
        for (size_t i = 1; i < s.trajectory.size(); ++i) ASSERT_GT(s.trajectory[i].t, s.trajectory[i - 1].t);
        std::vector<PlacedMesh> objects;
        for (const SceneObject& o : s.objects) objects.push_back({&o.mesh, o.pose});
        const Pose& first = s.trajectory.front().pose;
        EXPECT_LE(exact_check(s.tool.mesh, first, objects, 1.0).penetration_m, 1e-9);
        for (const SceneObject& o : s.objects) EXPECT_FALSE(tool_overlaps_object(o.mesh, o.pose, s.tool.mesh, first, 1e-9));
    }
}

TEST(PaperScenes, ZeroClearanceCavityStartsTouchingAndOneMillimetreCavityStartsFree) {
    const std::filesystem::path bundled = std::filesystem::path(SULCUS_SOURCE_DIR) / "content/assets/scenes/paper";
    for (const auto& [name, gap] : std::vector<std::pair<std::string, double>>{{"cavity_0mm", 0.0}, {"cavity_1mm", 0.5 * kMm}}) {
        const SceneLoad load = load_scene((bundled / (name + ".json")).string());
        ASSERT_TRUE(load.ok()) << name;
        std::vector<PlacedMesh> objects{{&load.scene.objects.front().mesh, load.scene.objects.front().pose}};
        const ExactCheck c = exact_check(load.scene.tool.mesh, load.scene.trajectory.front().pose, objects, 1.0);
        EXPECT_NEAR(c.distance_m, gap, 1e-12) << name;
        EXPECT_LE(c.penetration_m, 1e-12) << name;
    }
}

}  // namespace
}  // namespace sulcus
