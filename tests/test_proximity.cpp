// tool_distance and tool_collides give the same answers as brute force over every triangle of
// every object (no BVH) at seeded random poses of a probe-like tool near a dense bumpy sphere,
// cap the distance at max_distance_m, and measure a known gap exactly.
#include "sulcus/engine/proximity.h"

#include "geometry.h"
#include "scene_helpers.h"
#include "tool_placement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace sulcus {
namespace {

using test::mm;

// An icosahedron subdivided `levels` times (20 * 4^levels triangles), its vertices pushed out to
// a bumpy radius so the surface has concave and convex parts.
TriMesh bumpy_sphere(int levels, double radius_m, const Vec3& centre) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    TriMesh m;
    m.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                  {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (Vec3& v : m.vertices) v = glm::normalize(v);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            m.vertices.push_back(glm::normalize(m.vertices[a] + m.vertices[b]));
            const uint32_t i = uint32_t(m.vertices.size() - 1);
            mid.emplace(key, i);
            return i;
        };
        std::vector<std::array<uint32_t, 3>> next;
        for (const auto& tri : m.triangles) {
            const uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
            next.push_back({tri[0], ab, ca});
            next.push_back({tri[1], bc, ab});
            next.push_back({tri[2], ca, bc});
            next.push_back({ab, bc, ca});
        }
        m.triangles = std::move(next);
    }
    for (Vec3& v : m.vertices) {
        const double bump = 1.0 + 0.06 * std::sin(7.0 * v.x) * std::sin(5.0 * v.y + 1.0) * std::sin(6.0 * v.z + 2.0);
        v = centre + radius_m * bump * v;
    }
    return m;
}

// A probe-like tool in its own frame: a 16-sided rod (the tip, from the origin along +z) and a
// stubby box above it (compact: no bounding capsules), as one mesh of two convex pieces.
TriMesh probe_like_tool() {
    std::vector<Vec2> polygon;
    for (int i = 0; i < 16; ++i) {
        const double a = 2.0 * M_PI * i / 16.0;
        polygon.emplace_back(0.25 * mm * std::cos(a), 0.25 * mm * std::sin(a));
    }
    TriMesh tool = make_extruded_polygon(polygon, 0.0, 12 * mm);
    const TriMesh box = make_box(Vec3(1.5 * mm, 1.5 * mm, 2 * mm), Vec3(0, 0, 14 * mm));
    const uint32_t base = uint32_t(tool.vertices.size());
    tool.vertices.insert(tool.vertices.end(), box.vertices.begin(), box.vertices.end());
    for (const auto& t : box.triangles) tool.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return tool;
}

struct Brute {
    double distance = 1e300;
    bool collides = false;
};

double box_gap(const Aabb& a, const Aabb& b) {
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double g = std::max({0.0, a.lo[i] - b.hi[i], b.lo[i] - a.hi[i]});
        d2 += g * g;
    }
    return std::sqrt(d2);
}

// Every triangle of every object against every piece, no BVH. The only shortcut is the gap
// between the piece's and the triangle's boxes (a lower bound on their distance): a triangle
// whose boxes are apart cannot overlap the piece, nor be nearer than a gap no less than the least
// distance so far. The distance over a triangle is exact whatever the cutoff once it is below it,
// so passing the least distance so far keeps the minimum exact; `full` turns both shortcuts off.
Brute brute_force(const Model& model, const Pose& pose, bool full) {
    const ModelTool& tool = model.tool;
    std::vector<Vec3> vertices(tool.mesh.vertices.size()), normals(tool.face_normals.size());
    std::vector<double> offsets(tool.face_normals.size());
    std::vector<Vec3> capsule(tool.pieces.size() * (kToolCapsules + 1));
    const Quat q = pose.orientation;
    place_tool_vertices(tool, q, pose.position, vertices.data());
    place_tool_planes(tool, q, pose.position, normals.data(), offsets.data());
    place_tool_capsule(tool, q, pose.position, capsule.data());
    std::vector<Aabb> piece_box(tool.pieces.size());
    for (size_t k = 0; k < tool.pieces.size(); ++k)
        for (uint32_t v = 0; v < tool.pieces[k].vertex_count; ++v) piece_box[k].grow(vertices[tool.pieces[k].vertex_begin + v]);
    Brute b;
    for (const ModelObject& obj : model.objects) {
        for (const auto& t : obj.mesh.triangles) {
            const Vec3 &v0 = obj.mesh.vertices[t[0]], &v1 = obj.mesh.vertices[t[1]], &v2 = obj.mesh.vertices[t[2]];
            Aabb tb;
            tb.grow(v0);
            tb.grow(v1);
            tb.grow(v2);
            for (size_t k = 0; k < tool.pieces.size(); ++k) {
                const double gap = box_gap(piece_box[k], tb);
                if (!full && gap > 0.0 && gap >= b.distance) continue;
                const ConvexView view =
                    tool_convex_view(tool, k, vertices.data(), normals.data(), offsets.data(), &q, capsule.data());
                const double d = distance_convex_triangle_by_faces(view, piece_triangles(tool, k),
                                                                   int(tool.pieces[k].triangle_count), v0, v1, v2);
                b.distance = std::min(b.distance, d);
                if ((full || gap == 0.0) && separate_convex_triangle(view, v0, v1, v2).separation <= 0.0)
                    b.collides = true;
            }
        }
    }
    return b;
}

