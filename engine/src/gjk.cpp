// Distance bounds between a convex polytope (its vertices) and a triangle by the
// Gilbert-Johnson-Keerthi iteration on their Minkowski difference D = P - T.
//
// Safety does not rest on the simplex arithmetic: every lower bound reported is the gap along a
// direction v between the polytope's and the triangle's projections, min_D v.z / |v|, which bounds
// the distance for any v. The simplex only chooses v; rounding in it can cost iterations, never a
// bound that is too high. The upper bound is |v| for v a point of (the hull of) D. On a polytope
// certified for it (ToolPiece::descend) the vertex least along v is found by descent over its
// corners, which on such a polytope ends at the least vertex: the same gap.
#include "geometry.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

namespace {

// A point of D with the polytope vertex and triangle vertex it is the difference of.
struct Point {
    Vec3 p;
    uint16_t ia = 0;
    uint8_t ib = 0;
};

struct Simplex {
    Point p[4];
    int n = 0;
};

// The point of D least along v (the support of D in -v); on a polytope with neighbours, by
// descent from vertex `start` (least_along).
inline Point support_least(const ConvexView& poly, const Vec3 tri[3], const Vec3& v, int start = 0) {
    const int ia = least_along(poly.vertices, poly.vertex_count, poly.neighbour_offsets, poly.neighbours, poly.start_of,
                               v, start);
    int ib = 0;
    double top = glm::dot(v, tri[0]);
    for (int k = 1; k < 3; ++k) {
        const double s = glm::dot(v, tri[k]);
        if (s > top) {
            top = s;
            ib = k;
        }
    }
    return Point{poly.vertices[ia] - tri[ib], static_cast<uint16_t>(ia), static_cast<uint8_t>(ib)};
}

// Closest point to the origin of segment a-b; reduces the simplex to the feature holding it.
Vec3 closest_segment(Simplex& s) {
    const Vec3 a = s.p[0].p, b = s.p[1].p;
    const Vec3 ab = b - a;
    const double den = glm::dot(ab, ab);
    const double t = den > 0.0 ? -glm::dot(a, ab) / den : 0.0;
    if (t <= 0.0) {
        s.n = 1;
        return a;
    }
    if (t >= 1.0) {
        s.p[0] = s.p[1];
        s.n = 1;
        return b;
    }
    return a + t * ab;
}

// Closest point to the origin of triangle a, b, c; reduces the simplex likewise. A triangle
// with no area is taken as its longest edge.
Vec3 closest_triangle(Simplex& s) {
    const Vec3 a = s.p[0].p, b = s.p[1].p, c = s.p[2].p;
    const Vec3 nrm = glm::cross(b - a, c - a);
    const double scale = std::max({glm::dot(b - a, b - a), glm::dot(c - a, c - a), glm::dot(c - b, c - b)});
    if (glm::dot(nrm, nrm) <= 1e-24 * scale * scale) {
        const double ab = glm::dot(b - a, b - a), ac = glm::dot(c - a, c - a), bc = glm::dot(c - b, c - b);
        if (ac >= ab && ac >= bc) s.p[1] = s.p[2];
        else if (bc >= ab && bc >= ac) s.p[0] = s.p[2];
        s.n = 2;
        return closest_segment(s);
    }
    const TriClosest tc = closest_on_triangle(Vec3(0.0), a, b, c);
    switch (tc.region) {
        case TriRegion::Face:
            // Along the normal: its direction does not suffer the cancellation of a small point
            // found from large ones, which would cost the lower bound its last digits.
            return nrm * (glm::dot(nrm, a) / glm::dot(nrm, nrm));
        case TriRegion::Edge0: s.n = 2; break;                            // a b
        case TriRegion::Edge1: s.p[0] = s.p[2]; s.n = 2; break;           // c b
        case TriRegion::Edge2: s.p[1] = s.p[2]; s.n = 2; break;           // a c
        case TriRegion::Vertex0: s.n = 1; break;
        case TriRegion::Vertex1: s.p[0] = s.p[1]; s.n = 1; break;
        case TriRegion::Vertex2: s.p[0] = s.p[2]; s.n = 1; break;
    }
    return tc.point;
}

// Closest point to the origin of tetrahedron s; `inside` when the origin lies in it.
Vec3 closest_tetrahedron(Simplex& s, bool& inside) {
    inside = false;
    static constexpr int kFace[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
    bool outside_any = false;
    double best = 1e300;
    Simplex best_s;
    Vec3 best_p(0.0);
    for (const auto& f : kFace) {
        const Vec3 &a = s.p[f[0]].p, &b = s.p[f[1]].p, &c = s.p[f[2]].p, &d = s.p[f[3]].p;
        const Vec3 nrm = glm::cross(b - a, c - a);
        const double so = -glm::dot(nrm, a);     // origin's side
        const double sd = glm::dot(nrm, d - a);  // the fourth vertex's side
        // The origin beyond this face (or the tetrahedron flat): the face may hold the closest point.
        if (!(so * sd < 0.0) && !(sd == 0.0)) continue;
        outside_any = true;
        Simplex t;
        t.p[0] = s.p[f[0]];
        t.p[1] = s.p[f[1]];
        t.p[2] = s.p[f[2]];
        t.n = 3;
        const Vec3 q = closest_triangle(t);
        const double d2 = glm::dot(q, q);
        if (d2 < best) {
            best = d2;
            best_s = t;
            best_p = q;
        }
    }
    if (!outside_any) {
        inside = true;
        return Vec3(0.0);
    }
    s = best_s;
    return best_p;
}

// Closest point to the origin of the simplex (of any size), reducing it as above.
Vec3 closest_simplex(Simplex& s, bool& inside) {
    inside = false;
    if (s.n == 1) return s.p[0].p;
    if (s.n == 2) return closest_segment(s);
    if (s.n == 3) return closest_triangle(s);
    return closest_tetrahedron(s, inside);
}

// Written field by field where it is kept: a simplex made on the stack and copied there was
// read back in wider pieces than it was written in, a stall at every iteration of the search.
void set_names(GjkSimplex& g, const Simplex& s) {
    g = GjkSimplex{};
    g.count = static_cast<uint8_t>(s.n);
    for (int k = 0; k < s.n; ++k) {
        g.poly[k] = s.p[k].ia;
        g.tri[k] = s.p[k].ib;
    }
}

// The polytope and the triangle touch or overlap (the simplex holds the origin).
DistanceBounds& touching(DistanceBounds& r, const Simplex& s) {
    r.lower = r.upper = 0.0;
    r.direction = Vec3(0.0);
    r.direction_gap = -1e300;
    set_names(r.simplex, s);
    return r;
}

// Besides the distance's stops: `settle_at` ends the search once the gap along some direction (a
// lower bound on the signed separation, DistanceBounds::separation) reaches it, and `give_up_below`
// once the upper bound on the distance is under it.
DistanceBounds distance_bounds(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c, double cutoff,
                               double tolerance, int max_iterations, const Vec3* hint, const GjkSimplex* warm,
                               double settle_at = 1e300, double give_up_below = -1e300) {
    DistanceBounds r;
    const Vec3 tri[3] = {a, b, c};
    const int count = poly.vertex_count;
    Simplex s;
    // From the hint, the point of D least along it: often its gap already settles the cutoff.
    // The descent along edges starts from the earlier simplex's first vertex.
    const bool hinted = hint && glm::dot(*hint, *hint) > 0.0;
    const int start = warm && warm->count > 0 ? int(warm->poly[0]) : 0;
    s.p[0] = hinted ? support_least(poly, tri, *hint, start) : Point{poly.vertices[0] - a, 0, 0};
    s.n = 1;
    Vec3 v = s.p[0].p;
    double lower = 0.0;
    if (hinted) {
        // The gap along the hint itself.
        r.direction_gap = glm::dot(*hint, s.p[0].p) / glm::length(*hint);
        r.separation = r.direction_gap;
        lower = std::max(0.0, r.direction_gap);
        r.lower = lower;
        r.direction = *hint;
        if (lower >= cutoff || r.separation >= settle_at) return r;
        // A check of the separation with no search has its answer: the hint's gap.
        if (max_iterations <= 0 && settle_at < 1e300) return r;
    }
    if (warm && warm->count > 0 && warm->count <= 4) {
        // The earlier simplex, its points taken at this pose (repeats dropped); it starts the
        // search where it is nearer than the hint's point.
        Simplex ws;
        for (int k = 0; k < warm->count; ++k) {
            if (warm->poly[k] >= count || warm->tri[k] > 2) continue;
            const Point q{poly.vertices[warm->poly[k]] - tri[warm->tri[k]], warm->poly[k], warm->tri[k]};
            bool known = false;
            for (int j = 0; j < ws.n; ++j) known |= ws.p[j].ia == q.ia && ws.p[j].ib == q.ib;
            if (!known) ws.p[ws.n++] = q;
        }
        if (ws.n > 0) {
            bool inside = false;
            const Vec3 wv = closest_simplex(ws, inside);
            if (inside) return touching(r, ws);
            if (glm::dot(wv, wv) < glm::dot(v, v)) {
                s = ws;
                v = wv;
            }
        }
    }
    if (max_iterations <= 0) {
        // No search: the hint's gap below, and above the nearer of the hint's point and the
        // earlier simplex's closest point (points of D, with room for the rounding of taking
        // them at this pose).
        r.upper = glm::length(v) * (1.0 + 1e-12) + 1e-15;
        set_names(r.simplex, s);
        return r;
    }
    for (int it = 0; it < max_iterations; ++it) {
        r.iterations = it + 1;
        set_names(r.simplex, s);
        const double vv = glm::dot(v, v);
        if (vv == 0.0) return touching(r, s);
        const double vl = std::sqrt(vv);
        const Point w = support_least(poly, tri, v, s.p[s.n - 1].ia);
        // Every point z of D has v.z >= v.w: the gap along v bounds the distance.
        r.direction_gap = glm::dot(v, w.p) / vl;
        r.separation = std::max(r.separation, r.direction_gap);
        lower = std::max(lower, r.direction_gap);
        r.lower = lower;
        r.upper = vl;
        r.direction = v;
        if (lower >= cutoff || vl - lower <= tolerance || r.separation >= settle_at || vl < give_up_below) return r;
        // w adds nothing the simplex has: no further progress is possible.
        bool known = false;
        for (int k = 0; k < s.n; ++k) known |= s.p[k].p == w.p;
        if (known) return r;
        s.p[s.n++] = w;
        bool inside = false;
        const Vec3 next = closest_simplex(s, inside);
        if (inside) return touching(r, s);
        // Rounding can stall the descent: the bounds so far stand.
        if (!(glm::dot(next, next) < vv)) return r;
        v = next;
    }
    return r;
}

}  // namespace

DistanceBounds convex_triangle_distance(const Vec3* poly, int count, const Vec3& a, const Vec3& b, const Vec3& c,
                                        double cutoff, double tolerance, int max_iterations, const Vec3* hint,
                                        const GjkSimplex* warm) {
    ConvexView view;
    view.vertices = poly;
    view.vertex_count = count;
    return distance_bounds(view, a, b, c, cutoff, tolerance, max_iterations, hint, warm);
}

DistanceBounds convex_triangle_distance(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                        double cutoff, double tolerance, int max_iterations, const Vec3* hint,
                                        const GjkSimplex* warm) {
    return distance_bounds(poly, a, b, c, cutoff, tolerance, max_iterations, hint, warm);
}

DistanceBounds convex_triangle_separation(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                          double settle_at, double give_up_below, const Vec3* hint,
                                          const GjkSimplex* warm, int max_iterations) {
    return distance_bounds(poly, a, b, c, 1e300, 1e-13, max_iterations, hint, warm, settle_at, give_up_below);
}

}  // namespace sulcus
