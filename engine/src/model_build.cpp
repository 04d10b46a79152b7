// Builds the immutable model of the renderer: the tool's convex pieces with their features and
// each object's world-placed mesh, adjacency and BVH.
#include "sulcus/engine/renderer.h"

#include "geometry.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace sulcus {

namespace {

// Largest coordinate magnitude of a mesh, for scale-aware tolerances.
double mesh_scale(const TriMesh& m) {
    double s = 0.0;
    for (const Vec3& v : m.vertices) s = std::max(s, std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))));
    return std::max(s, 1e-9);
}

// The capsules around the principal axis of a piece's vertices (power iteration on their
// covariance).
void set_bounding_capsule(const TriMesh& piece_mesh, ToolPiece& tool) {
    const auto& vs = piece_mesh.vertices;
    Vec3 c(0.0);
    for (const Vec3& v : vs) c += v;
    c /= double(vs.size());
    glm::dmat3 cov(0.0);
    for (const Vec3& v : vs) cov += glm::outerProduct(v - c, v - c);
    Vec3 axis(1.0, 0.7, 0.3);
    for (int it = 0; it < 64; ++it) {
        const Vec3 next = cov * axis;
        const double len = glm::length(next);
        if (!(len > 0.0)) break;
        axis = next / len;
    }
    axis = glm::normalize(axis);
    double lo = 1e300, hi = -1e300;
    for (const Vec3& v : vs) {
        lo = std::min(lo, glm::dot(v - c, axis));
        hi = std::max(hi, glm::dot(v - c, axis));
    }
    tool.axis = axis;
    constexpr int K = kToolCapsules;
    for (int k = 0; k <= K; ++k) tool.capsule_points[size_t(k)] = c + (lo + (hi - lo) * k / K) * axis;
    // The tool between two cut planes is the hull of its vertices there and of its edges' crossings
    // of the planes; the largest distance to the axis is at one of those points.
    auto radial = [&](const Vec3& x) { return glm::length((x - c) - glm::dot(x - c, axis) * axis); };
    auto slab_of = [&](double s) { return std::clamp(int(std::floor((s - lo) / (hi - lo) * K)), 0, K - 1); };
    std::array<double, K> r{};
    // Each slab's points (axial coordinate from the slab's start over its length, radial
    // distance), for the taper below.
    std::array<std::vector<std::array<double, 2>>, K> points;
    const double length = (hi - lo) / K;
    auto add = [&](int k, double s, double rr) {
        r[size_t(k)] = std::max(r[size_t(k)], rr);
        points[size_t(k)].push_back({(s - (lo + length * k)) / length, rr});
    };
    for (const Vec3& v : vs) {
        const double s = glm::dot(v - c, axis);
        add(slab_of(s), s, radial(v));
        // A vertex on a cut belongs to both slabs.
        const double u = (s - lo) / (hi - lo) * K;
        const int near = int(std::lround(u));
        if (std::abs(u - near) < 1e-9 && near > 0 && near < K) {
            add(near - 1, s, radial(v));
            add(near, s, radial(v));
        }
    }
    for (const auto& tri : piece_mesh.triangles)
        for (int e = 0; e < 3; ++e) {
            const Vec3& a = vs[tri[size_t(e)]];
            const Vec3& b = vs[tri[size_t((e + 1) % 3)]];
            const double sa = glm::dot(a - c, axis), sb = glm::dot(b - c, axis);
            for (int k = 1; k < K; ++k) {
                const double cut = lo + (hi - lo) * k / K;
                if ((sa - cut) * (sb - cut) >= 0.0) continue;
                const double rr = radial(a + (b - a) * ((cut - sa) / (sb - sa)));
                add(k - 1, cut, rr);
                add(k, cut, rr);
            }
        }
    // A hair over, so rounding never puts a point outside.
    for (int k = 0; k < K; ++k) tool.capsule_radii_m[size_t(k)] = r[size_t(k)] * (1.0 + 1e-9) + 1e-12;
    // The taper: the line over the slab's points (radius against axial position) lowest at the
    // slab's middle, a side of their upper hull. The slab is the hull of those points, and the
    // truncated cone under that line holds them, so it holds the slab; the hull of the balls at
    // the ends holds the cone. Where the line comes out over the capsule's radius or under zero
    // at an end, or the balls would hold one another, the capsule itself.
    for (int k = 0; k < K; ++k) {
        const double cap = tool.capsule_radii_m[size_t(k)];
        tool.taper_radii_m[size_t(k)] = {cap, cap};
        auto& pts = points[size_t(k)];
        std::sort(pts.begin(), pts.end());
        std::vector<std::array<double, 2>> upper;  // the upper hull, left to right
        for (const auto& q : pts) {
            while (upper.size() >= 2) {
                const auto& o = upper[upper.size() - 2];
                const auto& m = upper.back();
                if ((m[0] - o[0]) * (q[1] - o[1]) - (m[1] - o[1]) * (q[0] - o[0]) >= 0.0) upper.pop_back();
                else break;
            }
            upper.push_back(q);
        }
        double a0 = -1.0, slope = 0.0;
        for (size_t i = 0; i + 1 < upper.size(); ++i) {
            const auto &p0 = upper[i], &p1 = upper[i + 1];
            if (p0[0] <= 0.5 && p1[0] >= 0.5 && p1[0] > p0[0]) {
                slope = (p1[1] - p0[1]) / (p1[0] - p0[0]);
                a0 = p0[1] - slope * p0[0];
                break;
            }
        }
        if (!(a0 >= 0.0)) continue;
        // Over every point by its rounding, then a hair more.
        double lift = 0.0;
        for (const auto& q : pts) lift = std::max(lift, q[1] - (a0 + slope * q[0]));
        const double r0 = (a0 + lift) * (1.0 + 1e-9) + 1e-12, r1 = (a0 + slope + lift) * (1.0 + 1e-9) + 1e-12;
        if (!(r0 >= 0.0 && r1 >= 0.0 && r0 <= cap && r1 <= cap && std::abs(r0 - r1) < 0.5 * length)) continue;
        tool.taper_radii_m[size_t(k)] = {r0, r1};
    }
    const double widest = *std::max_element(tool.capsule_radii_m.begin(), tool.capsule_radii_m.end());
    tool.capsule_count = (hi - lo) > 4.0 * widest ? K : 0;
}