Quat random_rotation(std::mt19937_64& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    return glm::normalize(Quat(n(rng), n(rng), n(rng), n(rng)));
}

struct Scene {
    std::unique_ptr<Model> model;
    std::vector<Pose> poses;
};

// The bumpy sphere (20480 triangles, radius 10 mm) and a box beside it; poses put the tool's
// tip from 1 mm inside to 3 mm outside the sphere's mean surface, pointing anywhere.
Scene near_surface_scene(int pose_count) {
    Scene s;
    const TriMesh sphere = bumpy_sphere(5, 10 * mm, Vec3(0.0));
    EXPECT_EQ(sphere.triangles.size(), 20480u);
    const TriMesh block = make_box(Vec3(3 * mm, 3 * mm, 3 * mm), Vec3(0.0));
    std::mt19937_64 rng(20240607);
    const Pose block_pose = test::pose(Vec3(0, 0, 14 * mm), random_rotation(rng));
    s.model = test::model_of(probe_like_tool(), {test::object("sphere", sphere), test::object("block", block, block_pose)});
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> off(-1 * mm, 3 * mm);
    for (int i = 0; i < pose_count; ++i) {
        const Vec3 u = glm::normalize(Vec3(n(rng), n(rng), n(rng)));
        s.poses.push_back(test::pose((10 * mm + off(rng)) * u, random_rotation(rng)));
    }
    return s;
}

TEST(Proximity, DistanceAndCollisionMatchBruteForceOverEveryTriangle) {
    const Scene s = near_surface_scene(300);
    ASSERT_TRUE(s.model);
    ASSERT_EQ(s.model->tool.pieces.size(), 2u);
    ASSERT_GT(s.model->tool.pieces[0].capsule_count, 0);  // the rod uses its capsules
    size_t total = 0;
    for (const ModelObject& o : s.model->objects) total += o.mesh.triangles.size();
    int apart = 0, touching = 0, colliding = 0;
    long tested = 0;
    for (size_t i = 0; i < s.poses.size(); ++i) {
        const Pose& p = s.poses[i];
        const Brute b = brute_force(*s.model, p, i % 30 == 0);
        ProximityStats st;
        const double d = tool_distance(*s.model, p, 1.0, &st);
        tested += st.triangles_tested;
        EXPECT_NEAR(d, b.distance, 1e-12 * b.distance) << "pose " << i;
        ProximityStats cst;
        const bool c = tool_collides(*s.model, p, &cst);
        EXPECT_EQ(c, b.collides) << "pose " << i;
        // Overlap and zero distance are the same event.
        EXPECT_EQ(c, d == 0.0) << "pose " << i;
        apart += d > 0.0;
        touching += d == 0.0;
        colliding += c;
    }
    // The poses cover both sides, and the BVH spares almost every triangle.
    EXPECT_GT(apart, 50);
    EXPECT_GT(touching, 50);
    EXPECT_GT(colliding, 50);
    EXPECT_LT(double(tested) / double(s.poses.size()), 0.02 * double(total));
}

