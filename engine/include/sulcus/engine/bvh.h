// Bounding-volume hierarchy over the triangles of one mesh (axis-aligned boxes, in the mesh's
// own frame). Built once with the model; queries never allocate: they report into a
// caller-provided collector.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <cstdint>
#include <limits>
#include <vector>

namespace sulcus {

struct CapsuleChainWalk;

class Bvh {
public:
    struct Node {
        Aabb box;
        uint32_t first = 0;  // leaf: first index into order(); inner: index of the left child
        uint32_t count = 0;  // leaf: number of triangles (> 0); inner: 0 (right child = left + 1)
    };

    Bvh() = default;
    explicit Bvh(const TriMesh& mesh, int max_leaf_size = 4);

    // Calls visit(triangle_index) for every triangle whose box overlaps `query`. Stops early and
    // returns false when visit returns false. Allocation-free (fixed-depth stack).
    template <class Visit>
    bool query(const Aabb& query, Visit&& visit) const;

    // The same walk, calling visit(slot) with each triangle's slot: its place in order(), whose
    // box is slot_box(slot). The slots come in increasing order, and every node's box holds its
    // triangles' boxes: so the query of a box inside `query` is this one's slots whose boxes
    // overlap it, in the same order (what a set of triangles kept between queries relies on).
    template <class Visit>
    bool query_slots(const Aabb& query, Visit&& visit) const;
    const Aabb& slot_box(uint32_t slot) const { return boxes_[slot]; }

    // Calls visit(triangle_index) for the triangles that may lie within radii[k] + extra of
    // segment points[k]-points[k + 1] for some k < count (a chain of capsules, count <= 16): every
    // such triangle is visited, once (a box is passed over only when its bounding sphere is
    // clear of every capsule, or it misses the box around them all); some farther ones may be too.
    // Allocation-free; stops early when visit returns false.
    template <class Visit>
    bool query_capsule_chain(const Vec3* points, const double* radii, int count, double extra, Visit&& visit) const;

    // The same walk in pieces: goes on with `walk` (CapsuleChainWalk::start sets its chain)
    // until `budget` (decreased by one per box and per triangle looked at) runs out, or to its
    // end; true when the walk is over (every triangle visited, or visit returned false).
    template <class Visit>
    bool walk_capsule_chain(CapsuleChainWalk& walk, long& budget, Visit&& visit) const;

    const std::vector<Node>& nodes() const { return nodes_; }
    const std::vector<uint32_t>& order() const { return order_; }
    int depth() const { return depth_; }

private:
    std::vector<Node> nodes_;
    std::vector<uint32_t> order_;  // triangle indices, grouped by leaf
    std::vector<Aabb> boxes_;      // box of triangle order_[i] at i, so leaves report exactly
    int depth_ = 0;
};

inline constexpr int kBvhMaxDepth = 64;

namespace bvh_detail {
// Whether a box may hold points within `radius` of segment p0 + t d (t in [0, 1], dd = d . d):
// false only when the sphere around the box is clear of that capsule.
inline bool box_near_segment(const Aabb& b, const Vec3& p0, const Vec3& d, double dd, double radius) {
    const Vec3 c = b.center();
    const Vec3 h = 0.5 * (b.hi - b.lo);
    const Vec3 w = c - p0;
    const double t = dd > 0.0 ? glm::clamp(glm::dot(w, d) / dd, 0.0, 1.0) : 0.0;
    const Vec3 off = w - t * d;
    const double reach = radius + glm::length(h);
    return glm::dot(off, off) <= reach * reach;
}
}  // namespace bvh_detail

template <class Visit>
bool Bvh::query(const Aabb& q, Visit&& visit) const {
    return query_slots(q, [&](uint32_t slot) { return visit(order_[slot]); });
}

template <class Visit>
bool Bvh::query_slots(const Aabb& q, Visit&& visit) const {
    if (nodes_.empty()) return true;
    uint32_t stack[kBvhMaxDepth + 2];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = nodes_[stack[--top]];
        if (!n.box.overlaps(q)) continue;
        if (n.count > 0) {
            for (uint32_t i = n.first; i < n.first + n.count; ++i)
                if (boxes_[i].overlaps(q) && !visit(i)) return false;
        } else {
            stack[top++] = n.first + 1;
            stack[top++] = n.first;
        }
    }
    return true;
}

// A walk of the triangles near a chain of capsules (as query_capsule_chain) that can stop after
// a budget of work and go on later: what a search spread over several servo ticks needs.
struct CapsuleChainWalk {
    static constexpr int kMaxChain = 16;
    int count = 0;
    Vec3 points[kMaxChain + 1];
    Vec3 d[kMaxChain];
    double dd[kMaxChain] = {}, r[kMaxChain] = {};
    Aabb q;
    uint32_t stack[kBvhMaxDepth + 2] = {};
    int top = 0;

    void start(const Vec3* chain, const double* radii, int chain_count, double extra) {
        count = chain_count < kMaxChain ? chain_count : kMaxChain;
        q = Aabb{};
        for (int k = 0; k <= count; ++k) points[k] = chain[k];
        for (int k = 0; k < count; ++k) {
            r[k] = radii[k] + extra;
            Aabb c;
            c.grow(points[k]);
            c.grow(points[k + 1]);
            c.inflate(r[k]);
            q.grow(c.lo);
            q.grow(c.hi);
            d[k] = points[k + 1] - points[k];
            dd[k] = glm::dot(d[k], d[k]);
        }
        top = 0;
        stack[top++] = 0;
    }
    bool near_any(const Aabb& b) const {
        for (int k = 0; k < count; ++k)
            if (bvh_detail::box_near_segment(b, points[k], d[k], dd[k], r[k])) return true;
        return false;
    }
};

template <class Visit>
bool Bvh::walk_capsule_chain(CapsuleChainWalk& w, long& budget, Visit&& visit) const {
    if (nodes_.empty() || w.count <= 0) {
        w.top = 0;
        return true;
    }
    while (w.top > 0) {
        if (budget <= 0) return false;
        --budget;
        const Node& n = nodes_[w.stack[--w.top]];
        if (!n.box.overlaps(w.q) || !w.near_any(n.box)) continue;
        if (n.count > 0) {
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                if (!boxes_[i].overlaps(w.q) || !w.near_any(boxes_[i])) continue;
                --budget;
                if (!visit(order_[i])) {
                    w.top = 0;
                    return true;
                }
            }
        } else {
            w.stack[w.top++] = n.first + 1;
            w.stack[w.top++] = n.first;
        }
    }
    return true;
}

template <class Visit>
bool Bvh::query_capsule_chain(const Vec3* points, const double* radii, int count, double extra, Visit&& visit) const {
    if (nodes_.empty() || count <= 0) return true;
    CapsuleChainWalk w;
    w.start(points, radii, count, extra);
    bool stopped = false;
    long budget = std::numeric_limits<long>::max();
    walk_capsule_chain(w, budget, [&](uint32_t tri) {
        if (visit(tri)) return true;
        stopped = true;
        return false;
    });
    return !stopped;
}

}  // namespace sulcus