// The descent along a convex piece's corners (least_along): each corner's neighbouring corners,
// and the corner a descent from each vertex starts at. Certified (true) when it finds the vertex
// least along every direction. It does on a closed, strictly convex surface where a vertex that is
// not the least has an edge going down from it to a corner: every edge must have two triangles
// with the far vertex of each on or below the other's plane (rounding aside), and every vertex
// must be a corner (the triangle normals at it span space) or lie inside a flat face (all its
// triangles in one plane), never on a straight edge between two corners, where the edge between
// them would be lost. A vertex inside a face is never the only least one: its face's corners
// are as low. Last, the descent runs from many vertices along many directions and must find the
// same value as looking at every vertex.
bool build_descent(const TriMesh& mesh, const MeshTopology& topo, std::vector<uint32_t>& offsets,
                   std::vector<uint32_t>& neighbours, std::vector<uint32_t>& start_of) {
    const auto& vs = mesh.vertices;
    const size_t n = vs.size();
    offsets.assign(n + 1, 0);
    neighbours.clear();
    start_of.assign(n, 0);
    const double eps = 1e-13 * mesh_scale(mesh);
    for (const MeshEdge& e : topo.edges) {
        if (e.tri[0] == e.tri[1] || e.tri[0] >= mesh.triangles.size() || e.tri[1] >= mesh.triangles.size()) return false;
        for (int side = 0; side < 2; ++side) {
            const auto& t = mesh.triangles[e.tri[size_t(1 - side)]];
            for (uint32_t w : t)
                if (w != e.v[0] && w != e.v[1] &&
                    glm::dot(topo.triangle_normals[e.tri[size_t(side)]], vs[w] - vs[e.v[0]]) > eps)
                    return false;
        }
    }
    std::vector<char> corner(n, 0);
    for (size_t v = 0; v < n; ++v) {
        const uint32_t b = topo.vertex_triangle_offsets[v], end = topo.vertex_triangle_offsets[v + 1];
        if (b == end) return false;
        bool flat = true;
        for (uint32_t i = b; i < end; ++i) {
            const Vec3& ni = topo.triangle_normals[topo.vertex_triangles[i]];
            flat &= glm::length(ni - topo.triangle_normals[topo.vertex_triangles[b]]) < 1e-9;
            for (uint32_t j = i + 1; j < end && !corner[v]; ++j)
                for (uint32_t k = j + 1; k < end && !corner[v]; ++k) {
                    const Vec3& nj = topo.triangle_normals[topo.vertex_triangles[j]];
                    const Vec3& nk = topo.triangle_normals[topo.vertex_triangles[k]];
                    corner[v] = std::abs(glm::dot(ni, glm::cross(nj, nk))) >= 1e-3;
                }
        }
        if (!corner[v] && !flat) return false;
    }
    for (size_t v = 0; v < n; ++v) {
        offsets[v] = uint32_t(neighbours.size());
        if (!corner[v]) continue;
        for (uint32_t i = topo.vertex_edge_offsets[v]; i < topo.vertex_edge_offsets[v + 1]; ++i) {
            const MeshEdge& e = topo.edges[topo.vertex_edges[i]];
            const uint32_t u = e.v[0] == v ? e.v[1] : e.v[0];
            if (corner[u]) neighbours.push_back(u);
        }
    }
    offsets[n] = uint32_t(neighbours.size());
    // A vertex inside a face starts from the nearest corner along the face's edges.
    for (size_t v = 0; v < n; ++v) {
        if (corner[v]) {
            start_of[v] = uint32_t(v);
            continue;
        }
        std::vector<uint32_t> queue{uint32_t(v)};
        std::vector<char> seen(n, 0);
        seen[v] = 1;
        bool found = false;
        for (size_t q = 0; q < queue.size() && !found; ++q)
            for (uint32_t i = topo.vertex_edge_offsets[queue[q]]; i < topo.vertex_edge_offsets[queue[q] + 1]; ++i) {
                const MeshEdge& e = topo.edges[topo.vertex_edges[i]];
                const uint32_t u = e.v[0] == queue[q] ? e.v[1] : e.v[0];
                if (seen[u]) continue;
                seen[u] = 1;
                if (corner[u]) {
                    start_of[v] = u;
                    found = true;
                    break;
                }
                queue.push_back(u);
            }
        if (!found) return false;
    }
    // Directions spread over the sphere (a Fibonacci lattice), from every vertex or a spread of them.
    const int count = int(n);
    const int stride = std::max(1, count / 64);
    constexpr int kDirections = 400;
    for (int i = 0; i < kDirections; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / kDirections, r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = i * 2.399963229728653;
        const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
        const double least = glm::dot(d, vs[size_t(least_along(vs.data(), count, nullptr, nullptr, nullptr, d, 0))]);
        for (int start = 0; start < count; start += stride)
            if (glm::dot(d, vs[size_t(least_along(vs.data(), count, offsets.data(), neighbours.data(), start_of.data(), d,
                                                  start))]) != least)
                return false;
    }
    return true;
}

