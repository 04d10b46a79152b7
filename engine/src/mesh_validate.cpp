// Validation of a triangle mesh as the boundary of a solid: the checks run from the cheapest and
// most basic (coordinates, indices) to the global ones (edges, vertex fans, volume), and the first
// fault found is reported with the triangle or vertex it concerns.
#include "mesh_edges.h"
#include "mesh_fault.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace sulcus {
namespace {

// Area below this fraction of the squared bounding-box diagonal counts as zero: about 1e4 times
// the rounding noise of a cross product of double coordinates, far below any real feature.
constexpr double kDegenerateAreaFraction = 1e-12;

std::string format(const char* fmt, auto... args) {
    char buf[256];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

MeshFault check_coordinates_and_indices(const TriMesh& mesh) {
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vec3& p = mesh.vertices[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return {format("vertex %zu: non-finite coordinate (%g, %g, %g)", i, p.x, p.y, p.z), -1, int64_t(i)};
    }
    const size_t n = mesh.vertices.size();
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint32_t v : mesh.triangles[t])
            if (v >= n)
                return {format("triangle %zu: vertex index %u out of range (%zu vertices)", t, v, n), int64_t(t)};
    return {};
}

MeshFault check_degenerate(const TriMesh& mesh) {
    Aabb box;
    for (const Vec3& p : mesh.vertices) box.grow(p);
    const double diag2 = glm::dot(box.hi - box.lo, box.hi - box.lo);
    const double min_double_area = 2.0 * kDegenerateAreaFraction * diag2;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        for (int k = 0; k < 3; ++k)
            if (tri[k] == tri[(k + 1) % 3])
                return {format("triangle %zu: degenerate (vertex %u used twice)", t, tri[k]), int64_t(t)};
        const Vec3& a = mesh.vertices[tri[0]];
        const double double_area = glm::length(glm::cross(mesh.vertices[tri[1]] - a, mesh.vertices[tri[2]] - a));
        if (!(double_area > min_double_area))
            return {format("triangle %zu: degenerate (zero area, vertices %u %u %u collinear or coincident)", t,
                           tri[0], tri[1], tri[2]),
                    int64_t(t)};
    }
    return {};
}

MeshFault check_duplicates(const TriMesh& mesh) {
    // Sorted vertex triples bucketed by their smallest vertex, then compared inside each bucket.
    const size_t nv = mesh.vertices.size();
    std::vector<uint32_t> start(nv + 1, 0);
    for (const auto& tri : mesh.triangles) ++start[std::min({tri[0], tri[1], tri[2]}) + 1];
    for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<std::array<uint32_t, 3>> keys(mesh.triangles.size());  // (mid, max, triangle)
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        auto s = mesh.triangles[t];
        std::sort(s.begin(), s.end());
        keys[fill[s[0]]++] = {s[1], s[2], uint32_t(t)};
    }
    // Report the duplicate with the lowest triangle index, against the first of its group.
    int64_t best = -1, original = -1;
    for (size_t v = 0; v < nv; ++v) {
        const auto first = keys.begin() + start[v], last = keys.begin() + start[v + 1];
        std::sort(first, last);
        for (auto it = first; it != last;) {
            auto end = it + 1;
            while (end != last && (*end)[0] == (*it)[0] && (*end)[1] == (*it)[1]) ++end;
            if (end - it > 1 && (best < 0 || (*(it + 1))[2] < best)) {
                best = (*(it + 1))[2];
                original = (*it)[2];
            }
            it = end;
        }
    }
    if (best >= 0)
        return {format("triangle %lld: duplicate of triangle %lld (same vertices)", (long long)best,
                       (long long)original),
                best};
    return {};
}

