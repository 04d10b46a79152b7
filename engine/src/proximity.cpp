// Tool-against-scene distance and overlap queries. Each object's BVH is walked depth first, the
// nearer child first, with a fixed stack; a node is skipped when a lower bound on its distance
// from the tool (from each piece's world box and bounding capsules) is no less than the best
// distance so far, so the search box shrinks as the best distance falls. Triangles that survive
// go to the exact tests of geometry.h.
#include "sulcus/engine/proximity.h"

#include "geometry.h"
#include "tool_placement.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace sulcus {

namespace {

// The tool placed at the query's pose, with cheap bounds per piece.
struct Scratch {
    // Sized to the largest tool seen on this thread: allocation only when a larger tool comes.
    std::vector<Vec3> vertices, normals;
    std::vector<double> offsets;
    Vec3 capsule[kMaxToolPieces * (kToolCapsules + 1)];
    Quat rotation{1.0, 0.0, 0.0, 0.0};
    Aabb piece_box[kMaxToolPieces];                    // world box of each piece's vertices
    Aabb segment_box[kMaxToolPieces][kToolCapsules];   // world box of each capsule's axis segment
    double radius[kMaxToolPieces][kToolCapsules] = {};
    int capsules[kMaxToolPieces] = {};
    int pieces = 0;
    Aabb tool_box;
};

Scratch& scratch() {
    thread_local std::unique_ptr<Scratch> s = std::make_unique<Scratch>();
    return *s;
}

// Unit to rounding is kept as given (as the step does), so results do not depend on a
// renormalization the caller did not ask for.
Quat unit(const Quat& q) {
    const double n = glm::length(q);
    return std::abs(n - 1.0) > 1e-12 ? q / n : q;
}

void place(const Model& model, const Pose& pose, Scratch& s) {
    const ModelTool& tool = model.tool;
    const Quat q = unit(pose.orientation);
    const Vec3& p = pose.position;
    if (s.vertices.size() < tool.mesh.vertices.size()) s.vertices.resize(tool.mesh.vertices.size());
    if (s.normals.size() < tool.face_normals.size()) {
        s.normals.resize(tool.face_normals.size());
        s.offsets.resize(tool.face_normals.size());
    }
    place_tool_vertices(tool, q, p, s.vertices.data());
    place_tool_planes(tool, q, p, s.normals.data(), s.offsets.data());
    place_tool_capsule(tool, q, p, s.capsule);
    s.rotation = q;
    s.pieces = static_cast<int>(std::min(tool.pieces.size(), size_t(kMaxToolPieces)));
    s.tool_box = Aabb{};
    for (int k = 0; k < s.pieces; ++k) {
        const ToolPiece& piece = tool.pieces[size_t(k)];
        Aabb b;
        for (uint32_t v = piece.vertex_begin; v < piece.vertex_begin + piece.vertex_count; ++v) b.grow(s.vertices[v]);
        s.piece_box[k] = b;
        s.tool_box.grow(b);
        s.capsules[k] = std::min(piece.capsule_count, kToolCapsules);
        const Vec3* axis = s.capsule + size_t(k) * (kToolCapsules + 1);
        for (int j = 0; j < s.capsules[k]; ++j) {
            Aabb sb;
            sb.grow(axis[j]);
            sb.grow(axis[j + 1]);
            s.segment_box[k][j] = sb;
            s.radius[k][j] = piece.capsule_radii_m[size_t(j)];
        }
    }
}

// Squared distance between two boxes (0 when they overlap).
double box_distance2(const Aabb& a, const Aabb& b) {
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double g = std::max(a.lo[i] - b.hi[i], b.lo[i] - a.hi[i]);
        if (g > 0.0) d2 += g * g;
    }
    return d2;
}

// A lower bound on the distance between piece k and anything inside `box`.
double piece_bound(const Scratch& s, int k, const Aabb& box) {
    double lower = std::sqrt(box_distance2(s.piece_box[k], box));
    if (s.capsules[k] > 0) {
        // The piece lies in the union of its capsules, each inside its axis box grown by its radius.
        double caps = 1e300;
        for (int j = 0; j < s.capsules[k]; ++j)
            caps = std::min(caps, std::sqrt(box_distance2(s.segment_box[k][j], box)) - s.radius[k][j]);
        lower = std::max(lower, caps);
    }
    return lower;
}

double tool_bound(const Scratch& s, const Aabb& box) {
    double lower = 1e300;
    for (int k = 0; k < s.pieces; ++k) lower = std::min(lower, piece_bound(s, k, box));
    return lower;
}

// Whether piece k may meet `box` (false only when it certainly does not).
bool piece_may_touch(const Scratch& s, int k, const Aabb& box) {
    if (!s.piece_box[k].overlaps(box)) return false;
    if (s.capsules[k] == 0) return true;
    for (int j = 0; j < s.capsules[k]; ++j)
        if (box_distance2(s.segment_box[k][j], box) <= s.radius[k][j] * s.radius[k][j]) return true;
    return false;
}

ConvexView view_of(const Model& model, const Scratch& s, int k) {
    return tool_convex_view(model.tool, size_t(k), s.vertices.data(), s.normals.data(), s.offsets.data(),
                            &s.rotation, s.capsule);
}

Aabb triangle_box(const Vec3& a, const Vec3& b, const Vec3& c) {
    Aabb box;
    box.grow(a);
    box.grow(b);
    box.grow(c);
    return box;
}

struct Entry {
    uint32_t node;
    double bound;
};