// Poses where a single triangle or two decide: each apart pose is advanced toward the sphere's
// centre until the tool just touches (conservative advancement), then set 1 um short of that
// and 1 um past it.
TEST(Proximity, GrazingContactsMatchBruteForce) {
    const Scene s = near_surface_scene(150);
    ASSERT_TRUE(s.model);
    int grazing = 0;
    for (size_t i = 0; i < s.poses.size(); ++i) {
        Pose p = s.poses[i];
        if (tool_distance(*s.model, p, 1.0) == 0.0) continue;
        const Vec3 in = -glm::normalize(p.position);
        double d = 1.0;
        for (int it = 0; it < 200 && d > 1e-9; ++it) {
            d = tool_distance(*s.model, p, 1.0);
            p.position += d * in;
        }
        if (d > 1e-9) continue;
        for (double step : {-1e-6, 1e-6}) {
            const Pose q = test::pose(p.position + step * in, p.orientation);
            const Brute b = brute_force(*s.model, q, false);
            // To rounding: a femtometre, on coordinates of centimetres.
            EXPECT_NEAR(tool_distance(*s.model, q, 1.0), b.distance, 1e-15) << "pose " << i;
            EXPECT_EQ(tool_collides(*s.model, q), b.collides) << "pose " << i;
            if (step > 0.0) grazing += b.collides;
        }
    }
    EXPECT_GT(grazing, 20);
}

TEST(Proximity, DistanceIsCappedAtMaxDistance) {
    const Scene s = near_surface_scene(120);
    ASSERT_TRUE(s.model);
    const double cap = 0.5 * mm;
    int capped = 0, below = 0;
    for (size_t i = 0; i < s.poses.size(); ++i) {
        const double exact = tool_distance(*s.model, s.poses[i], 1.0);
        ProximityStats capped_stats, exact_stats;
        const double d = tool_distance(*s.model, s.poses[i], cap, &capped_stats);
        if (exact >= cap) {
            EXPECT_EQ(d, cap) << "pose " << i;
            ++capped;
        } else {
            EXPECT_EQ(d, exact) << "pose " << i;
            ++below;
        }
        // A smaller cap only prunes more.
        tool_distance(*s.model, s.poses[i], 1.0, &exact_stats);
        EXPECT_LE(capped_stats.triangles_tested, exact_stats.triangles_tested) << "pose " << i;
    }
    EXPECT_GT(capped, 10);
    EXPECT_GT(below, 10);
}

TEST(Proximity, BoxOneMillimetreAboveAPlane) {
    // A 2 mm cube over a slab whose top face is y = 0.
    const TriMesh slab = make_box(Vec3(50 * mm, 5 * mm, 50 * mm), Vec3(0, -5 * mm, 0));
    const auto model = test::model_of(make_box(Vec3(1 * mm)), {test::object("slab", slab)});
    ASSERT_TRUE(model);
    const Pose above = test::pose(Vec3(3 * mm, 2 * mm, -7 * mm));
    EXPECT_NEAR(tool_distance(*model, above, 1.0), 1e-3, 1e-12);
    EXPECT_FALSE(tool_collides(*model, above));
    // Below the cap the cap is returned.
    EXPECT_EQ(tool_distance(*model, above, 0.5 * mm), 0.5 * mm);
    // Turned 45 degrees about x: the lowest edge is sqrt(2) mm below the centre.
    const Pose edge_down = test::pose(Vec3(0, 2 * mm, 0), test::axis_angle(Vec3(1, 0, 0), M_PI / 4));
    EXPECT_NEAR(tool_distance(*model, edge_down, 1.0), 2e-3 - std::sqrt(2.0) * 1e-3, 1e-12);
    // Sunk 0.1 mm into the slab: overlapping.
    const Pose sunk = test::pose(Vec3(0, 0.9 * mm, 0));
    EXPECT_EQ(tool_distance(*model, sunk, 1.0), 0.0);
    EXPECT_TRUE(tool_collides(*model, sunk));
}

TEST(Proximity, NoObjectsMeansNothingNear) {
    const auto model = test::model_of(make_box(Vec3(1 * mm)), {});
    ASSERT_TRUE(model);
    EXPECT_EQ(tool_distance(*model, Pose{}, 0.25), 0.25);
    EXPECT_FALSE(tool_collides(*model, Pose{}));
}

