// Adjacency of a validated mesh: undirected edges with their two triangles, triangle neighbours,
// outward normals, vertex stars, and the convex/concave classification of edges and vertices.
// Everything is built by sorting, so the result depends only on the mesh.
#include "mesh_edges.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace sulcus {
namespace {

// CSR layout from (key, value) pairs listed in ascending value order; the counting sort is
// stable, so each key's values stay ascending.
void build_csr(size_t keys, const std::vector<std::pair<uint32_t, uint32_t>>& pairs, std::vector<uint32_t>& offsets,
               std::vector<uint32_t>& values) {
    offsets.assign(keys + 1, 0);
    for (const auto& p : pairs) ++offsets[p.first + 1];
    for (size_t i = 0; i < keys; ++i) offsets[i + 1] += offsets[i];
    values.resize(pairs.size());
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (const auto& p : pairs) values[fill[p.first]++] = p.second;
}

}  // namespace

MeshTopology build_topology(const TriMesh& mesh) {
    MeshTopology topo;
    const size_t nt = mesh.triangles.size();
    const size_t nv = mesh.vertices.size();

    topo.triangle_normals.resize(nt);
    topo.triangle_spheres.resize(nt);
    for (size_t t = 0; t < nt; ++t) {
        const auto& tri = mesh.triangles[t];
        const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
        topo.triangle_normals[t] = glm::normalize(glm::cross(b - a, c - a));
        topo.triangle_spheres[t] = triangle_sphere(a, b, c);
    }

    const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);

    topo.triangle_edges.assign(nt, {0, 0, 0});
    topo.triangle_neighbours.assign(nt, {0, 0, 0});
    topo.edges.reserve(uses.size() / 2);
    for (size_t i = 0; i + 1 < uses.size(); i += 2) {
        const EdgeUse& p = uses[i];
        const EdgeUse& q = uses[i + 1];
        assert(p.lo == q.lo && p.hi == q.hi && "build_topology needs a mesh that passed validate_mesh");
        const bool p_up = p.runs_up(mesh);
        MeshEdge e;
        e.v = {p.lo, p.hi};
        e.tri = p_up ? std::array<uint32_t, 2>{p.tri, q.tri} : std::array<uint32_t, 2>{q.tri, p.tri};
        const uint32_t index = uint32_t(topo.edges.size());
        topo.triangle_edges[p.tri][p.k] = index;
        topo.triangle_edges[q.tri][q.k] = index;
        topo.triangle_neighbours[p.tri][p.k] = q.tri;
        topo.triangle_neighbours[q.tri][q.k] = p.tri;

        // Signed bend angle from the normal of tri[0] to the normal of tri[1] about the edge
        // direction v0 -> v1 (as it runs in tri[0]): positive where the surface folds away from
        // its outward side, i.e. the far vertex of tri[1] lies behind the plane of tri[0].
        const Vec3& n0 = topo.triangle_normals[e.tri[0]];
        const Vec3& n1 = topo.triangle_normals[e.tri[1]];
        const Vec3 dir = glm::normalize(mesh.vertices[e.v[1]] - mesh.vertices[e.v[0]]);
        const double angle = std::atan2(glm::dot(glm::cross(n0, n1), dir), glm::dot(n0, n1));
        if (std::abs(angle) < kFlatEdgeAngle) {
            e.convexity = Convexity::Flat;
            e.dihedral = 0.0;
        } else {
            e.convexity = angle > 0.0 ? Convexity::Convex : Convexity::Concave;
            e.dihedral = angle;
        }
        topo.edges.push_back(e);
    }

    // Vertex stars, each list ascending (pairs are generated in ascending triangle / edge order).
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    pairs.reserve(3 * nt);
    for (size_t t = 0; t < nt; ++t)
        for (uint32_t v : mesh.triangles[t]) pairs.push_back({v, uint32_t(t)});
    build_csr(nv, pairs, topo.vertex_triangle_offsets, topo.vertex_triangles);

    pairs.clear();
    for (size_t e = 0; e < topo.edges.size(); ++e) {
        pairs.push_back({topo.edges[e].v[0], uint32_t(e)});
        pairs.push_back({topo.edges[e].v[1], uint32_t(e)});
    }
    build_csr(nv, pairs, topo.vertex_edge_offsets, topo.vertex_edges);

    topo.vertex_convexity.assign(nv, Convexity::Flat);
    for (size_t v = 0; v < nv; ++v) {
        bool convex = false, concave = false;
        for (uint32_t i = topo.vertex_edge_offsets[v]; i < topo.vertex_edge_offsets[v + 1]; ++i) {
            const Convexity c = topo.edges[topo.vertex_edges[i]].convexity;
            convex |= c == Convexity::Convex;
            concave |= c == Convexity::Concave;
        }
        topo.vertex_convexity[v] = convex && concave ? Convexity::Mixed
                                   : convex          ? Convexity::Convex
                                   : concave         ? Convexity::Concave
                                                     : Convexity::Flat;
    }
    topo.triangle_corners.assign(nt, 0);
    for (size_t t = 0; t < nt; ++t) {
        uint8_t bits = 0;
        for (int k = 0; k < 3; ++k) {
            const Convexity cv = topo.vertex_convexity[mesh.triangles[t][size_t(k)]];
            if (cv == Convexity::Convex || cv == Convexity::Mixed) bits |= uint8_t(1u << k);
            if (topo.edges[topo.triangle_edges[t][size_t(k)]].convexity == Convexity::Convex)
                bits |= uint8_t(1u << (3 + k));
        }
        topo.triangle_corners[t] = bits;
    }
    return topo;
}

std::vector<TriMesh> connected_components(const TriMesh& mesh) {
    const size_t nv = mesh.vertices.size();
    std::vector<uint32_t> parent(nv);
    for (size_t v = 0; v < nv; ++v) parent[v] = uint32_t(v);
    auto find = [&](uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    for (const auto& t : mesh.triangles) {
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
        parent[find(t[1])] = find(t[0]);
        parent[find(t[2])] = find(t[0]);
    }
    std::vector<TriMesh> out;
    std::vector<int> component(nv, -1);  // by root vertex
    std::vector<uint32_t> local(nv, UINT32_MAX);
    for (const auto& t : mesh.triangles) {
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
        const uint32_t root = find(t[0]);
        if (component[root] < 0) {
            component[root] = int(out.size());
            out.emplace_back();
        }
        TriMesh& m = out[size_t(component[root])];
        std::array<uint32_t, 3> tri{};
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = t[size_t(k)];
            if (local[v] == UINT32_MAX) {
                local[v] = uint32_t(m.vertices.size());
                m.vertices.push_back(mesh.vertices[v]);
            }
            tri[size_t(k)] = local[v];
        }
        m.triangles.push_back(tri);
    }
    return out;
}

}  // namespace sulcus
