// The edges of a triangle mesh as a sorted list of edge uses, shared by validation and topology.
// Built by a counting sort on the lower vertex and a small sort inside each vertex's bucket:
// linear in the mesh size, and the order depends only on the mesh.
#pragma once

#include "sulcus/engine/mesh.h"

#include <algorithm>
#include <vector>

namespace sulcus {

// Edge k of triangle tri runs tri[k] -> tri[(k + 1) % 3]; lo < hi is its undirected key.
struct EdgeUse {
    uint32_t lo, hi, tri;
    uint8_t k;
    bool runs_up(const TriMesh& mesh) const { return mesh.triangles[tri][k] == lo; }
};

// All 3 * triangles edge uses, sorted by (lo, hi, tri, k), so the uses of one undirected edge
// are adjacent. Indices must be in range.
inline std::vector<EdgeUse> sorted_edge_uses(const TriMesh& mesh) {
    const size_t nv = mesh.vertices.size();
    std::vector<uint32_t> start(nv + 1, 0);
    for (const auto& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++start[std::min(tri[k], tri[(k + 1) % 3]) + 1];
    for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<EdgeUse> uses(3 * mesh.triangles.size());
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint8_t k = 0; k < 3; ++k) {
            const uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
            const uint32_t lo = std::min(a, b);
            uses[fill[lo]++] = {lo, std::max(a, b), uint32_t(t), k};
        }
    // Inside a bucket the uses are already in (tri, k) order; a stable sort by hi keeps it.
    for (size_t v = 0; v < nv; ++v)
        std::stable_sort(uses.begin() + start[v], uses.begin() + start[v + 1],
                         [](const EdgeUse& p, const EdgeUse& q) { return p.hi < q.hi; });
    return uses;
}

}  // namespace sulcus