// ToolPiece::plane_ratio of a convex piece. A point p outside it has a nearest point q on it
// and p = q + delta u with u in the cone of the normals of the faces through q, so over each
// such face p is delta (n . u); and for any unit d, n . u >= min over those normals of d . n when
// that is positive (u is a blend of the normals). d is the direction of the least point of the
// normals' hull, found by a few hundred steps of Frank-Wolfe: any d gives a true bound, a better
// one a larger bound. The faces through a point inside an edge or a face are among those round
// the edge's vertices, so the least over the vertices holds everywhere.
double plane_ratio(const MeshTopology& topo, size_t vertex_count) {
    double ratio = 1.0;
    for (size_t v = 0; v < vertex_count; ++v) {
        const uint32_t* tris = topo.vertex_triangles.data() + topo.vertex_triangle_offsets[v];
        const int count = int(topo.vertex_triangle_offsets[v + 1] - topo.vertex_triangle_offsets[v]);
        if (count == 0) return 0.0;
        Vec3 x = topo.triangle_normals[tris[0]];
        for (int step = 0; step < 400; ++step) {
            // The normal furthest back along x; the step towards it that brings x nearest the origin.
            int j = 0;
            for (int i = 1; i < count; ++i)
                if (glm::dot(topo.triangle_normals[tris[i]], x) < glm::dot(topo.triangle_normals[tris[j]], x)) j = i;
            const Vec3 s = topo.triangle_normals[tris[j]] - x;
            const double ss = glm::dot(s, s);
            if (!(ss > 0.0)) break;
            const double t = std::clamp(-glm::dot(x, s) / ss, 0.0, 1.0);
            if (t == 0.0) break;
            x += t * s;
        }
        const double len = glm::length(x);
        if (!(len > 0.0)) return 0.0;
        const Vec3 d = x / len;
        double least = 1.0;
        for (int i = 0; i < count; ++i) least = std::min(least, glm::dot(d, topo.triangle_normals[tris[i]]));
        ratio = std::min(ratio, least);
    }
    return std::max(ratio, 0.0);
}

