#include "geometry.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

TriClosest closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    // Voronoi regions of the triangle, tested in turn (vertex, edge, face).
    TriClosest r;
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        r.point = a;
        r.region = TriRegion::Vertex0;
    } else {
        const Vec3 bp = p - b;
        const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
        const Vec3 cp = p - c;
        const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
        const double vc = d1 * d4 - d3 * d2;
        const double vb = d5 * d2 - d1 * d6;
        const double va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) {
            r.point = b;
            r.region = TriRegion::Vertex1;
        } else if (d6 >= 0.0 && d5 <= d6) {
            r.point = c;
            r.region = TriRegion::Vertex2;
        } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            r.point = a + (d1 / (d1 - d3)) * ab;
            r.region = TriRegion::Edge0;
        } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
            const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            r.point = b + w * (c - b);
            r.region = TriRegion::Edge1;
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            r.point = a + (d2 / (d2 - d6)) * ac;
            r.region = TriRegion::Edge2;
        } else {
            const double den = 1.0 / (va + vb + vc);
            r.point = a + ab * (vb * den) + ac * (vc * den);
            r.region = TriRegion::Face;
        }
    }
    r.distance = glm::length(p - r.point);
    return r;
}

SegmentClosest closest_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
    SegmentClosest r;
    closest_segment_params(p0, p1, q0, q1, r.s, r.t);
    r.distance = glm::length((p0 + r.s * (p1 - p0)) - (q0 + r.t * (q1 - q0)));
    return r;
}

namespace {

// The gap along unit axis n between a polytope spanning [pmin, pmax] along it and triangle
// (a, b, c): with the polytope on the positive side, its min minus the triangle's max; also the
// other orientation. Returns the larger, `sign` +1 for the first.
inline double extent_gap(double pmin, double pmax, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                         double& sign) {
    const double ta = glm::dot(n, a), tb = glm::dot(n, b), tc = glm::dot(n, c);
    const double tmin = std::min(ta, std::min(tb, tc)), tmax = std::max(ta, std::max(tb, tc));
    const double pos = pmin - tmax, neg = tmin - pmax;
    sign = pos >= neg ? 1.0 : -1.0;
    return std::max(pos, neg);
}

// Separation along unit axis n (extent_gap), the polytope's extent by looking at every vertex.
inline double axis_separation(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                              double& sign) {
    double pmin = 1e300, pmax = -1e300;
    for (int i = 0; i < poly.vertex_count; ++i) {
        const double v = glm::dot(n, poly.vertices[i]);
        pmin = std::min(pmin, v);
        pmax = std::max(pmax, v);
    }
    return extent_gap(pmin, pmax, n, a, b, c, sign);
}

}  // namespace

double gap_along_axis(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                      int* extremes) {
    if (!extremes || !poly.neighbours) {
        double sign = 1.0;
        return axis_separation(poly, n, a, b, c, sign);
    }
    // The polytope's least and greatest vertices along n by descent from those of the last axis
    // (the same values as the scan's: a certified descent ends at a least vertex).
    extremes[0] = least_along(poly.vertices, poly.vertex_count, poly.neighbour_offsets, poly.neighbours,
                              poly.start_of, n, extremes[0]);
    extremes[1] = least_along(poly.vertices, poly.vertex_count, poly.neighbour_offsets, poly.neighbours,
                              poly.start_of, -n, extremes[1]);
    double sign = 1.0;
    return extent_gap(glm::dot(n, poly.vertices[extremes[0]]), glm::dot(n, poly.vertices[extremes[1]]), n, a, b, c,
                      sign);
}

bool vertex_deep_inside(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c, double floor,
                        int* rejecting) {
    for (const Vec3* p : {&a, &b, &c}) {
        const int h = rejecting ? *rejecting : -1;
        if (h >= 0 && h < poly.face_count && glm::dot(poly.normals[h], *p) - poly.offsets[h] >= floor) continue;
        bool deep = true;
        for (int f = 0; f < poly.face_count && deep; ++f) {
            deep = glm::dot(poly.normals[f], *p) - poly.offsets[f] < floor;
            if (!deep && rejecting) *rejecting = f;
        }
        if (deep) return true;
    }
    return false;
}

