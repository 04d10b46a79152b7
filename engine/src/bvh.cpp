// Top-down construction of the triangle BVH: median split along the longest axis of the
// centroid box. The median split halves the triangle count at every level, so the depth is
// about log2(n / max_leaf_size) + 1 whatever the geometry (coincident or flat triangles included).
#include "sulcus/engine/bvh.h"

#include <algorithm>
#include <cassert>

namespace sulcus {

namespace {

struct BuildItem {
    uint32_t node;
    uint32_t begin, end;  // range of order_
    int level;            // 1 for the root
};

int longest_axis(const Aabb& b) {
    const Vec3 e = b.hi - b.lo;
    if (e.x >= e.y && e.x >= e.z) return 0;
    return e.y >= e.z ? 1 : 2;
}

}  // namespace

Bvh::Bvh(const TriMesh& mesh, int max_leaf_size) {
    const size_t n = mesh.triangles.size();
    if (n == 0) return;
    assert(n < size_t(UINT32_MAX));
    const uint32_t leaf_size = max_leaf_size < 1 ? 1u : uint32_t(max_leaf_size);

    // Centroids travel with their triangle index in one contiguous array: the partitioning
    // below then streams through memory instead of chasing indices.
    struct Item {
        Vec3 c;
        uint32_t t;
    };
    std::vector<Aabb> boxes(n);
    std::vector<Item> items(n);
    for (size_t t = 0; t < n; ++t) {
        Aabb b;
        for (uint32_t v : mesh.triangles[t]) b.grow(mesh.vertices[v]);
        boxes[t] = b;
        items[t] = {b.center(), uint32_t(t)};
    }

    // Every split leaves at least ceil(leaf_size / 2) triangles on each side, which bounds the
    // leaf count; a full binary tree has 2 * leaves - 1 nodes.
    const size_t min_leaf = (leaf_size + 1) / 2;
    nodes_.reserve(2 * ((n + min_leaf - 1) / min_leaf));
    nodes_.push_back(Node{});
    std::vector<BuildItem> work;
    work.reserve(2 * kBvhMaxDepth + 4);
    work.push_back({0, 0, uint32_t(n), 1});
    while (!work.empty()) {
        const BuildItem item = work.back();
        work.pop_back();
        depth_ = std::max(depth_, item.level);
        const uint32_t count = item.end - item.begin;
        if (count <= leaf_size) {
            nodes_[item.node].first = item.begin;
            nodes_[item.node].count = count;
            continue;
        }
        Aabb cbox;
        for (uint32_t i = item.begin; i < item.end; ++i) cbox.grow(items[i].c);
        const int axis = longest_axis(cbox);
        const uint32_t mid = item.begin + count / 2;
        // Ties on the centroid coordinate are broken by triangle index: a strict total order,
        // so the two halves (and the tree) do not depend on the input permutation's accidents.
        std::nth_element(items.begin() + item.begin, items.begin() + mid, items.begin() + item.end,
                         [axis](const Item& a, const Item& b) {
                             const double ca = a.c[axis], cb = b.c[axis];
                             return ca < cb || (ca == cb && a.t < b.t);
                         });
        const uint32_t left = uint32_t(nodes_.size());
        nodes_.push_back(Node{});
        nodes_.push_back(Node{});
        nodes_[item.node].first = left;
        nodes_[item.node].count = 0;
        work.push_back({left + 1, mid, item.end, item.level + 1});
        work.push_back({left, item.begin, mid, item.level + 1});
    }
    nodes_.shrink_to_fit();
    order_.resize(n);
    boxes_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        order_[i] = items[i].t;
        boxes_[i] = boxes[items[i].t];
    }
    // Boxes bottom-up: children always come after their parent in nodes_.
    for (size_t k = nodes_.size(); k-- > 0;) {
        Node& nd = nodes_[k];
        Aabb b;
        if (nd.count > 0) {
            for (uint32_t i = nd.first; i < nd.first + nd.count; ++i) b.grow(boxes_[i]);
        } else {
            b.grow(nodes_[nd.first].box);
            b.grow(nodes_[nd.first + 1].box);
        }
        nd.box = b;
    }
    // The query's fixed stack holds at most one entry per level plus one.
    assert(depth_ <= kBvhMaxDepth);
}

}  // namespace sulcus