// One convex piece, appended to the tool's arrays.
std::string add_piece(const TriMesh& mesh, size_t index, ModelTool& tool) {
    ToolPiece piece;
    piece.vertex_begin = uint32_t(tool.mesh.vertices.size());
    piece.vertex_count = uint32_t(mesh.vertices.size());
    piece.triangle_begin = uint32_t(tool.mesh.triangles.size());
    piece.triangle_count = uint32_t(mesh.triangles.size());
    piece.face_begin = uint32_t(tool.face_normals.size());
    piece.edge_begin = uint32_t(tool.edges.size());
    const std::string name = "piece " + std::to_string(index) + ": ";
    if (!(mesh_volume(mesh) > 0.0)) return name + "faces point inward (negative volume)";
    const MeshTopology topo = build_topology(mesh);
    const double tol = 1e-9 * mesh_scale(mesh);
    // Distinct face planes: coplanar triangles share one plane.
    std::vector<Vec3> normals;
    std::vector<double> offsets;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3& n = topo.triangle_normals[t];
        const double d = glm::dot(n, mesh.vertices[mesh.triangles[t][0]]);
        bool found = false;
        for (size_t f = 0; f < normals.size(); ++f) {
            if (glm::length(normals[f] - n) < 1e-9 && std::abs(offsets[f] - d) <= tol) {
                found = true;
                break;
            }
        }
        if (!found) {
            normals.push_back(n);
            offsets.push_back(d);
        }
    }
    // Convexity: every vertex on the inner side of every face plane.
    for (size_t f = 0; f < normals.size(); ++f) {
        for (size_t v = 0; v < mesh.vertices.size(); ++v) {
            const double s = glm::dot(normals[f], mesh.vertices[v]) - offsets[f];
            if (s > tol)
                return name + "not convex: vertex " + std::to_string(v) + " lies " + std::to_string(s) +
                       " m outside face plane " + std::to_string(f);
        }
    }
    for (size_t f = 0; f < normals.size(); ++f) {
        double lo = offsets[f];
        for (const Vec3& v : mesh.vertices) lo = std::min(lo, glm::dot(normals[f], v));
        tool.face_normals.push_back(normals[f]);
        tool.face_offsets.push_back(offsets[f]);
        tool.face_depths.push_back(offsets[f] - lo);
    }
    piece.face_count = uint32_t(normals.size());
    for (const MeshEdge& e : topo.edges)
        if (e.convexity != Convexity::Flat) {
            tool.edges.push_back({e.v[0] + piece.vertex_begin, e.v[1] + piece.vertex_begin});
            tool.piece_edges.push_back({e.v[0], e.v[1]});
            tool.edge_normals.push_back({topo.triangle_normals[e.tri[0]], topo.triangle_normals[e.tri[1]]});
            tool.edge_triangles.push_back({e.tri[0], e.tri[1]});
            const Vec3 from = mesh.vertices[e.v[0]], along = mesh.vertices[e.v[1]] - from;
            const double length2 = glm::dot(along, along);
            tool.edge_lines.push_back({from, along, length2 > 0.0 ? 1.0 / length2 : 0.0, length2});
        }
    piece.edge_count = uint32_t(tool.edges.size()) - piece.edge_begin;
    {
        // The edges' boxes, four to a block, and the blocks' boxes, four to a group.
        auto put = [](ToolPiece::BoxLanes& lanes, int lane, const Aabb& b) {
            for (int d = 0; d < 3; ++d) {
                lanes.lo[d][lane] = b.lo[d];
                lanes.hi[d][lane] = b.hi[d];
            }
        };
        const uint32_t blocks = (piece.edge_count + 3) / 4, groups = (blocks + 3) / 4;
        piece.edge_boxes.assign(blocks, ToolPiece::BoxLanes{});
        piece.edge_block_boxes.assign(groups, ToolPiece::BoxLanes{});
        for (uint32_t b = 0; b < 4 * groups; ++b) {
            Aabb block;
            for (uint32_t e = 4 * b; e < 4 * b + 4; ++e) {
                Aabb edge;
                if (e < piece.edge_count) {
                    edge.grow(mesh.vertices[tool.piece_edges[piece.edge_begin + e][0]]);
                    edge.grow(mesh.vertices[tool.piece_edges[piece.edge_begin + e][1]]);
                    block.grow(edge);
                }
                if (b < blocks) put(piece.edge_boxes[b], int(e % 4), edge);
            }
            put(piece.edge_block_boxes[b / 4], int(b % 4), block);
        }
    }
    Aabb box;
    for (const Vec3& v : mesh.vertices) {
        tool.mesh.vertices.push_back(v);
        tool.vertex_piece.push_back(uint8_t(index));
        tool.radius_m = std::max(tool.radius_m, glm::length(v));
        piece.radius_m = std::max(piece.radius_m, glm::length(v));
        box.grow(v);
    }
    piece.centre = box.center();
    for (const Vec3& v : mesh.vertices) piece.spread_m = std::max(piece.spread_m, glm::length(v - piece.centre));
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& t = mesh.triangles[i];
        tool.piece_triangles.push_back(t);
        tool.piece_triangle_normals.push_back(topo.triangle_normals[i]);
        tool.mesh.triangles.push_back({t[0] + piece.vertex_begin, t[1] + piece.vertex_begin, t[2] + piece.vertex_begin});
    }
    set_bounding_capsule(mesh, piece);
    piece.plane_ratio = plane_ratio(topo, mesh.vertices.size());
    {
        std::vector<uint32_t> offsets, neighbours, start_of;
        piece.descend = build_descent(mesh, topo, offsets, neighbours, start_of);
        if (!piece.descend) {
            offsets.assign(mesh.vertices.size() + 1, 0);
            neighbours.clear();
            start_of.assign(mesh.vertices.size(), 0);
        }
        const uint32_t base = uint32_t(tool.neighbours.size());
        for (size_t v = 0; v < mesh.vertices.size(); ++v) tool.neighbour_offsets.push_back(base + offsets[v]);
        tool.neighbours.insert(tool.neighbours.end(), neighbours.begin(), neighbours.end());
        tool.descent_start.insert(tool.descent_start.end(), start_of.begin(), start_of.end());
    }
    {
        std::vector<uint32_t> order(mesh.vertices.size());
        for (uint32_t v = 0; v < order.size(); ++v) order[v] = v;
        auto coord = [&](uint32_t v) { return glm::dot(piece.axis, mesh.vertices[v]); };
        std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return coord(x) < coord(y); });
        for (uint32_t v : order) {
            tool.axial_vertices.push_back(piece.vertex_begin + v);
            tool.axial_coords.push_back(coord(v));
        }
        {
            // The slabs along the axis (ToolPiece::axial_first), from the coordinates the step
            // compares with.
            const double* coords = tool.axial_coords.data() + piece.vertex_begin;
            const size_t n = order.size();
            piece.axial_lo_m = coords[0];
            piece.axial_per_m = coords[n - 1] > coords[0] ? kAxialCells / (coords[n - 1] - coords[0]) : 1.0;
            size_t r = 0;
            for (int i = 0; i <= kAxialCells; ++i) {
                while (r < n && piece.axial_cell(coords[r]) < i) ++r;
                piece.axial_first[size_t(i)] = uint32_t(r);
            }
        }
        if (order.size() <= 64) {
            // The slabs across the axis (ToolPiece::cross_range), their bits by axial order.
            const Vec3 a = piece.axis;
            const Vec3 e = std::abs(a.x) <= std::abs(a.y) && std::abs(a.x) <= std::abs(a.z) ? Vec3(1.0, 0.0, 0.0)
                           : std::abs(a.y) <= std::abs(a.z)                                   ? Vec3(0.0, 1.0, 0.0)
                                                                                              : Vec3(0.0, 0.0, 1.0);
            piece.cross_u = glm::normalize(glm::cross(a, e));
            piece.cross_w = glm::cross(a, piece.cross_u);
            double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
            for (const Vec3& p : mesh.vertices) {
                const double c[2] = {glm::dot(piece.cross_u, p), glm::dot(piece.cross_w, p)};
                for (int k = 0; k < 2; ++k) {
                    lo[k] = std::min(lo[k], c[k]);
                    hi[k] = std::max(hi[k], c[k]);
                }
            }
            for (int k = 0; k < 2; ++k) {
                piece.cross_lo_m[size_t(k)] = lo[k];
                piece.cross_per_m[size_t(k)] = hi[k] > lo[k] ? kCrossCells / (hi[k] - lo[k]) : 1.0;
            }
            piece.cross_cells = kCrossCells;
            piece.cross_narrow_m = 0.25 * std::min(hi[0] - lo[0], hi[1] - lo[1]);
            for (int k = 0; k < 2; ++k) {
                const Vec3 along = k == 0 ? piece.cross_u : piece.cross_w;
                uint64_t slab[kCrossCells] = {};
                for (size_t r = 0; r < order.size(); ++r)
                    slab[piece.cross_cell(k, glm::dot(along, mesh.vertices[order[r]]))] |= uint64_t(1) << r;
                for (int i0 = 0; i0 < kCrossCells; ++i0) {
                    uint64_t m = 0;
                    for (int i1 = i0; i1 < kCrossCells; ++i1) {
                        m |= slab[i1];
                        piece.cross_range[size_t(k)][size_t(i0 * kCrossCells + i1)] = m;
                    }
                }
            }
        }
    }
    tool.pieces.push_back(piece);
    return "";
}