// closest_at_an_end, taken in a frame moved and turned from the world's as the renderer's tool
// frame is, never says "at an end" where closest_segment_params in the world finds the closest
// points inside both segments: on pairs built with their lines' closest points just inside or
// just outside an end (by 1e-12 to 1e-5 of the length), at angles down to near parallel,
// 10 um to 1 mm long, up to 0.1 m from the origin. And it does settle the pairs clearly outside.
TEST(SegmentClosest, AnEndSeenInAnotherFrameIsAnEndInTheWorld) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
    auto random_unit = [&] {
        for (;;) {
            const Vec3 v(u(rng), u(rng), u(rng));
            if (glm::length(v) > 0.1 && glm::length(v) < 1.0) return glm::normalize(v);
        }
    };
    const double offsets[] = {-1e-5, -1e-7, -1e-9, -1e-12, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 0.3};
    const double sines[] = {1.0, 0.3, 0.1, 0.03, 0.011, 0.0101, 0.009, 1e-3};
    int inside = 0, settled_outside = 0, clearly_outside = 0;
    for (int trial = 0; trial < 40000; ++trial) {
        const double len1 = std::pow(10.0, -5.0 + 2.0 * unit(rng)), len2 = std::pow(10.0, -5.0 + 2.0 * unit(rng));
        const Vec3 origin = 0.1 * Vec3(u(rng), u(rng), u(rng));
        const Vec3 d1 = len1 * random_unit();
        // The common perpendicular: from s0 along segment 1 to t0 along segment 2, `gap` long.
        const double delta = offsets[rng() % std::size(offsets)];
        const bool past_end = rng() % 2 == 0;
        const double s0 = past_end ? 1.0 + delta : -delta;  // delta < 0: inside
        const double t0 = 0.05 + 0.9 * unit(rng);
        Vec3 n = glm::cross(d1, random_unit());
        n = glm::normalize(n);
        const double sine = sines[rng() % std::size(sines)];
        const Vec3 across = glm::normalize(glm::cross(n, d1));
        const Vec3 d2 = len2 * (std::sqrt(1.0 - sine * sine) * glm::normalize(d1) + sine * across);
        const double gap = 1e-4 * unit(rng);
        const Vec3 p0 = origin;
        const Vec3 q0 = p0 + s0 * d1 + gap * n - t0 * d2;
        // The world's answer.
        double s, t;
        closest_segment_params(d1, d2, p0 - q0, glm::dot(d1, d1), glm::dot(d2, d2), s, t);
        const bool interior = s > 1e-9 && s < 1.0 - 1e-9 && t > 1e-9 && t < 1.0 - 1e-9;
        // The same segments in a frame turned by q and moved to p.
        const Quat q = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 p = origin + 1e-3 * Vec3(u(rng), u(rng), u(rng));
        const glm::dmat3 to_local = glm::mat3_cast(glm::conjugate(q));
        const Vec3 p0l = to_local * (p0 - p), p1l = to_local * (p0 + d1 - p);
        const Vec3 q0l = to_local * (q0 - p), q1l = to_local * (q0 + d2 - p);
        const Vec3 d1l = p1l - p0l, d2l = q1l - q0l;
        const bool at_end = closest_at_an_end(d1l, d2l, p0l - q0l, glm::dot(d1l, d1l), glm::dot(d2l, d2l));
        if (interior) {
            ++inside;
            ASSERT_FALSE(at_end) << "trial " << trial << ": s " << s << " t " << t << " sine " << sine;
        }
        if (delta > 2e-8 / (sine * sine) && sine * sine > 1.01e-4) {
            ++clearly_outside;
            settled_outside += at_end;
        }
    }
    EXPECT_GT(inside, 5000);
    // Clearly outside (by twice the margin, at a squared sine over 1e-4): settled.
    EXPECT_GT(clearly_outside, 3000);
    EXPECT_EQ(settled_outside, clearly_outside);
}

