// The independent penetration / gap check. Everything is computed in each object's own frame
// (the tool is moved there), so object vertices are used exactly as stored.
//
// Inside tests use winding numbers. One reference point inside the tool gets a full
// generalised winding number (sum of solid angles over all triangles of the object); every other
// point the check needs (tool vertices, points on tool edges) lies inside the tool's box, so its
// winding number follows from the reference by counting signed crossings of the segment between
// them, and only triangles near the tool can cross that segment. When a crossing is too close to
// call (a segment grazing an edge or ending on a face) the point gets a full winding number of its
// own instead.
//
// The depth is measured at features, as specified: vertices, edges (exact maximum for object
// edges, sampled and refined for tool edges, a lower bound there). Where a corner of an object
// grazes an edge of the tool, a point inside a tool face can lie somewhat deeper than any
// feature (seen up to ~11 % of the depth in random shallow box-box contacts); any overlap at all
// still gives a positive depth, since two crossing surfaces always have an edge through a face.
#include "sulcus/engine/exact_check.h"

#include "exact_primitives.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace sulcus {

namespace {

using namespace exact;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kFourPi = 4.0 * 3.14159265358979323846;
constexpr int kEdgeSamples = 64;  // samples per inside part of a tool edge, term (d)

// Half-space of the tool: a point x is inside when d - n.x > 0 (n unit, outward).
struct Plane {
    Vec3 n;
    double d;
};

// Reused between objects of one call.
struct Scratch {
    std::vector<Vec3> tool_v;                       // tool vertices in the object's frame
    std::vector<Plane> planes;                      // tool face planes in the object's frame
    std::vector<std::array<uint32_t, 2>> tool_edges;  // undirected, each once
    std::vector<int> tool_winding;                  // winding number of each tool vertex
    std::vector<uint32_t> near;                     // object triangles near the tool
    std::vector<Aabb> near_box;                     // their boxes
    std::vector<uint32_t> wide;                     // object triangles near deep points
    std::vector<Aabb> wide_box;
    std::vector<double> alpha, beta;                // tool planes along one segment
    std::vector<std::pair<double, int>> crossings;  // (parameter, winding step) along a tool edge
    std::vector<std::array<double, 2>> inside_parts;
};

bool contains(const Aabb& b, const Vec3& p) {
    return p.x >= b.lo.x && p.x <= b.hi.x && p.y >= b.lo.y && p.y <= b.hi.y && p.z >= b.lo.z && p.z <= b.hi.z;
}

class ObjectCheck {
public:
    ObjectCheck(const TriMesh& tool, const TriMesh& obj, Scratch& s, double gap_limit)
        : tool_(tool), obj_(obj), s_(s), gap_(gap_limit) {}

    // Fills the scratch for this object; returns false when the object is too far to matter.
    bool prepare() {
        for (const Vec3& v : s_.tool_v) tool_box_.grow(v);
        near_box_ = tool_box_;
        near_box_.inflate(gap_);
        Aabb obj_box;
        for (const Vec3& v : obj_.vertices) obj_box.grow(v);
        if (!obj_box.overlaps(near_box_)) return false;

        s_.near.clear();
        s_.near_box.clear();
        for (uint32_t t = 0; t < obj_.triangles.size(); ++t) {
            Aabb b;
            for (uint32_t v : obj_.triangles[t]) b.grow(obj_.vertices[v]);
            if (!b.overlaps(near_box_)) continue;
            s_.near.push_back(t);
            s_.near_box.push_back(b);
        }
        s_.planes.clear();
        for (const auto& t : tool_.triangles) {
            const Vec3 &a = s_.tool_v[t[0]], &b = s_.tool_v[t[1]], &c = s_.tool_v[t[2]];
            const Vec3 n = cross(b - a, c - a);
            const double len = norm(n);
            if (!(len > 0.0)) continue;
            const Vec3 u = n / len;
            s_.planes.push_back({u, dot(u, a)});
        }
        return true;
    }

