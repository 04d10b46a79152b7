// Geometric primitives of the exact check, kept apart from the solver's own geometry on purpose:
// the check must not share code (and so bugs) with what it checks.
#pragma once

#include "sulcus/engine/types.h"

#include <algorithm>
#include <cmath>

namespace sulcus::exact {

inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// Squared distance from p to the triangle abc (closest point by Voronoi regions of the vertices,
// edges and face). Degenerate triangles fall into the vertex/edge regions and stay correct.
inline double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return dot(ap, ap);
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return dot(bp, bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        const Vec3 q = ap - v * ab;
        return dot(q, q);
    }
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return dot(cp, cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        const Vec3 q = ap - w * ac;
        return dot(q, q);
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        const Vec3 q = bp - w * (c - b);
        return dot(q, q);
    }
    // Inside the face region: the distance is the height over the plane, computed directly
    // (more accurate than subtracting a reconstructed closest point).
    const Vec3 n = cross(ab, ac);
    const double nn = dot(n, n);
    if (!(nn > 0.0)) return dot(ap, ap);
    const double h = dot(ap, n);
    return h * h / nn;
}

// Squared distance between the segments p0p1 and q0q1 (clamped closest parameters; parallel
// segments take s = 0 first and are then clamped, which still yields the minimum distance).
inline double segment_segment_distance2(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
    const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0.0, t = 0.0;
    if (a <= 0.0 && e <= 0.0) return dot(r, r);
    if (a <= 0.0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= 0.0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2);
            const double denom = a * e - b * b;
            s = denom > 1e-300 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1.0) {
                t = 1.0;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    const Vec3 d = (p0 + s * d1) - (q0 + t * d2);
    return dot(d, d);
}

// Six times the signed volume of the tetrahedron abcd: > 0 when d lies on the side of the
// plane abc toward which the counter-clockwise normal of abc points.
inline double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return dot(cross(b - a, c - a), d - a);
}

// A conservative bound of the rounding error of orient3d (a generous multiple of the
// product of the edge lengths times the unit roundoff).
inline double orient3d_tolerance(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return 1e-12 * norm(b - a) * norm(c - a) * norm(d - a);
}

enum class Crossing { None, Proper, Degenerate };

// Does the segment pq cross the triangle abc? Proper: it passes through the interior of the
// triangle with p and q strictly on opposite sides; then `t` is the crossing parameter along
// pq and `step` is +1 when the segment enters the solid (goes against the outward normal of a
// counter-clockwise triangle), -1 when it leaves it. Degenerate: too close to call (an endpoint
// on the plane, or the segment grazing an edge or vertex); the caller falls back to a slower,
// robust method.
inline Crossing segment_triangle_crossing(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                          const Vec3& c, double* t, int* step) {
    const double op = orient3d(a, b, c, p), oq = orient3d(a, b, c, q);
    const double tp = orient3d_tolerance(a, b, c, p), tq = orient3d_tolerance(a, b, c, q);
    if ((op > tp && oq > tq) || (op < -tp && oq < -tq)) return Crossing::None;
    const double e0 = orient3d(p, q, a, b), e1 = orient3d(p, q, b, c), e2 = orient3d(p, q, c, a);
    const double t0 = orient3d_tolerance(p, q, a, b), t1 = orient3d_tolerance(p, q, b, c),
                 t2 = orient3d_tolerance(p, q, c, a);
    const bool pos = e0 > t0 || e1 > t1 || e2 > t2;
    const bool neg = e0 < -t0 || e1 < -t1 || e2 < -t2;
    if (pos && neg) return Crossing::None;  // the line of pq passes beside the triangle
    const bool clear_sides = (op > tp && oq < -tq) || (op < -tp && oq > tq);
    const bool clear_edges = (e0 > t0 && e1 > t1 && e2 > t2) || (e0 < -t0 && e1 < -t1 && e2 < -t2);
    if (!clear_sides || !clear_edges) return Crossing::Degenerate;
    *t = op / (op - oq);
    *step = op > 0.0 ? 1 : -1;
    return Crossing::Proper;
}

// Solid angle in steradians subtended by the triangle abc seen from p (signed: positive when p
// is on the inner side of a counter-clockwise triangle), by the formula of Van Oosterom and
// Strackee.
inline double solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ra = a - p, rb = b - p, rc = c - p;
    const double la = norm(ra), lb = norm(rb), lc = norm(rc);
    const double num = dot(ra, cross(rb, rc));
    const double den = la * lb * lc + dot(ra, rb) * lc + dot(ra, rc) * lb + dot(rb, rc) * la;
    return 2.0 * std::atan2(num, den);
}

// Distance from p to the box b (0 inside).
inline double point_box_distance2(const Vec3& p, const Aabb& b) {
    const Vec3 d = glm::max(glm::max(b.lo - p, p - b.hi), Vec3(0.0));
    return dot(d, d);
}

// Gap between two boxes (0 when they overlap), squared.
inline double box_box_distance2(const Aabb& a, const Aabb& b) {
    const Vec3 d = glm::max(glm::max(a.lo - b.hi, b.lo - a.hi), Vec3(0.0));
    return dot(d, d);
}

}  // namespace sulcus::exact