// pairs_not_at_an_end (four pairs at a time where the build has AVX2) leaves open exactly the pairs
// closest_at_an_end leaves open, in their order: over lists of 0 to 13 lines taken in any order
// and with repeats (the tails of fewer than four included), built with their closest points just
// inside or past an end, at squared sines near the 1e-4 below which nothing is decided, and with
// points for segments.
TEST(SegmentClosest, FourAtATimeLeaveOpenWhatOneAtATimeDoes) {
    std::mt19937 rng(57);
    std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
    auto random_unit = [&] {
        for (;;) {
            const Vec3 v(u(rng), u(rng), u(rng));
            if (glm::length(v) > 0.1 && glm::length(v) < 1.0) return glm::normalize(v);
        }
    };
    const double offsets[] = {-1e-5, -1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-7, 1e-5, 0.3};
    const double sines[] = {1.0, 0.1, 0.0101, 0.01, 0.0099, 1e-3, 0.0};
    std::vector<ModelTool::EdgeLine> lines(64);
    int open_total = 0, settled_total = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const Vec3 origin = 0.01 * Vec3(u(rng), u(rng), u(rng));
        const Vec3 d2 = std::pow(10.0, -5.0 + 2.0 * unit(rng)) * random_unit();
        for (ModelTool::EdgeLine& line : lines) {
            const double len = rng() % 16 == 0 ? 0.0 : std::pow(10.0, -5.0 + 2.0 * unit(rng));
            const double sine = sines[rng() % std::size(sines)];
            const Vec3 across = glm::normalize(glm::cross(glm::cross(d2, random_unit()), d2));
            line.along = len * (std::sqrt(1.0 - sine * sine) * glm::normalize(d2) + sine * across);
            const double delta = offsets[rng() % std::size(offsets)];
            const double t0 = rng() % 2 == 0 ? 1.0 + delta : -delta;  // on d2's line, from origin
            const double s0 = unit(rng) * 1.4 - 0.2;                  // on the line's own
            line.from = origin + t0 * d2 + 1e-4 * unit(rng) * across - s0 * line.along;
            line.length2 = glm::dot(line.along, line.along);
            line.inv_length2 = line.length2 > 0.0 ? 1.0 / line.length2 : 0.0;
        }
        const int count = int(rng() % 14);
        uint16_t hits[16], open[16], expected[16];
        for (int h = 0; h < count; ++h) hits[h] = uint16_t(rng() % lines.size());
        const double e = glm::dot(d2, d2);
        int expected_count = 0;
        for (int h = 0; h < count; ++h) {
            const ModelTool::EdgeLine& line = lines[hits[h]];
            if (!closest_at_an_end(line.along, d2, line.from - origin, line.length2, e)) expected[expected_count++] = hits[h];
        }
        const int open_count = pairs_not_at_an_end(lines.data(), hits, count, d2, origin, e, open);
        ASSERT_EQ(open_count, expected_count) << "trial " << trial;
        for (int h = 0; h < open_count; ++h) ASSERT_EQ(open[h], expected[h]) << "trial " << trial << ", pair " << h;
        open_total += open_count;
        settled_total += count - open_count;
    }
    // Both answers come up often.
    EXPECT_GT(open_total, 3000);
    EXPECT_GT(settled_total, 3000);
}

// distance_to_edge_region is a true distance to the points of the plane whose closest point on the
// triangle is on edge k: no point of the plane that closest_on_triangle puts on edge k is nearer
// the foot than it says, and one just past that distance towards the edge is on it (the strip's
// nearest point). Triangles of every shape (slivers included), 10 um to 1 mm across, far from the
// origin, with feet inside, beyond each edge and beyond each corner.
TEST(TriangleRegions, DistanceToAnEdgesRegionIsTheNearestPointOnIt) {
    std::mt19937 rng(83);
    std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
    int sampled_on_edge = 0, reached = 0, reach_tries = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const double size = std::pow(10.0, -5.0 + 2.0 * unit(rng));
        const Vec3 centre = 0.03 * Vec3(u(rng), u(rng), u(rng));
        Vec3 t[3];
        for (Vec3& v : t) v = centre + size * Vec3(u(rng), u(rng), u(rng));
        if (trial % 5 == 0) t[2] = t[0] + (0.5 + 0.01 * u(rng)) * (t[1] - t[0]) + 1e-3 * size * Vec3(u(rng), u(rng), u(rng));
        const Vec3 cr = glm::cross(t[1] - t[0], t[2] - t[0]);
        if (!(glm::length(cr) > 1e-9 * size * size)) continue;
        const Vec3 n = glm::normalize(cr);
        const Vec3 in_u = glm::normalize(t[1] - t[0]), in_w = glm::cross(n, in_u);
        auto on_plane = [&](const Vec3& p) { return p - glm::dot(n, p - t[0]) * n; };
        const Vec3 foot = on_plane(centre + 2.0 * size * (u(rng) * in_u + u(rng) * in_w));
        for (int k = 0; k < 3; ++k) {
            const double d = distance_to_edge_region(t, n, foot, k);
            ASSERT_GE(d, 0.0);
            const TriRegion edge = TriRegion(int(TriRegion::Edge0) + k);
            // Points of the plane round the foot, out to twice that distance and more.
            for (int s = 0; s < 200; ++s) {
                const double r = (s < 100 ? 2.0 * d : 3.0 * size) * std::sqrt(unit(rng));
                const double a = 2.0 * M_PI * unit(rng);
                const Vec3 y = on_plane(foot + r * (std::cos(a) * in_u + std::sin(a) * in_w));
                if (closest_on_triangle(y, t[0], t[1], t[2]).region != edge) continue;
                ++sampled_on_edge;
                ASSERT_GE(glm::length(y - foot), d - 1e-12 - 1e-9 * d)
                    << "trial " << trial << ", edge " << k << ": " << glm::length(y - foot) << " < " << d;
            }
            // The strip's nearest point, a little further in: on the edge.
            if (d > 1e-3 * size) {
                const Vec3& a0 = t[k];
                const Vec3 ab = t[(k + 1) % 3] - a0;
                Vec3 out = glm::normalize(glm::cross(ab, n));
                if (glm::dot(out, t[(k + 2) % 3] - a0) > 0.0) out = -out;
                const double along = std::clamp(glm::dot(foot - a0, ab) / glm::dot(ab, ab), 0.01, 0.99);
                const double over = std::max(glm::dot(foot - a0, out), 1e-3 * size);
                const Vec3 nearest = a0 + along * ab + over * out;
                ++reach_tries;
                if (closest_on_triangle(nearest, t[0], t[1], t[2]).region == edge &&
                    glm::length(nearest - foot) <= d + 0.02 * size)
                    ++reached;
            }
        }
    }
    EXPECT_GT(sampled_on_edge, 20000);
    EXPECT_GT(reach_tries, 3000);
    // Not a loose bound: a point of the region lies about that far off (measured: 7,562 of 7,702;
    // the rest are feet whose nearest point the test's own margins into the strip move further).
    EXPECT_GT(reached, reach_tries * 95 / 100) << reached << " of " << reach_tries;
}

