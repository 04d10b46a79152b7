// Tools made of several convex pieces (a rigid union): the model keeps each piece's features, and
// the step takes candidates and constraints from every piece.
#include "scene_helpers.h"

#include "geometry.h"
#include "tool_placement.h"
#include "sulcus/content/probes.h"
#include "sulcus/engine/exact_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

namespace sulcus {
namespace {

using namespace test;

TriMesh merge(const TriMesh& a, const TriMesh& b) {
    TriMesh m = a;
    const uint32_t base = uint32_t(a.vertices.size());
    m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (const auto& t : b.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return m;
}

// The piece an active atom's tool feature belongs to.
int piece_of(const ModelTool& tool, const Atom& a) {
    switch (a.kind) {
        case AtomKind::VertexFace:
        case AtomKind::FixedAxis: return tool.vertex_piece[a.tool_vertex];
        case AtomKind::EdgeEdge: return tool.vertex_piece[tool.edges[a.tool_edge][0]];
        case AtomKind::FaceVertex:
            for (size_t k = 0; k < tool.pieces.size(); ++k)
                if (a.tool_face >= tool.pieces[k].face_begin &&
                    a.tool_face < tool.pieces[k].face_begin + tool.pieces[k].face_count)
                    return int(k);
    }
    return -1;
}

// A probe-like tool: a straight tip (0.5 mm square, 10 mm long, its end at the origin) and a
// shank bent off it at right angles near its top, overlapping the tip.
TriMesh bent_probe() {
    const TriMesh tip = make_box(Vec3(0.25 * mm, 5 * mm, 0.25 * mm), Vec3(0, 5 * mm, 0));
    const TriMesh shank = make_box(Vec3(3 * mm, 0.5 * mm, 0.25 * mm), Vec3(2.75 * mm, 9.5 * mm, 0));
    return merge(tip, shank);
}

TEST(ToolPieces, ModelKeepsEachConvexPiece) {
    const ModelBuild b = build_model(bent_probe(), {}, RendererSettings{});
    ASSERT_TRUE(b.model) << b.error;
    const ModelTool& tool = b.model->tool;
    ASSERT_EQ(tool.pieces.size(), 2u);
    for (const ToolPiece& p : tool.pieces) {
        EXPECT_EQ(p.vertex_count, 8u);
        EXPECT_EQ(p.triangle_count, 12u);
        EXPECT_EQ(p.face_count, 6u);   // a box: six planes
        EXPECT_EQ(p.edge_count, 12u);  // and twelve real edges
        for (uint32_t v = p.vertex_begin; v < p.vertex_begin + p.vertex_count; ++v)
            EXPECT_EQ(tool.vertex_piece[v], &p - tool.pieces.data());
    }
    // Each piece's vertices lie inside its own face planes.
    for (const ToolPiece& p : tool.pieces)
        for (uint32_t f = p.face_begin; f < p.face_begin + p.face_count; ++f)
            for (uint32_t v = p.vertex_begin; v < p.vertex_begin + p.vertex_count; ++v)
                EXPECT_LE(glm::dot(tool.face_normals[f], tool.mesh.vertices[v]) - tool.face_offsets[f], 1e-15);
    // The tip is long enough to carry bounding capsules; both pieces are.
    EXPECT_EQ(tool.pieces[0].capsule_count, kToolCapsules);
}

TEST(ToolPieces, EachPieceListsItsOwnVerticesInOrderAlongItsAxis) {
    const ModelBuild b = build_model(bent_probe(), {}, RendererSettings{});
    ASSERT_TRUE(b.model) << b.error;
    const ModelTool& tool = b.model->tool;
    ASSERT_EQ(tool.axial_vertices.size(), tool.mesh.vertices.size());
    ASSERT_EQ(tool.axial_coords.size(), tool.mesh.vertices.size());
    for (const ToolPiece& p : tool.pieces) {
        EXPECT_NEAR(glm::length(p.axis), 1.0, 1e-12);
        // The axis is the capsules' (the tip's runs along y, the shank's along x).
        const Vec3 chain = p.capsule_points[kToolCapsules] - p.capsule_points[0];
        EXPECT_NEAR(std::abs(glm::dot(p.axis, chain)), glm::length(chain), 1e-12);
        std::set<uint32_t> seen;
        for (uint32_t r = p.vertex_begin; r < p.vertex_begin + p.vertex_count; ++r) {
            const uint32_t v = tool.axial_vertices[r];
            EXPECT_GE(v, p.vertex_begin);
            EXPECT_LT(v, p.vertex_begin + p.vertex_count);
            seen.insert(v);
            EXPECT_EQ(tool.axial_coords[r], glm::dot(p.axis, tool.mesh.vertices[v]));
            if (r > p.vertex_begin) {
                EXPECT_LE(tool.axial_coords[r - 1], tool.axial_coords[r]);
            }
        }
        EXPECT_EQ(seen.size(), p.vertex_count);  // each of the piece's vertices once
    }
    EXPECT_GT(std::abs(tool.pieces[0].axis.y), 0.999);
    EXPECT_GT(std::abs(tool.pieces[1].axis.x), 0.999);
}

// The slabs across each piece's axis (ToolPiece::cross_range) hold every vertex a ball holds:
// for balls round points about the piece, at the radii gather asks (tens of micrometres to a
// millimetre), the masks of the slabs the ball's shadow meets along both cross vectors have the
// bit of each vertex within the ball. And they leave some out, or they would save nothing.
TEST(ToolPieces, TheSlabsAcrossTheAxisHoldEveryVertexABallHolds) {
    std::vector<TriMesh> tools = {bent_probe()};
    for (ProbeKind kind : kAllProbeKinds) tools.push_back(make_probe_tip_collision(kind));
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
    int balls = 0, held = 0, left_out = 0;
    for (const TriMesh& mesh : tools) {
        const ModelBuild b = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        for (const ToolPiece& p : tool.pieces) {
            if (p.vertex_count > 64u) {
                EXPECT_EQ(p.cross_cells, 0);  // gather walks the axial run alone
                continue;
            }
            ASSERT_EQ(p.cross_cells, kCrossCells);
            EXPECT_NEAR(glm::length(p.cross_u), 1.0, 1e-12);
            EXPECT_NEAR(glm::length(p.cross_w), 1.0, 1e-12);
            EXPECT_NEAR(glm::dot(p.cross_u, p.axis), 0.0, 1e-12);
            EXPECT_NEAR(glm::dot(p.cross_w, p.axis), 0.0, 1e-12);
            EXPECT_NEAR(glm::dot(p.cross_u, p.cross_w), 0.0, 1e-12);
            for (int trial = 0; trial < 2000; ++trial) {
                // Round a vertex of the piece, or anywhere in its box.
                const uint32_t near = p.vertex_begin + uint32_t(rng() % p.vertex_count);
                const Vec3 centre = trial % 2 == 0 ? tool.mesh.vertices[near] + 3e-4 * Vec3(u(rng), u(rng), u(rng))
                                                   : p.centre + p.spread_m * Vec3(u(rng), u(rng), u(rng));
                const double radius = 1e-5 * std::pow(100.0, unit(rng));
                const double cu = glm::dot(p.cross_u, centre), cw = glm::dot(p.cross_w, centre);
                const uint64_t mask = p.cross_range[0][size_t(p.cross_cell(0, cu - radius) * kCrossCells +
                                                             p.cross_cell(0, cu + radius))] &
                                      p.cross_range[1][size_t(p.cross_cell(1, cw - radius) * kCrossCells +
                                                             p.cross_cell(1, cw + radius))];
                ++balls;
                for (uint32_t r = 0; r < p.vertex_count; ++r) {
                    const Vec3& v = tool.mesh.vertices[tool.axial_vertices[p.vertex_begin + r]];
                    const bool in_mask = (mask >> r & 1u) != 0;
                    if (glm::length(v - centre) <= radius) {
                        ++held;
                        EXPECT_TRUE(in_mask) << "vertex " << r << " of a piece, ball of " << radius << " m";
                    } else if (!in_mask) {
                        ++left_out;
                    }
                }
            }
        }
    }
    EXPECT_GT(held, balls / 10);
    EXPECT_GT(left_out, balls);
}

// The lanes of edge boxes the edge query reads (ToolPiece::edge_boxes, edge_block_boxes): each
// edge's box, exactly its two ends' bounds, in lane e % 4 of block e / 4; each block's box in
// its group's lane holds its edges' boxes; every lane past the last edge or block is empty, so it
// meets no query. The query finds an edge exactly where its own box meets the query box, which
// these make so.
TEST(ToolPieces, EdgeBoxLanesHoldEachEdgeInItsBlockAndNothingElse) {
    std::vector<TriMesh> tools = {bent_probe()};
    for (ProbeKind kind : kAllProbeKinds) tools.push_back(make_probe_tip_collision(kind));
    int edges = 0;
    for (const TriMesh& mesh : tools) {
        const ModelBuild b = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        for (const ToolPiece& p : tool.pieces) {
            const uint32_t blocks = (p.edge_count + 3) / 4;
            ASSERT_EQ(p.edge_boxes.size(), blocks);
            ASSERT_EQ(p.edge_block_boxes.size(), (blocks + 3) / 4);
            for (uint32_t e = 0; e < 4 * blocks; ++e) {
                const ToolPiece::BoxLanes& lanes = p.edge_boxes[e / 4];
                const ToolPiece::BoxLanes& group = p.edge_block_boxes[e / 16];
                const int lane = int(e % 4), block_lane = int(e / 4 % 4);
                if (e >= p.edge_count) {
                    for (int d = 0; d < 3; ++d) EXPECT_GT(lanes.lo[d][lane], lanes.hi[d][lane]) << "lane past the end";
                    continue;
                }
                ++edges;
                const Vec3& a = tool.mesh.vertices[tool.edges[p.edge_begin + e][0]];
                const Vec3& c = tool.mesh.vertices[tool.edges[p.edge_begin + e][1]];
                for (int d = 0; d < 3; ++d) {
                    EXPECT_EQ(lanes.lo[d][lane], std::min(a[d], c[d])) << "edge " << e;
                    EXPECT_EQ(lanes.hi[d][lane], std::max(a[d], c[d])) << "edge " << e;
                    EXPECT_LE(group.lo[d][block_lane], lanes.lo[d][lane]) << "edge " << e;
                    EXPECT_GE(group.hi[d][block_lane], lanes.hi[d][lane]) << "edge " << e;
                }
            }
            for (uint32_t k = blocks; k < 4 * uint32_t(p.edge_block_boxes.size()); ++k)
                for (int d = 0; d < 3; ++d)
                    EXPECT_GT(p.edge_block_boxes[k / 4].lo[d][k % 4], p.edge_block_boxes[k / 4].hi[d][k % 4])
                        << "block past the end";
        }
    }
    EXPECT_GT(edges, 100);
}

// The slabs along each piece's axis (ToolPiece::axial_first) find where an axial run starts as
// std::lower_bound does, for coordinates at, just beside and between the vertices', past both
// ends, and NaN; say a run is empty only when no vertex lies in it, and say so for most runs
// beside a long piece; and, for a piece of at most 64 vertices, give a mask with every vertex of
// the run.
TEST(ToolPieces, TheSlabsAlongTheAxisFindEveryRunAsASearchWould) {
    std::vector<TriMesh> tools = {bent_probe()};
    for (ProbeKind kind : kAllProbeKinds) tools.push_back(make_probe_tip_collision(kind));
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int runs = 0, said_empty = 0, empty = 0;
    for (const TriMesh& mesh : tools) {
        const ModelBuild b = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        for (const ToolPiece& p : tool.pieces) {
            const double* coords = tool.axial_coords.data() + p.vertex_begin;
            const int n = int(p.vertex_count);
            EXPECT_EQ(p.axial_first[0], 0u);
            EXPECT_EQ(p.axial_first[kAxialCells], uint32_t(n));
            const double lo = coords[0], hi = coords[n - 1], span = hi - lo;
            std::vector<double> probes = {lo - span, hi + span, std::numeric_limits<double>::quiet_NaN()};
            for (int r = 0; r < n; ++r) {
                probes.push_back(coords[r]);
                probes.push_back(std::nextafter(coords[r], -1e300));
                probes.push_back(std::nextafter(coords[r], 1e300));
            }
            for (int i = 0; i < 2000; ++i) probes.push_back(lo - 0.1 * span + 1.2 * span * unit(rng));
            for (double bottom : probes) {
                const int start = p.axial_run_start(coords, bottom);
                EXPECT_EQ(start, int(std::lower_bound(coords, coords + n, bottom) - coords)) << "at " << bottom;
                // Runs as gather asks: a ball's reach along the axis, micrometres to a millimetre.
                const double top = bottom + 2e-5 * std::pow(50.0, unit(rng));
                int inside = 0;
                for (int r = 0; r < n; ++r) inside += coords[r] >= bottom && coords[r] <= top;
                ++runs;
                empty += inside == 0;
                if (p.axial_run_empty(bottom, top)) {
                    ++said_empty;
                    EXPECT_EQ(inside, 0) << "run [" << bottom << ", " << top << "] said empty";
                }
                if (n <= 64 && !std::isnan(bottom)) {
                    const uint64_t mask = p.axial_mask(p.axial_cell(bottom), p.axial_cell(top));
                    for (int r = 0; r < n; ++r) {
                        if (coords[r] >= bottom && coords[r] <= top) {
                            EXPECT_TRUE(mask >> r & 1u) << "vertex " << r << " of run [" << bottom << ", " << top << "]";
                        }
                    }
                }
            }
        }
    }
    // Most empty runs are found so without a search.
    EXPECT_GT(said_empty, empty / 2);
    EXPECT_GT(empty, runs / 10);
}

// A point outside a piece is over the face plane it is most in front of by at least plane_ratio
// of its distance from the piece: points off the pieces' vertices, edges and faces, along blends
// of the normals of the faces round them (where the bound is tightest: a box's corner along its
// diagonal is over each face by 1 / sqrt(3) of its distance).
TEST(ToolPieces, ThePlaneRatioBoundsHowFarAPointIsOverTheFacesOfThePiece) {
    std::vector<TriMesh> tools = {bent_probe()};
    for (ProbeKind kind : kAllProbeKinds) tools.push_back(make_probe_tip_collision(kind));
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double tightest = 1e300;
    int points = 0;
    for (const TriMesh& mesh : tools) {
        const ModelBuild b = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        for (size_t k = 0; k < tool.pieces.size(); ++k) {
            const ToolPiece& p = tool.pieces[k];
            EXPECT_GT(p.plane_ratio, 0.5) << "piece " << k;
            EXPECT_LE(p.plane_ratio, 1.0) << "piece " << k;
            const Vec3* vs = tool.mesh.vertices.data() + p.vertex_begin;
            const uint32_t t0 = p.triangle_begin, t1 = p.triangle_begin + p.triangle_count;
            auto over = [&](const Vec3& q) {
                double most = -1e300;
                for (uint32_t f = p.face_begin; f < p.face_begin + p.face_count; ++f)
                    most = std::max(most, glm::dot(tool.face_normals[f], q) - tool.face_offsets[f]);
                return most;
            };
            auto distance = [&](const Vec3& q) {
                double least = 1e300;
                for (uint32_t t = t0; t < t1; ++t) {
                    const auto& tri = tool.piece_triangles[t];
                    least = std::min(least, closest_on_triangle(q, vs[tri[0]], vs[tri[1]], vs[tri[2]]).distance);
                }
                return least;
            };
            for (uint32_t t = t0; t < t1; ++t) {
                const auto& tri = tool.piece_triangles[t];
                for (int corner = 0; corner < 3; ++corner) {
                    const uint32_t v = tri[size_t(corner)];
                    const Vec3& next = vs[tri[size_t((corner + 1) % 3)]];
                    const Vec3& last = vs[tri[size_t((corner + 2) % 3)]];
                    // The normals of the faces round v, blended at random; from v itself, from a
                    // point of an edge of v and from a point inside the triangle.
                    std::vector<Vec3> normals;
                    for (uint32_t u = t0; u < t1; ++u)
                        for (uint32_t c : tool.piece_triangles[u])
                            if (c == v) normals.push_back(tool.piece_triangle_normals[u]);
                    for (int trial = 0; trial < 6; ++trial) {
                        Vec3 blend(0.0);
                        for (const Vec3& n : normals) blend += std::pow(unit(rng), 4.0) * n;
                        if (trial == 0) blend = normals[0];
                        const double len = glm::length(blend);
                        if (!(len > 0.0)) continue;
                        const double a = unit(rng), c = unit(rng) * (1.0 - a);
                        const Vec3 from = trial < 3   ? vs[v]
                                          : trial < 5 ? vs[v] + a * (next - vs[v])
                                                      : vs[v] + a * (next - vs[v]) + c * (last - vs[v]);
                        const Vec3 q = from + (1e-6 * std::pow(1000.0, unit(rng))) * (blend / len);
                        const double d = distance(q), h = over(q);
                        if (!(h > 0.0)) continue;  // not outside (a blend that points in)
                        ++points;
                        tightest = std::min(tightest, h / d);
                        EXPECT_GE(h, p.plane_ratio * d - 1e-15) << "piece " << k << " vertex " << v;
                    }
                }
            }
        }
    }
    EXPECT_GT(points, 1000);
    // The bound is needed: some points are over every face by well under their distance.
    EXPECT_LT(tightest, 0.9);
}

// A piece certified for it finds the vertex least along a direction by descending along its
// corners: the same value as looking at every vertex, from any start, for any direction; GJK's
// bounds with the descent are those without it, to the tolerance asked. Certified: a vertex
// inside a flat face (the descent starts at a corner); not certified: a vertex on a straight
// edge.
TEST(ToolPieces, DescentAlongEdgesFindsTheLeastVertexOfACertifiedPiece) {
    std::vector<TriMesh> tools = {bent_probe()};
    for (ProbeKind kind : kAllProbeKinds) tools.push_back(make_probe_collision(kind));
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int certified = 0;
    for (const TriMesh& mesh : tools) {
        const ModelBuild b = build_model(mesh, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        ASSERT_EQ(tool.neighbour_offsets.size(), tool.mesh.vertices.size() + 1);
        for (size_t k = 0; k < tool.pieces.size(); ++k) {
            const ToolPiece& p = tool.pieces[k];
            if (!p.descend) continue;
            ++certified;
            const Vec3* vs = tool.mesh.vertices.data() + p.vertex_begin;
            const int n = int(p.vertex_count);
            const uint32_t* offsets = tool.neighbour_offsets.data() + p.vertex_begin;
            for (int trial = 0; trial < 3000; ++trial) {
                Vec3 d(u(rng), u(rng), u(rng));
                if (trial % 3 == 0) d = Vec3(double(trial % 2), double(trial / 3 % 2), 0.0);  // axis-aligned ties
                if (!(glm::dot(d, d) > 0.0)) d = Vec3(0.0, 0.0, 1.0);
                const int start = int(rng() % uint64_t(n));
                const int scan = least_along(vs, n, nullptr, nullptr, nullptr, d, 0);
                const int descent = least_along(vs, n, offsets, tool.neighbours.data(),
                                                tool.descent_start.data() + p.vertex_begin, d, start);
                ASSERT_EQ(glm::dot(d, vs[descent]), glm::dot(d, vs[scan])) << "piece " << k << " trial " << trial;
            }
            // GJK on triangles around the piece: the same bounds with the descent as without it.
            std::vector<Vec3> world(tool.mesh.vertices.begin(), tool.mesh.vertices.end());
            std::vector<Vec3> normals(tool.face_normals.begin(), tool.face_normals.end());
            const Quat q{1.0, 0.0, 0.0, 0.0};
            const ConvexView with = tool_convex_view(tool, k, world.data(), normals.data(), tool.face_offsets.data(), &q);
            ASSERT_NE(with.neighbours, nullptr);
            ConvexView without = with;
            without.neighbours = nullptr;
            without.neighbour_offsets = nullptr;
            const Vec3 centre = p.centre;
            for (int trial = 0; trial < 500; ++trial) {
                const Vec3 at = centre + (p.spread_m * 1.5) * Vec3(u(rng), u(rng), u(rng));
                const Vec3 a = at + 2e-4 * Vec3(u(rng), u(rng), u(rng)), bb = at + 2e-4 * Vec3(u(rng), u(rng), u(rng)),
                           c = at + 2e-4 * Vec3(u(rng), u(rng), u(rng));
                const Vec3 hint = centre - at;
                const DistanceBounds x = convex_triangle_distance(with, a, bb, c, 1e300, 1e-13, 64, &hint);
                const DistanceBounds y = convex_triangle_distance(without, a, bb, c, 1e300, 1e-13, 64, &hint);
                // Where two vertices tie along a direction the descent may take the other one:
                // the search then runs its own way to the same bounds, but for rounding.
                ASSERT_NEAR(x.lower, y.lower, 1e-13) << "piece " << k << " trial " << trial;
                ASSERT_NEAR(x.upper, y.upper, 1e-13) << "piece " << k << " trial " << trial;
            }
        }
    }
    // Both boxes of the bent probe and at least the working tip of every probe.
    EXPECT_GE(certified, 2 + int(std::size(kAllProbeKinds)));

    // A box whose top face has a vertex at its middle: certified, and a descent from there
    // starts at a corner of the face, so it does not stop on the face (along +y every neighbour
    // of the middle is as high) but goes down to the bottom.
    const auto up = [](const TriMesh& m, const std::array<uint32_t, 3>& tri) {
        return m.vertices[tri[0]].y > 0 && m.vertices[tri[1]].y > 0 && m.vertices[tri[2]].y > 0;
    };
    TriMesh centred = make_box(Vec3(1 * mm, 1 * mm, 1 * mm), Vec3(0.0));
    {
        std::vector<std::array<uint32_t, 3>> kept, top;
        for (const auto& tri : centred.triangles) (up(centred, tri) ? top : kept).push_back(tri);
        ASSERT_EQ(top.size(), 2u);
        const uint32_t mid = uint32_t(centred.vertices.size());
        centred.vertices.push_back(Vec3(0.0, 1 * mm, 0.0));
        // Each boundary edge of the top face (in one of its two triangles only) fanned to the middle.
        for (size_t t = 0; t < 2; ++t)
            for (size_t e = 0; e < 3; ++e) {
                const uint32_t v0 = top[t][e], v1 = top[t][(e + 1) % 3];
                bool shared = false;
                for (size_t f = 0; f < 3; ++f) shared |= top[1 - t][f] == v1 && top[1 - t][(f + 1) % 3] == v0;
                if (!shared) kept.push_back({v0, v1, mid});
            }
        centred.triangles = kept;
        const ModelBuild b = build_model(centred, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        const ModelTool& tool = b.model->tool;
        ASSERT_EQ(tool.pieces.size(), 1u);
        EXPECT_TRUE(tool.pieces[0].descend);
        const int least = least_along(tool.mesh.vertices.data(), int(tool.mesh.vertices.size()),
                                      tool.neighbour_offsets.data(), tool.neighbours.data(), tool.descent_start.data(),
                                      Vec3(0.0, 1.0, 0.0), int(mid));
        EXPECT_NEAR(tool.mesh.vertices[size_t(least)].y, -1 * mm, 1e-12);
    }
    // A box with a vertex in the middle of one of its edges: the edge between the two corners
    // is lost to a descent over corners, so the box is not certified.
    TriMesh split = make_box(Vec3(1 * mm, 1 * mm, 1 * mm), Vec3(0.0));
    {
        const MeshTopology topo = build_topology(split);
        const MeshEdge* edge = nullptr;
        for (const MeshEdge& e : topo.edges)
            if (e.convexity == Convexity::Convex) {
                edge = &e;
                break;
            }
        ASSERT_NE(edge, nullptr);
        const uint32_t mid = uint32_t(split.vertices.size());
        split.vertices.push_back(0.5 * (split.vertices[edge->v[0]] + split.vertices[edge->v[1]]));
        std::vector<std::array<uint32_t, 3>> tris;
        for (const auto& tri : split.triangles) {
            bool cut = false;
            for (size_t k = 0; k < 3 && !cut; ++k) {
                const uint32_t x = tri[k], y = tri[(k + 1) % 3], z = tri[(k + 2) % 3];
                if ((x == edge->v[0] && y == edge->v[1]) || (x == edge->v[1] && y == edge->v[0])) {
                    tris.push_back({x, mid, z});
                    tris.push_back({mid, y, z});
                    cut = true;
                }
            }
            if (!cut) tris.push_back(tri);
        }
        split.triangles = tris;
        const ModelBuild b = build_model(split, {}, RendererSettings{});
        ASSERT_TRUE(b.model) << b.error;
        ASSERT_EQ(b.model->tool.pieces.size(), 1u);
        EXPECT_FALSE(b.model->tool.pieces[0].descend);
    }
}

TEST(ToolPieces, RejectsANonConvexPieceAndTooManyPieces) {
    // An L-shaped single piece: two boxes sharing a face would be one non-convex component.
    const std::vector<Vec2> ell = {{0, 0}, {2e-3, 0}, {2e-3, 1e-3}, {1e-3, 1e-3}, {1e-3, 2e-3}, {0, 2e-3}};
    const TriMesh box = make_box(Vec3(1e-3));
    const ModelBuild b = build_model(merge(box, make_extruded_polygon(ell, 5e-3, 6e-3)), {}, RendererSettings{});
    ASSERT_FALSE(b.model);
    EXPECT_NE(b.error.find("piece 1: not convex"), std::string::npos) << b.error;

    TriMesh many;
    for (int i = 0; i <= kMaxToolPieces; ++i)
        many = merge(many, make_box(Vec3(0.1e-3), Vec3(i * 1e-3, 0, 0)));
    const ModelBuild m = build_model(many, {}, RendererSettings{});
    ASSERT_FALSE(m.model);
    EXPECT_NE(m.error.find("pieces"), std::string::npos) << m.error;
}

// The tip pressed on the pocket floor while the shank rests on a neighbouring crown: two contact
// regions, one on each piece, and no penetration anywhere.
TEST(ToolPieces, ShankOnNeighbourCrownWhileTipOnPocketFloor) {
    const TriMesh tool = bent_probe();
    const std::vector<SceneObject> objects = {
        object("floor", make_box(Vec3(5 * mm, 1 * mm, 5 * mm), Vec3(0, -1 * mm, 0))),
        // Its top at 9 mm, under the shank (x 3..5 mm), clear of the tip.
        object("neighbour crown", make_box(Vec3(1 * mm, 1 * mm, 1 * mm), Vec3(4 * mm, 8 * mm, 0))),
    };
    auto model = model_of(tool, objects);
    const std::vector<TriMesh> pieces = connected_components(tool);
    std::vector<PlacedMesh> placed;
    for (const SceneObject& o : objects) placed.push_back(PlacedMesh{&o.mesh, o.pose});

    State state = make_state(pose(Vec3(0, 1 * mm, 0)));
    StepResult r;
    double worst = 0.0;
    const int down = 400, hold = 200;
    for (int i = 0; i <= down + hold; ++i) {
        const double y = 1 * mm - 1.3 * mm * std::min(1.0, double(i) / down);  // to 0.3 mm below the floor
        r = step(*model, state, pose(Vec3(0, y, 0)));
        ASSERT_TRUE(std::isfinite(r.force_N.y));
        worst = std::max(worst, exact_check(pieces, r.graphic, placed, 0.0).penetration_m);
    }
    EXPECT_LE(worst, 1e-6);
    EXPECT_EQ(r.status, StepStatus::Contact);
    EXPECT_EQ(r.stats.regions, 2);
    std::set<int> pieces_touching, objects_touching;
    for (int i = 0; i < state.active_count; ++i) {
        pieces_touching.insert(piece_of(model->tool, state.active[i]));
        objects_touching.insert(state.active[i].object);
    }
    EXPECT_EQ(pieces_touching, (std::set<int>{0, 1}));
    EXPECT_EQ(objects_touching, (std::set<int>{0, 1}));
    // Both contacts carry the push: the tool rests at the floor and on the crown.
    EXPECT_NEAR(r.graphic.position.y, 0.0, 1e-6);
    EXPECT_NEAR(r.force_N.y, 1000.0 * 0.3 * mm, 1e-3);
}

}  // namespace
}  // namespace sulcus