std::string build_tool(const TriMesh& mesh, ModelTool& tool) {
    const std::vector<TriMesh> parts = connected_components(mesh);
    if (parts.size() > size_t(kMaxToolPieces))
        return "has " + std::to_string(parts.size()) + " pieces (connected components); at most " +
               std::to_string(kMaxToolPieces);
    for (size_t i = 0; i < parts.size(); ++i)
        if (std::string err = add_piece(parts[i], i, tool); !err.empty()) return err;
    tool.neighbour_offsets.push_back(uint32_t(tool.neighbours.size()));
    tool.topology = build_topology(tool.mesh);
    return "";
}

// Zones of an object: its own material, then each region's over the triangles it selects.
std::string assign_zones(const SceneObject& so, Model& model, ModelObject& o) {
    auto add_zone = [&](int scene_material, const Vec3& direction) {
        model.zone_material.push_back(uint16_t(scene_material + 1));  // 0 is the default material
        model.zone_direction.push_back(direction);
        return uint16_t(model.zone_material.size() - 1);
    };
    if (model.zone_material.size() + 1 + so.regions.size() > 65535) return "too many material zones (at most 65535)";
    o.zone = add_zone(so.material, Vec3(0.0));
    bool compliant = model.materials[model.zone_material[o.zone]].compliant;
    if (!so.regions.empty()) {
        o.triangle_zone.assign(o.mesh.triangles.size(), o.zone);
        for (const MaterialRegion& reg : so.regions) {
            const uint16_t z = add_zone(reg.material, glm::normalize(reg.normal));
            compliant |= model.materials[model.zone_material[z]].compliant;
            for (size_t t = 0; t < o.mesh.triangles.size(); ++t) {
                const auto& tri = o.mesh.triangles[t];
                // A triangle that reaches into the sphere (a flat floor decimates into large
                // triangles whose centroids may lie far from the site).
                const TriClosest c = closest_on_triangle(reg.center, o.mesh.vertices[tri[0]], o.mesh.vertices[tri[1]],
                                                         o.mesh.vertices[tri[2]]);
                if (c.distance <= reg.radius_m && glm::dot(o.topology.triangle_normals[t], reg.normal) >= reg.min_cos)
                    o.triangle_zone[t] = z;
            }
        }
        // A vertex takes the zone of its first triangle (in the adjacency's order).
        o.vertex_zone.assign(o.mesh.vertices.size(), o.zone);
        for (size_t v = 0; v < o.mesh.vertices.size(); ++v) {
            const uint32_t a = o.topology.vertex_triangle_offsets[v];
            if (a < o.topology.vertex_triangle_offsets[v + 1]) o.vertex_zone[v] = o.triangle_zone[o.topology.vertex_triangles[a]];
        }
    }
    o.compliant = compliant;
    return "";
}

}  // namespace