// Lowers `best` to the distance between the tool and the object when that is smaller.
void object_distance(const Model& model, const ModelObject& obj, const Scratch& s, double& best,
                     ProximityStats& st) {
    const auto& nodes = obj.bvh.nodes();
    if (nodes.empty()) return;
    const auto& order = obj.bvh.order();
    const ModelTool& tool = model.tool;
    Entry stack[kBvhMaxDepth + 2];
    int top = 0;
    ++st.nodes_visited;
    const double root = tool_bound(s, nodes[0].box);
    if (root >= best) return;
    stack[top++] = {0, root};
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.bound >= best) continue;  // best fell since it was pushed
        const Bvh::Node& n = nodes[e.node];
        if (n.count > 0) {
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                const auto& t = obj.mesh.triangles[order[i]];
                const Vec3& a = obj.mesh.vertices[t[0]];
                const Vec3& b = obj.mesh.vertices[t[1]];
                const Vec3& c = obj.mesh.vertices[t[2]];
                const Aabb tb = triangle_box(a, b, c);
                bool tested = false;
                for (int k = 0; k < s.pieces; ++k) {
                    if (piece_bound(s, k, tb) >= best) continue;
                    tested = true;
                    const double d = distance_convex_triangle(view_of(model, s, k), piece_triangles(tool, size_t(k)),
                                                              int(tool.pieces[size_t(k)].triangle_count), a, b, c, best);
                    if (d < best) best = d;
                    if (best <= 0.0) {
                        ++st.triangles_tested;
                        best = 0.0;
                        return;
                    }
                }
                if (tested) ++st.triangles_tested;
            }
            continue;
        }
        const uint32_t l = n.first, r = n.first + 1;
        st.nodes_visited += 2;
        const double bl = tool_bound(s, nodes[l].box);
        const double br = tool_bound(s, nodes[r].box);
        // Nearer child on top, so it is searched first and lowers best for the other.
        const Entry near = bl <= br ? Entry{l, bl} : Entry{r, br};
        const Entry far = bl <= br ? Entry{r, br} : Entry{l, bl};
        if (far.bound < best) stack[top++] = far;
        if (near.bound < best) stack[top++] = near;
    }
}

// Whether the tool overlaps one of the object's triangles. Pieces ride down the tree as a mask of
// those whose bounds still meet the node.
bool object_collides(const Model& model, const ModelObject& obj, const Scratch& s, ProximityStats& st) {
    static_assert(kMaxToolPieces <= 32, "piece mask is 32 bits");
    const auto& nodes = obj.bvh.nodes();
    if (nodes.empty()) return false;
    const auto& order = obj.bvh.order();
    struct Item {
        uint32_t node;
        uint32_t pieces;
    };
    Item stack[kBvhMaxDepth + 2];
    int top = 0;
    const uint32_t all = s.pieces >= 32 ? ~0u : (1u << s.pieces) - 1u;
    stack[top++] = {0, all};
    while (top > 0) {
        const Item it = stack[--top];
        const Bvh::Node& n = nodes[it.node];
        ++st.nodes_visited;
        uint32_t mask = 0;
        for (int k = 0; k < s.pieces; ++k)
            if ((it.pieces >> k & 1u) && piece_may_touch(s, k, n.box)) mask |= 1u << k;
        if (mask == 0) continue;
        if (n.count > 0) {
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                const auto& t = obj.mesh.triangles[order[i]];
                const Vec3& a = obj.mesh.vertices[t[0]];
                const Vec3& b = obj.mesh.vertices[t[1]];
                const Vec3& c = obj.mesh.vertices[t[2]];
                const Aabb tb = triangle_box(a, b, c);
                bool tested = false;
                for (int k = 0; k < s.pieces; ++k) {
                    if (!(mask >> k & 1u) || !piece_may_touch(s, k, tb)) continue;
                    const ConvexView view = view_of(model, s, k);
                    if (capsule_lower_bound(view, a, b, c) > 0.0) continue;  // clear of the piece's capsules
                    tested = true;
                    // GJK finds a gap along some direction: apart (the cheaper proof for most).
                    if (convex_triangle_distance(view, a, b, c, std::numeric_limits<double>::min()).lower > 0.0) continue;
                    if (separate_convex_triangle(view, a, b, c).separation <= 0.0) {
                        ++st.triangles_tested;
                        return true;
                    }
                }
                if (tested) ++st.triangles_tested;
            }
            continue;
        }
        stack[top++] = {n.first + 1, mask};
        stack[top++] = {n.first, mask};
    }
    return false;
}

}  // namespace

double tool_distance(const Model& model, const Pose& tool_pose, double max_distance_m, ProximityStats* stats) {
    ProximityStats local;
    ProximityStats& st = stats ? *stats : local;
    st = ProximityStats{};
    double best = max_distance_m;
    if (model.tool.pieces.empty() || !(best > 0.0)) return best;
    Scratch& s = scratch();
    place(model, tool_pose, s);
    for (const ModelObject& obj : model.objects) {
        object_distance(model, obj, s, best, st);
        if (best <= 0.0) return 0.0;
    }
    return best;
}

bool tool_collides(const Model& model, const Pose& tool_pose, ProximityStats* stats) {
    ProximityStats local;
    ProximityStats& st = stats ? *stats : local;
    st = ProximityStats{};
    if (model.tool.pieces.empty()) return false;
    Scratch& s = scratch();
    place(model, tool_pose, s);
    for (const ModelObject& obj : model.objects)
        if (object_collides(model, obj, s, st)) return true;
    return false;
}

}  // namespace sulcus