SatResult separate_convex_triangle(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c) {
    SatResult best;
    best.separation = -1e300;
    auto keep = [&](double s, double sign, const Vec3& axis, int kind, int index) {
        if (s > best.separation) {
            best.separation = s;
            best.axis = sign * axis;
            best.kind = kind;
            best.index = index;
        }
    };
    auto consider = [&](const Vec3& axis, int kind, int index) {
        double sign = 1.0;
        const double s = axis_separation(poly, axis, a, b, c, sign);
        keep(s, sign, axis, kind, index);
    };
    const Vec3 tn = glm::cross(b - a, c - a);
    const double tl = glm::length(tn);
    if (tl > 0.0) consider(tn / tl, 0, 0);
    const bool fast = poly.depths && poly.edge_normals && poly.rotation;
    for (int f = 0; f < poly.face_count; ++f) {
        if (!fast) {
            consider(poly.normals[f], 1, f);
            continue;
        }
        // The polytope spans [offset - depth, offset] along its own face normal.
        const Vec3& n = poly.normals[f];
        double sign = 1.0;
        const double s = extent_gap(poly.offsets[f] - poly.depths[f], poly.offsets[f], n, a, b, c, sign);
        keep(s, sign, n, 1, f);
    }
    const Vec3 te[3] = {b - a, c - b, a - c};
    // Edge pairs: only those that form a face of the Minkowski difference can be the separating
    // axis of least overlap (their arcs on the Gauss map cross). The triangle's edge k maps to the
    // half great circle of normals perpendicular to it on its outer side; the polytope's edge to the
    // arc between its two face normals. Tested in the polytope's frame.
    Vec3 e_local[3], out_local[3];
    if (fast && tl > 0.0) {
        const Quat inv = glm::conjugate(*poly.rotation);
        for (int k = 0; k < 3; ++k) {
            e_local[k] = inv * te[k];
            out_local[k] = inv * glm::cross(te[k], tn);
        }
    }
    // The pair of the triangle's edge k and the polytope's edge e, with x (local frame) a normal in
    // the edge's cone where the pair's arcs cross (zero without the Gauss-map test).
    const double scale_e[3] = {glm::length(te[0]), glm::length(te[1]), glm::length(te[2])};
    auto edge_pair = [&](int k, int e, const Vec3& x) {
        const Vec3 pe = poly.vertices[poly.edges[e][1]] - poly.vertices[poly.edges[e][0]];
        const Vec3 u = glm::cross(te[k], pe);
        const double ul = glm::length(u);
        // Near-parallel edge pairs give no new axis: the face normals cover them.
        if (ul <= 1e-9 * scale_e[k] * glm::length(pe)) return;
        if (glm::length(x) > 0.0) {
            // A face of the Minkowski difference: along its normal (x, in the edge's normal
            // cone) the polytope reaches farthest at this edge, so its extent is one dot.
            Vec3 n = u / ul;
            if (glm::dot(n, *poly.rotation * x) < 0.0) n = -n;
            const double pmax = glm::dot(n, poly.vertices[poly.edges[e][0]]);
            const double tmin = std::min(glm::dot(n, a), std::min(glm::dot(n, b), glm::dot(n, c)));
            keep(tmin - pmax, -1.0, n, 2, k * poly.edge_count + e);
            return;
        }
        consider(u / ul, 2, k * poly.edge_count + e);
    };
    if (!(fast && tl > 0.0)) {
        for (int k = 0; k < 3; ++k)
            for (int e = 0; e < poly.edge_count; ++e) edge_pair(k, e, Vec3(0.0));
        return best;
    }
    // The arcs cross where the edge's two normals are not both on one side of the plane normal to
    // the triangle's edge, and x, their blend on that plane, faces out of the triangle.
    auto arcs_cross = [&](int k, int e, double al, double be, double out_length) {
        const Vec3 x = std::abs(be) * poly.edge_normals[e][0] + std::abs(al) * poly.edge_normals[e][1];
        if (glm::dot(x, out_local[k]) > 1e-9 * glm::length(x) * out_length) return;
        edge_pair(k, e, x);
    };
    // Where the polytope's triangles fit the table, each triangle normal's dot product with the
    // triangle's edge (the same products as taken edge by edge) and its side are taken once for
    // every polytope edge at it.
    constexpr int kTableTriangles = 256;
    const bool table = poly.triangle_normals && poly.edge_triangles && poly.triangle_count <= kTableTriangles;
    double along[kTableTriangles];
    uint8_t side[kTableTriangles];
    for (int k = 0; k < 3; ++k) {
        const double tol = 1e-12 * scale_e[k];
        const double out_length = glm::length(out_local[k]);
        if (!table) {
            for (int e = 0; e < poly.edge_count; ++e) {
                const double al = glm::dot(poly.edge_normals[e][0], e_local[k]);
                const double be = glm::dot(poly.edge_normals[e][1], e_local[k]);
                if ((al > tol && be > tol) || (al < -tol && be < -tol)) continue;
                arcs_cross(k, e, al, be, out_length);
            }
            continue;
        }
        for (int t = 0; t < poly.triangle_count; ++t) {
            const double d = glm::dot(poly.triangle_normals[t], e_local[k]);
            along[t] = d;
            side[t] = uint8_t((d > tol ? 1 : 0) | (d < -tol ? 2 : 0));
        }
        for (int e = 0; e < poly.edge_count; ++e) {
            const uint32_t t0 = poly.edge_triangles[e][0], t1 = poly.edge_triangles[e][1];
            // Both above the tolerance or both below it.
            if (side[t0] & side[t1]) continue;
            arcs_cross(k, e, along[t0], along[t1], out_length);
        }
    }
    return best;
}