double material_depth(const ModelMaterial& m, double force_N) {
    if (!m.compliant || !(force_N > 0.0)) return 0.0;
    double depth = 0.0;
    for (int j = 0; j < m.springs; ++j) depth += std::min(force_N / m.stiffness_N_per_m[j], m.cap_m[j]);
    return depth;
}

ModelBuild build_model(const SceneFile& scene, RendererSettings settings) {
    settings.haptic = scene.haptic;
    return build_model(scene.tool.mesh, scene.objects, settings, scene.materials);
}

std::string material_from_curve(const ContactMaterial& in, ModelMaterial& out) {
    out = ModelMaterial{};
    out.friction_static = in.friction_static;
    out.friction_kinetic = in.friction_kinetic;
    out.compliant = in.compliant;
    if (!in.compliant) return "";
    const auto& pts = in.yield_curve;
    if (pts.empty() || pts.size() > size_t(kMaxMaterialSprings)) return "a yield curve needs 1 to 7 points past the origin";
    // Segment compliances (m/N), never increasing along a stiffening curve.
    double c[kMaxMaterialSprings];
    double f0 = 0.0, d0 = 0.0;
    for (size_t j = 0; j < pts.size(); ++j) {
        const double df = pts[j][0] - f0, dd = pts[j][1] - d0;
        if (!(df > 0.0) || !(dd > 0.0) || !std::isfinite(df) || !std::isfinite(dd))
            return "force and depth must both increase along the yield curve";
        c[j] = dd / df;
        if (j > 0 && c[j] > c[j - 1] * (1.0 + 1e-12)) return "the yield curve softens; it must stiffen or stay linear";
        f0 = pts[j][0];
        d0 = pts[j][1];
    }
    // Spring j carries the compliance the curve loses at point j and bottoms out at its force.
    const int n = int(pts.size());
    for (int j = 0; j < n; ++j) {
        const double cj = j + 1 < n ? c[j] - c[j + 1] : c[j];
        if (!(cj > 0.0)) continue;  // the curve goes on straight here: no spring
        out.stiffness_N_per_m[out.springs] = 1.0 / cj;
        out.cap_m[out.springs] = j + 1 < n ? cj * pts[size_t(j)][0] : std::numeric_limits<double>::infinity();
        ++out.springs;
    }
    return "";
}