// Every undirected edge must be used by exactly two triangles, once in each direction.
MeshFault check_edges(const TriMesh& mesh) {
    const size_t nt = mesh.triangles.size();
    const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);

    enum Kind : uint8_t { Ok, Open, NonManifold, Inconsistent };
    struct Status {
        Kind kind = Ok;
        uint32_t count = 0;
        uint32_t partner = 0;
    };
    std::vector<std::array<Status, 3>> status(nt);
    std::vector<uint8_t> inconsistent_count(nt, 0);
    for (size_t i = 0; i < uses.size();) {
        size_t j = i;
        while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
        const uint32_t count = uint32_t(j - i);
        for (size_t u = i; u < j; ++u) {
            Status& s = status[uses[u].tri][uses[u].k];
            s.count = count;
            if (count == 1) s.kind = Open;
            else if (count > 2) s.kind = NonManifold;
        }
        if (count == 2) {
            const EdgeUse& p = uses[i];
            const EdgeUse& q = uses[i + 1];
            if (p.runs_up(mesh) == q.runs_up(mesh)) {
                status[p.tri][p.k] = {Inconsistent, 2, q.tri};
                status[q.tri][q.k] = {Inconsistent, 2, p.tri};
                ++inconsistent_count[p.tri];
                ++inconsistent_count[q.tri];
            }
        }
        i = j;
    }

    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const Status& s = status[t][k];
            const uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
            switch (s.kind) {
            case Ok: break;
            case Open: return {format("triangle %zu: open boundary at edge (%u,%u)", t, a, b), int64_t(t)};
            case NonManifold:
                return {format("triangle %zu: non-manifold edge (%u,%u) shared by %u triangles", t, a, b, s.count),
                        int64_t(t)};
            case Inconsistent: {
                // Name the triangle that disagrees with more of its neighbours: a single flipped
                // triangle disagrees on all three edges, its neighbours on one each.
                size_t bad = t, other = s.partner;
                if (inconsistent_count[other] > inconsistent_count[t]) std::swap(bad, other);
                return {format("triangle %zu: inconsistent orientation at edge (%u,%u): triangle %zu runs the "
                               "same way (one of them is flipped)",
                               bad, a, b, other),
                        int64_t(bad)};
            }
            }
        }
    return {};
}

// With manifold, consistently oriented edges, the triangles around a vertex form one or more
// closed fans; a manifold vertex has exactly one.
MeshFault check_vertex_fans(const TriMesh& mesh) {
    const size_t nv = mesh.vertices.size();
    std::vector<uint32_t> offsets(nv + 1, 0);
    for (const auto& tri : mesh.triangles)
        for (uint32_t v : tri) ++offsets[v + 1];
    for (size_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
    // For each corner: the vertex after and before the fan's centre in that triangle.
    struct Corner {
        uint32_t prev, next;
    };
    std::vector<Corner> corners(offsets[nv]);
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (const auto& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k) corners[fill[tri[k]]++] = {tri[(k + 2) % 3], tri[(k + 1) % 3]};

    std::vector<Corner> fan;
    std::vector<bool> seen;
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t n = offsets[v + 1] - offsets[v];
        if (n == 0) continue;
        fan.assign(corners.begin() + offsets[v], corners.begin() + offsets[v + 1]);
        // Sorted by prev, so the corner following c around v (the one whose prev is c.next)
        // is found by binary search; edges are manifold, so it is unique.
        std::sort(fan.begin(), fan.end(), [](const Corner& a, const Corner& b) { return a.prev < b.prev; });
        seen.assign(n, false);
        uint32_t fans = 0;
        for (uint32_t start = 0; start < n; ++start) {
            if (seen[start]) continue;
            ++fans;
            uint32_t c = start;
            while (!seen[c]) {
                seen[c] = true;
                auto it = std::lower_bound(fan.begin(), fan.end(), fan[c].next,
                                           [](const Corner& a, uint32_t key) { return a.prev < key; });
                if (it == fan.end() || it->prev != fan[c].next) break;  // cannot happen after check_edges
                c = uint32_t(it - fan.begin());
            }
        }
        if (fans > 1)
            return {format("vertex %zu: non-manifold vertex (its %u triangles form %u separate fans)", v, n, fans),
                    -1, int64_t(v)};
    }
    return {};
}

}  // namespace

MeshFault find_mesh_fault(const TriMesh& mesh) {
    if (mesh.triangles.empty()) return {"empty mesh (no triangles)"};
    MeshFault f = check_coordinates_and_indices(mesh);
    if (f.what.empty()) f = check_degenerate(mesh);
    if (f.what.empty()) f = check_duplicates(mesh);
    if (f.what.empty()) f = check_edges(mesh);
    if (f.what.empty()) f = check_vertex_fans(mesh);
    if (!f.what.empty()) return f;
    const double volume = mesh_volume(mesh);
    if (!(volume > 0.0))
        return {volume < 0.0 ? format("inside out: negative enclosed volume (%g m^3)", volume)
                             : std::string("zero enclosed volume")};
    return {};
}

std::string validate_mesh(const TriMesh& mesh) { return find_mesh_fault(mesh).what; }

double mesh_volume(const TriMesh& mesh) {
    if (mesh.vertices.empty()) return 0.0;
    // Relative to one vertex, so the cancelling terms stay small for meshes far from the origin.
    const Vec3 o = mesh.vertices[0];
    const size_t n = mesh.vertices.size();
    double six_v = 0.0;
    for (const auto& tri : mesh.triangles) {
        if (tri[0] >= n || tri[1] >= n || tri[2] >= n) continue;
        const Vec3 a = mesh.vertices[tri[0]] - o, b = mesh.vertices[tri[1]] - o, c = mesh.vertices[tri[2]] - o;
        six_v += glm::dot(a, glm::cross(b, c));
    }
    return six_v / 6.0;
}

}  // namespace sulcus