    double penetration() {
        double pen = 0.0;
        choose_reference();
        // (a) tool vertices inside the object.
        s_.tool_winding.resize(s_.tool_v.size());
        for (size_t i = 0; i < s_.tool_v.size(); ++i) {
            s_.tool_winding[i] = winding_at(s_.tool_v[i]);
            if (s_.tool_winding[i] != 0) pen = std::max(pen, surface_distance(s_.tool_v[i]));
        }
        // (b) object vertices inside the tool.
        for (const Vec3& p : obj_.vertices) {
            if (!contains(tool_box_, p)) continue;
            pen = std::max(pen, tool_depth(p));
        }
        // (c) object edges through the tool (exact maximum of a concave function).
        for (size_t k = 0; k < s_.near.size(); ++k) {
            if (!s_.near_box[k].overlaps(tool_box_)) continue;
            const auto& t = obj_.triangles[s_.near[k]];
            for (int e = 0; e < 3; ++e)
                pen = std::max(pen, edge_depth_in_tool(obj_.vertices[t[e]], obj_.vertices[t[(e + 1) % 3]]));
        }
        // (d) tool edges through the object (sampled: a lower bound of this term).
        for (const auto& e : s_.tool_edges) pen = std::max(pen, tool_edge_depth(e[0], e[1]));
        return pen;
    }

    // Smallest distance between the two surfaces, up to gap_ (assumes no overlap).
    double distance() const {
        double best2 = gap_ * gap_;
        if (!(best2 > 0.0)) return 0.0;
        for (const Vec3& p : s_.tool_v)
            for (size_t k = 0; k < s_.near.size(); ++k) {
                if (point_box_distance2(p, s_.near_box[k]) >= best2) continue;
                const auto& t = obj_.triangles[s_.near[k]];
                best2 = std::min(best2, point_triangle_distance2(p, obj_.vertices[t[0]], obj_.vertices[t[1]],
                                                                  obj_.vertices[t[2]]));
            }
        for (const Vec3& p : obj_.vertices) {
            if (point_box_distance2(p, tool_box_) >= best2) continue;
            for (const auto& t : tool_.triangles)
                best2 = std::min(best2,
                                 point_triangle_distance2(p, s_.tool_v[t[0]], s_.tool_v[t[1]], s_.tool_v[t[2]]));
        }
        for (const auto& e : s_.tool_edges) {
            const Vec3 &a = s_.tool_v[e[0]], &b = s_.tool_v[e[1]];
            Aabb eb;
            eb.grow(a);
            eb.grow(b);
            for (size_t k = 0; k < s_.near.size(); ++k) {
                if (box_box_distance2(eb, s_.near_box[k]) >= best2) continue;
                const auto& t = obj_.triangles[s_.near[k]];
                for (int i = 0; i < 3; ++i)
                    best2 = std::min(best2, segment_segment_distance2(a, b, obj_.vertices[t[i]],
                                                                      obj_.vertices[t[(i + 1) % 3]]));
            }
        }
        return std::sqrt(best2);
    }

private:
    double tool_depth(const Vec3& p) const {
        double d = kInf;
        for (const Plane& pl : s_.planes) d = std::min(d, pl.d - dot(pl.n, p));
        return d;
    }

    double winding_number(const Vec3& p) const {
        double sum = 0.0;
        for (const auto& t : obj_.triangles)
            sum += solid_angle(p, obj_.vertices[t[0]], obj_.vertices[t[1]], obj_.vertices[t[2]]);
        return sum / kFourPi;
    }

    // A point strictly inside the tool, not on the object's surface, with its winding number.
    void choose_reference() {
        Vec3 centroid(0.0);
        for (const Vec3& v : s_.tool_v) centroid += v;
        centroid /= double(s_.tool_v.size());
        ref_ = centroid;
        for (size_t k = 0; k <= s_.tool_v.size(); ++k) {
            if (k > 0) ref_ = centroid + 0.37 * (s_.tool_v[k - 1] - centroid);
            const double w = winding_number(ref_);
            ref_winding_ = int(std::lround(w));
            if (std::abs(w - ref_winding_) < 0.25) return;
        }
    }