ModelBuild build_model(const TriMesh& tool_mesh, const std::vector<SceneObject>& objects,
                       const RendererSettings& settings, const std::vector<ContactMaterial>& materials) {
    ModelBuild out;
    if (std::string err = validate_mesh(tool_mesh); !err.empty()) {
        out.error = "tool: " + err;
        return out;
    }
    auto model = std::make_unique<Model>();
    model->settings = settings;
    static std::atomic<uint64_t> serials{0};
    model->serial = ++serials;
    if (std::string err = build_tool(tool_mesh, model->tool); !err.empty()) {
        out.error = "tool: " + err;
        return out;
    }
    if (objects.size() > 65535) {
        out.error = "too many objects (at most 65535)";
        return out;
    }
    model->materials.push_back(ModelMaterial{});
    for (const ContactMaterial& cm : materials) {
        ModelMaterial m;
        if (std::string err = material_from_curve(cm, m); !err.empty()) {
            out.error = "material " + cm.name + ": " + err;
            return out;
        }
        model->materials.push_back(m);
    }
    for (const SceneObject& so : objects) {
        if (std::string err = validate_mesh(so.mesh); !err.empty()) {
            out.error = so.name + ": " + err;
            return out;
        }
        ModelObject o;
        o.name = so.name;
        o.pose = so.pose;
        o.mesh = so.mesh;
        for (Vec3& v : o.mesh.vertices) v = so.pose.apply(v);
        o.topology = build_topology(o.mesh);
        o.bvh = Bvh(o.mesh);
        if (so.material < -1 || so.material >= int(materials.size())) {
            out.error = so.name + ": material index " + std::to_string(so.material) + " out of range";
            return out;
        }
        for (const MaterialRegion& reg : so.regions)
            if (reg.material < 0 || reg.material >= int(materials.size())) {
                out.error = so.name + ": region " + reg.name + ": material index out of range";
                return out;
            }
        if (std::string err = assign_zones(so, *model, o); !err.empty()) {
            out.error = so.name + ": " + err;
            return out;
        }
        model->objects.push_back(std::move(o));
    }
    // Only what zones use counts: a material no object takes costs nothing.
    for (uint16_t m : model->zone_material) {
        model->any_compliant |= model->materials[m].compliant;
        model->any_friction |= model->materials[m].friction_static > 0.0;
    }
    out.model = std::move(model);
    return out;
}

}  // namespace sulcus