// root_exceeds(x, f) answers as the rounded root's comparison sqrt(x) > f does, for x drawn
// round f squared to within a few ulps (where the band needs the root), across twenty orders of
// magnitude and far from it, and for NaN and infinite x.
TEST(RootExceeds, AnswersAsTheRoundedRootDoes) {
    std::mt19937_64 rng(20261206);
    std::uniform_real_distribution<double> exponent(-12.0, 8.0), unit(0.5, 2.0);
    long near = 0;
    for (int i = 0; i < 200000; ++i) {
        const double f = std::pow(10.0, exponent(rng)) * unit(rng);
        double x = f * f;
        // Step x by up to 40 ulps either way of f squared, or scale it well away.
        if (i % 4 != 0) {
            const int steps = int(rng() % 81) - 40;
            for (int k = 0; k < std::abs(steps); ++k) x = std::nextafter(x, steps > 0 ? HUGE_VAL : 0.0);
            ++near;
        } else {
            x *= unit(rng) * unit(rng);
        }
        EXPECT_EQ(root_exceeds(x, f), std::sqrt(x) > f) << "x " << x << " f " << f;
    }
    EXPECT_GT(near, 100000);
    EXPECT_FALSE(root_exceeds(std::nan(""), 1e-3));
    EXPECT_TRUE(root_exceeds(HUGE_VAL, 1e-3));
    EXPECT_FALSE(root_exceeds(0.0, 1e-3));
}

// closest_on_triangle_within gives closest_on_triangle's point, feature and distance wherever
// that distance is within the bound (to the bit), and false wherever it is beyond: points
// round a triangle in every feature's region, and bounds at and a rounding either side of the
// distance.
TEST(RootExceeds, TheTriangleTestWithinABoundIsTheTriangleTest) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> coord(-2e-3, 2e-3);
    const Vec3 a(0.0, 0.0, 0.0), b(1e-3, 0.1e-3, 0.0), c(0.2e-3, 0.9e-3, 0.3e-3);
    int regions[7] = {};
    for (int i = 0; i < 100000; ++i) {
        const Vec3 p(coord(rng), coord(rng), coord(rng));
        const TriClosest full = closest_on_triangle(p, a, b, c);
        ++regions[int(full.region)];
        for (const double within : {full.distance, std::nextafter(full.distance, 0.0),
                                    std::nextafter(full.distance, HUGE_VAL), 0.5 * full.distance, 2.0 * full.distance}) {
            TriClosest r;
            const bool in = closest_on_triangle_within(p, a, b, c, b - a, c - a, within, r);
            ASSERT_EQ(in, !(full.distance > within)) << i;
            if (!in) continue;
            EXPECT_EQ(r.region, full.region);
            EXPECT_EQ(r.distance, full.distance);
            EXPECT_EQ(r.point, full.point);
        }
    }
    for (int k = 0; k < 7; ++k) EXPECT_GT(regions[k], 100) << "region " << k;
}

}  // namespace
}  // namespace sulcus