    // Winding number of p (a point inside the tool's box).
    int winding_at(const Vec3& p) const {
        int w = ref_winding_;
        Aabb seg;
        seg.grow(ref_);
        seg.grow(p);
        for (size_t k = 0; k < s_.near.size(); ++k) {
            if (!s_.near_box[k].overlaps(seg)) continue;
            const auto& t = obj_.triangles[s_.near[k]];
            double at = 0.0;
            int step = 0;
            switch (segment_triangle_crossing(ref_, p, obj_.vertices[t[0]], obj_.vertices[t[1]],
                                              obj_.vertices[t[2]], &at, &step)) {
                case Crossing::None: break;
                case Crossing::Proper: w += step; break;
                case Crossing::Degenerate: return int(std::lround(winding_number(p)));
            }
        }
        return w;
    }

    // Nearest surface distance among a set of triangles, or -1 when a triangle outside the set
    // could be nearer (the set holds every triangle whose box meets `box`, so one outside lies
    // at least as far as the boundary of `box`).
    double distance_in_set(const Vec3& p, const std::vector<uint32_t>& set, const std::vector<Aabb>& boxes,
                           const Aabb& box) const {
        double best2 = kInf;
        for (size_t k = 0; k < set.size(); ++k) {
            if (point_box_distance2(p, boxes[k]) >= best2) continue;
            const auto& t = obj_.triangles[set[k]];
            best2 = std::min(best2, point_triangle_distance2(p, obj_.vertices[t[0]], obj_.vertices[t[1]],
                                                              obj_.vertices[t[2]]));
        }
        const Vec3 lo = p - box.lo, hi = box.hi - p;
        const double bound = std::min({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
        return bound > 0.0 && best2 <= bound * bound ? std::sqrt(best2) : -1.0;
    }

    // Distance from p (a point inside the tool's box) to the object's surface. Tried on the
    // near triangles, then on a wider set around the tool; when both fall short, all triangles
    // are searched and the wider set is rebuilt with twice the depth found, so that the other
    // points of the same tool resolve locally.
    double surface_distance(const Vec3& p) const {
        double d = distance_in_set(p, s_.near, s_.near_box, near_box_);
        if (d >= 0.0) return d;
        if (wide_margin_ > 0.0) {
            d = distance_in_set(p, s_.wide, s_.wide_box, wide_box_);
            if (d >= 0.0) return d;
        }
        double best2 = kInf;
        for (const auto& t : obj_.triangles)
            best2 = std::min(best2, point_triangle_distance2(p, obj_.vertices[t[0]], obj_.vertices[t[1]],
                                                              obj_.vertices[t[2]]));
        d = std::sqrt(best2);
        wide_margin_ = std::max(2.0 * d, 2.0 * wide_margin_);
        wide_box_ = tool_box_;
        wide_box_.inflate(wide_margin_);
        s_.wide.clear();
        s_.wide_box.clear();
        for (uint32_t t = 0; t < obj_.triangles.size(); ++t) {
            Aabb b;
            for (uint32_t v : obj_.triangles[t]) b.grow(obj_.vertices[v]);
            if (!b.overlaps(wide_box_)) continue;
            s_.wide.push_back(t);
            s_.wide_box.push_back(b);
        }
        return d;
    }

    // Largest distance to the tool's boundary over the part of segment pq inside the (convex)
    // tool. The depth h(t) = min_j (alpha_j + beta_j t) is concave and piecewise linear on the
    // clipped interval: a golden-section search brackets the maximum to 1e-15 in t, then the
    // two lines active at the bracket ends are intersected to land on the breakpoint exactly.
    double edge_depth_in_tool(const Vec3& p, const Vec3& q) {
        Aabb eb;
        eb.grow(p);
        eb.grow(q);
        if (!eb.overlaps(tool_box_)) return 0.0;
        const Vec3 pq = q - p;
        const size_t m = s_.planes.size();
        s_.alpha.resize(m);
        s_.beta.resize(m);
        double lo = 0.0, hi = 1.0;
        for (size_t j = 0; j < m; ++j) {
            const double a = s_.planes[j].d - dot(s_.planes[j].n, p);
            const double b = -dot(s_.planes[j].n, pq);
            s_.alpha[j] = a;
            s_.beta[j] = b;
            if (b == 0.0) {
                if (a <= 0.0) return 0.0;
            } else if (b > 0.0) {
                lo = std::max(lo, -a / b);
            } else {
                hi = std::min(hi, -a / b);
            }
            if (!(lo < hi)) return 0.0;
        }
        auto h = [&](double t, size_t* arg) {
            double v = kInf;
            for (size_t j = 0; j < m; ++j) {
                const double f = s_.alpha[j] + s_.beta[j] * t;
                if (f < v) {
                    v = f;
                    if (arg) *arg = j;
                }
            }
            return v;
        };
        double best = std::max(h(lo, nullptr), h(hi, nullptr));
        const double r = 0.5 * (std::sqrt(5.0) - 1.0);
        double a = lo, b = hi;
        double x1 = b - r * (b - a), x2 = a + r * (b - a);
        double f1 = h(x1, nullptr), f2 = h(x2, nullptr);
        for (int it = 0; it < 200 && b - a > 1e-15; ++it) {
            if (f1 < f2) {
                a = x1;
                x1 = x2;
                f1 = f2;
                x2 = a + r * (b - a);
                f2 = h(x2, nullptr);
            } else {
                b = x2;
                x2 = x1;
                f2 = f1;
                x1 = b - r * (b - a);
                f1 = h(x1, nullptr);
            }
        }
        best = std::max({best, f1, f2});
        size_t ja = 0, jb = 0;
        best = std::max(best, h(a, &ja));
        best = std::max(best, h(b, &jb));
        if (s_.beta[ja] != s_.beta[jb]) {
            const double tx = (s_.alpha[jb] - s_.alpha[ja]) / (s_.beta[ja] - s_.beta[jb]);
            if (tx >= lo && tx <= hi) best = std::max(best, h(tx, nullptr));
        }
        return std::max(best, 0.0);
    }

    // Deepest point of a sub-interval [t0, t1] of tool edge ab that lies inside the object:
    // kEdgeSamples samples, then a golden-section refinement around the best one. Every value
    // is the depth of a real point, so the result is a lower bound of the true maximum.
    double sample_inside_part(const Vec3& a, const Vec3& b, double t0, double t1) const {
        if (!(t1 > t0)) return 0.0;
        const double dt = (t1 - t0) / kEdgeSamples;
        auto depth = [&](double t) { return surface_distance(a + t * (b - a)); };
        double best = 0.0, best_t = t0;
        for (int k = 0; k < kEdgeSamples; ++k) {
            const double t = t0 + (k + 0.5) * dt;
            const double d = depth(t);
            if (d > best) best = d, best_t = t;
        }
        const double r = 0.5 * (std::sqrt(5.0) - 1.0);
        double lo = std::max(t0, best_t - dt), hi = std::min(t1, best_t + dt);
        double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
        double f1 = depth(x1), f2 = depth(x2);
        for (int it = 0; it < 40; ++it) {
            if (f1 < f2) {
                lo = x1, x1 = x2, f1 = f2;
                x2 = lo + r * (hi - lo);
                f2 = depth(x2);
            } else {
                hi = x2, x2 = x1, f2 = f1;
                x1 = hi - r * (hi - lo);
                f1 = depth(x1);
            }
        }
        return std::max({best, f1, f2});
    }

    // Term (d) for tool edge (i, j): the parts of the edge inside the object follow from the
    // winding numbers of its ends and the signed crossings between them.
    double tool_edge_depth(uint32_t i, uint32_t j) {
        const Vec3 &a = s_.tool_v[i], &b = s_.tool_v[j];
        Aabb eb;
        eb.grow(a);
        eb.grow(b);
        s_.crossings.clear();
        bool degenerate = false;
        for (size_t k = 0; k < s_.near.size() && !degenerate; ++k) {
            if (!s_.near_box[k].overlaps(eb)) continue;
            const auto& t = obj_.triangles[s_.near[k]];
            double at = 0.0;
            int step = 0;
            switch (segment_triangle_crossing(a, b, obj_.vertices[t[0]], obj_.vertices[t[1]], obj_.vertices[t[2]],
                                              &at, &step)) {
                case Crossing::None: break;
                case Crossing::Proper: s_.crossings.push_back({at, step}); break;
                case Crossing::Degenerate: degenerate = true; break;
            }
        }
        if (!degenerate) {
            std::sort(s_.crossings.begin(), s_.crossings.end());
            s_.inside_parts.clear();
            int w = s_.tool_winding[i];
            double from = 0.0;
            for (const auto& [t, step] : s_.crossings) {
                if (w != 0) s_.inside_parts.push_back({from, t});
                w += step;
                from = t;
            }
            if (w != 0) s_.inside_parts.push_back({from, 1.0});
            // The two ends must agree with the crossings; if rounding made them disagree, sample.
            if (w == s_.tool_winding[j]) {
                double best = 0.0;
                for (const auto& part : s_.inside_parts)
                    best = std::max(best, sample_inside_part(a, b, part[0], part[1]));
                return best;
            }
        }
        // Robust fallback: an inside test per sample along the whole edge.
        double best = 0.0;
        for (int k = 0; k < kEdgeSamples; ++k) {
            const Vec3 p = a + ((k + 0.5) / kEdgeSamples) * (b - a);
            if (winding_at(p) != 0) best = std::max(best, surface_distance(p));
        }
        return best;
    }

    const TriMesh& tool_;
    const TriMesh& obj_;
    Scratch& s_;
    double gap_;
    Aabb tool_box_, near_box_;
    Vec3 ref_{0.0};
    int ref_winding_ = 0;
    // Wider triangle set for deep points (built on demand; scratch is logically const).
    mutable double wide_margin_ = 0.0;
    mutable Aabb wide_box_;
};

}  // namespace

ExactCheck exact_check(const TriMesh& tool, const Pose& tool_pose, const std::vector<PlacedMesh>& objects,
                       double gap_limit) {
    const double gap = gap_limit > 0.0 && std::isfinite(gap_limit) ? gap_limit : 0.0;
    ExactCheck out;
    out.distance_m = gap;
    if (tool.vertices.empty() || tool.triangles.empty()) return out;

    Scratch s;
    // Each undirected edge of a closed mesh runs i -> j with i < j in exactly one triangle.
    for (const auto& t : tool.triangles)
        for (int e = 0; e < 3; ++e)
            if (t[e] < t[(e + 1) % 3]) s.tool_edges.push_back({t[e], t[(e + 1) % 3]});

    for (const PlacedMesh& placed : objects) {
        if (!placed.mesh || placed.mesh->triangles.empty()) continue;
        s.tool_v.resize(tool.vertices.size());
        for (size_t i = 0; i < tool.vertices.size(); ++i)
            s.tool_v[i] = placed.pose.inverse_apply(tool_pose.apply(tool.vertices[i]));
        ObjectCheck check(tool, *placed.mesh, s, gap);
        if (!check.prepare()) continue;
        const double pen = check.penetration();
        out.penetration_m = std::max(out.penetration_m, pen);
        out.distance_m = std::min(out.distance_m, pen > 0.0 ? 0.0 : check.distance());
    }
    return out;
}

ExactCheck exact_check(const std::vector<TriMesh>& tool_pieces, const Pose& tool_pose,
                       const std::vector<PlacedMesh>& objects, double gap_limit) {
    ExactCheck out;
    out.distance_m = gap_limit > 0.0 && std::isfinite(gap_limit) ? gap_limit : 0.0;
    for (const TriMesh& piece : tool_pieces) {
        const ExactCheck c = exact_check(piece, tool_pose, objects, gap_limit);
        out.penetration_m = std::max(out.penetration_m, c.penetration_m);
        out.distance_m = std::min(out.distance_m, c.distance_m);
    }
    return out;
}

}  // namespace sulcus