namespace {

double triangle_triangle_distance(const Vec3 p[3], const Vec3 q[3]) {
    double best = 1e300;
    for (int i = 0; i < 3; ++i) {
        best = std::min(best, closest_on_triangle(p[i], q[0], q[1], q[2]).distance);
        best = std::min(best, closest_on_triangle(q[i], p[0], p[1], p[2]).distance);
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            best = std::min(best, closest_segments(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3]).distance);
    return best;
}

}  // namespace

double segment_triangle_distance(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 n = glm::cross(b - a, c - a);
    const double s0 = glm::dot(n, p0 - a), s1 = glm::dot(n, p1 - a);
    if ((s0 <= 0.0 && s1 >= 0.0) || (s0 >= 0.0 && s1 <= 0.0)) {
        // The segment meets the triangle's plane: inside the triangle means distance 0.
        const double den = s0 - s1;
        const Vec3 x = den != 0.0 ? p0 + (p1 - p0) * (s0 / den) : p0;
        if (glm::dot(glm::cross(b - a, x - a), n) >= 0.0 && glm::dot(glm::cross(c - b, x - b), n) >= 0.0 &&
            glm::dot(glm::cross(a - c, x - c), n) >= 0.0)
            return 0.0;
    }
    double d = std::min(closest_on_triangle(p0, a, b, c).distance, closest_on_triangle(p1, a, b, c).distance);
    d = std::min(d, closest_segments(p0, p1, a, b).distance);
    d = std::min(d, closest_segments(p0, p1, b, c).distance);
    d = std::min(d, closest_segments(p0, p1, c, a).distance);
    return d;
}

double capsule_lower_bound(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c) {
    if (!poly.capsule || poly.capsule_count <= 0) return -1e300;
    constexpr int kMaxCapsules = 16;
    const int count = poly.capsule_count;
    auto exact = [&](int k) {
        return segment_triangle_distance(poly.capsule[k], poly.capsule[k + 1], a, b, c) - poly.capsule_radii[k];
    };
    if (count > kMaxCapsules) {
        double lower = 1e300;
        for (int k = 0; k < count; ++k) lower = std::min(lower, exact(k));
        return lower;
    }
    // Every point of the triangle lies within the sphere round it (TriangleSphere), so a capsule
    // is no nearer to the triangle than to that sphere: the nearest capsule by the sphere first,
    // then only those the sphere puts under the least so far (with room for rounding, far above
    // it) are measured. The least is the same as measuring all.
    const TriangleSphere ts = triangle_sphere(a, b, c);
    double sphere[kMaxCapsules];
    int first = 0;
    for (int k = 0; k < count; ++k) {
        sphere[k] = capsule_sphere_lower(poly.capsule[k], poly.capsule[k + 1], poly.capsule_radii[k], ts);
        if (sphere[k] < sphere[first]) first = k;
    }
    const double room = 1e-9 + 1e-12 * (glm::length(ts.centre) + ts.radius);
    double lower = exact(first);
    for (int k = 0; k < count; ++k)
        if (k != first && sphere[k] - room < lower) lower = std::min(lower, exact(k));
    return lower;
}

double distance_convex_triangle_by_faces(const ConvexView& poly, const uint32_t (*triangles)[3], int triangle_count,
                                         const Vec3& a, const Vec3& b, const Vec3& c) {
    // Overlap first: the separating-axis test is exact for convex against triangle.
    const SatResult sat = separate_convex_triangle(poly, a, b, c);
    if (sat.separation <= 0.0) return 0.0;
    const Vec3 q[3] = {a, b, c};
    double best = 1e300;
    for (int i = 0; i < triangle_count; ++i) {
        const Vec3 p[3] = {poly.vertices[triangles[i][0]], poly.vertices[triangles[i][1]],
                           poly.vertices[triangles[i][2]]};
        // The closest point of a convex polytope lies on a face the triangle is (partly) in
        // front of, or on that face's boundary, which a neighbouring face the triangle is in front
        // of also holds.
        const Vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
        const double d0 = glm::dot(n, p[0]);
        if (glm::dot(n, a) <= d0 && glm::dot(n, b) <= d0 && glm::dot(n, c) <= d0) continue;
        best = std::min(best, triangle_triangle_distance(p, q));
    }
    return best;
}

double distance_convex_triangle(const ConvexView& poly, const uint32_t (*triangles)[3], int triangle_count,
                                const Vec3& a, const Vec3& b, const Vec3& c, double cutoff) {
    const double lower = capsule_lower_bound(poly, a, b, c);
    if (lower >= cutoff) return lower;
    // GJK: a lower bound of at least the cutoff, or the distance to within its tolerance.
    constexpr double kTolerance = 1e-13;
    const DistanceBounds g = convex_triangle_distance(poly, a, b, c, cutoff, kTolerance);
    if (g.lower >= cutoff || g.upper - g.lower <= kTolerance) return g.lower;
    // Rounding stalled it: the separating-axis test and the polytope's triangles.
    return distance_convex_triangle_by_faces(poly, triangles, triangle_count, a, b, c);
}

}  // namespace sulcus
