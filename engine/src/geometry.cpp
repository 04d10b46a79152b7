#include "geometry.h"
#include "lanes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace sulcus {

TriClosest closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    TriClosest r;
    closest_point_on_triangle(p, a, b, c, b - a, c - a, r);
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

// The polytope's extent [pmin, pmax] along n, by looking at every vertex.
inline void extent_along(const ConvexView& poly, const Vec3& n, double& pmin, double& pmax) {
    pmin = 1e300;
    pmax = -1e300;
    for (int i = 0; i < poly.vertex_count; ++i) {
        const double v = glm::dot(n, poly.vertices[i]);
        pmin = std::min(pmin, v);
        pmax = std::max(pmax, v);
    }
}

// A four-lane mask's bit j moved to bit 0 of byte j.
constexpr uint32_t kLaneBytes[16] = {0x00000000, 0x00000001, 0x00000100, 0x00000101, 0x00010000, 0x00010001,
                                     0x00010100, 0x00010101, 0x01000000, 0x01000001, 0x01000100, 0x01000101,
                                     0x01010000, 0x01010001, 0x01010100, 0x01010101};

// extent_along with four vertices at a time, where that gives its answer to the bit: the products
// are the same, and the least and greatest of a set of numbers do not depend on the order they
// are taken in, except for the sign of a zero (then false, and the caller looks one at a time).
inline bool extent_four_at_a_time(const ConvexView& poly, const Vec3& n, double& pmin, double& pmax) {
#if defined(__AVX2__)
    const __m256d nx = lanes_of(n.x), ny = lanes_of(n.y), nz = lanes_of(n.z);
    __m256d lo = lanes_of(1e300), hi = lanes_of(-1e300);
    int i = 0;
    for (; i + 4 <= poly.vertex_count; i += 4) {
        __m256d x, y, z;
        lanes_of_vectors(poly.vertices + i, x, y, z);
        const __m256d v = lanes_dot(nx, ny, nz, x, y, z);
        lo = lanes_min(lo, v);
        hi = lanes_max(hi, v);
    }
    alignas(32) double l[4], h[4];
    _mm256_store_pd(l, lo);
    _mm256_store_pd(h, hi);
    pmin = std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
    pmax = std::max(std::max(h[0], h[1]), std::max(h[2], h[3]));
    for (; i < poly.vertex_count; ++i) {
        const double v = glm::dot(n, poly.vertices[i]);
        pmin = std::min(pmin, v);
        pmax = std::max(pmax, v);
    }
    return pmin != 0.0 && pmax != 0.0;
#else
    (void)poly;
    (void)n;
    (void)pmin;
    (void)pmax;
    return false;
#endif
}

// Separation along unit axis n (extent_gap), the polytope's extent by looking at every vertex.
inline double axis_separation(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                              double& sign) {
    double pmin, pmax;
    extent_along(poly, n, pmin, pmax);
    return extent_gap(pmin, pmax, n, a, b, c, sign);
}

}  // namespace

double gap_along_axis_by_descent(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                                 int* extremes) {
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

double gap_along_axis(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                      int* extremes) {
    double sign = 1.0;
    if (!extremes || !poly.neighbours) return axis_separation(poly, n, a, b, c, sign);
    // A piece of a few dozen vertices: all of them, four at a time, which takes fewer steps than
    // the two descents and none that branches on a vertex (a descent's steps are as good as
    // random to the branch predictor). The same extent (extent_four_at_a_time; where it cannot
    // say so, the descent).
    double pmin, pmax;
    if (poly.vertex_count <= kScanVertices && extent_four_at_a_time(poly, n, pmin, pmax))
        return extent_gap(pmin, pmax, n, a, b, c, sign);
    return gap_along_axis_by_descent(poly, n, a, b, c, extremes);
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

SatResult separate_convex_triangle(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                   bool four_at_a_time) {
    return separate_convex_triangle_until(poly, a, b, c, std::numeric_limits<double>::infinity(), four_at_a_time);
}

SatResult separate_convex_triangle_until(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                         double enough, bool four_at_a_time) {
    (void)four_at_a_time;  // without AVX2, one at a time
    SatResult best;
    best.separation = -1e300;
    // Whether an axis's gap has reached `enough`: the test stops there.
    auto reached = [&] { return best.separation >= enough; };
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
    if (tl > 0.0) {
        const Vec3 axis = tn / tl;
        double sign = 1.0;
        double pmin, pmax;
        if (!(four_at_a_time && extent_four_at_a_time(poly, axis, pmin, pmax))) extent_along(poly, axis, pmin, pmax);
        keep(extent_gap(pmin, pmax, axis, a, b, c, sign), sign, axis, 0, 0);
        if (reached()) return best;
    }
    const bool fast = poly.depths && poly.edge_normals && poly.rotation;
    int f = 0;
#if defined(__AVX2__)
    // Four faces at a time: extent_gap's operations in its order, the gaps kept in face order.
    if (fast && four_at_a_time) {
        const __m256d ax = lanes_of(a.x), ay = lanes_of(a.y), az = lanes_of(a.z);
        const __m256d bx = lanes_of(b.x), by = lanes_of(b.y), bz = lanes_of(b.z);
        const __m256d cx = lanes_of(c.x), cy = lanes_of(c.y), cz = lanes_of(c.z);
        for (; f + 4 <= poly.face_count; f += 4) {
            __m256d nx, ny, nz;
            lanes_of_vectors(poly.normals + f, nx, ny, nz);
            const __m256d pmax = _mm256_loadu_pd(poly.offsets + f);
            const __m256d pmin = _mm256_sub_pd(pmax, _mm256_loadu_pd(poly.depths + f));
            const __m256d ta = lanes_dot(nx, ny, nz, ax, ay, az), tb = lanes_dot(nx, ny, nz, bx, by, bz),
                          tc = lanes_dot(nx, ny, nz, cx, cy, cz);
            const __m256d tmin = lanes_min(ta, lanes_min(tb, tc)), tmax = lanes_max(ta, lanes_max(tb, tc));
            const __m256d pos = _mm256_sub_pd(pmin, tmax), neg = _mm256_sub_pd(tmin, pmax);
            const int positive = _mm256_movemask_pd(_mm256_cmp_pd(pos, neg, _CMP_GE_OQ));
            alignas(32) double s[4];
            _mm256_store_pd(s, lanes_max(pos, neg));
            for (int j = 0; j < 4; ++j) keep(s[j], (positive >> j & 1) ? 1.0 : -1.0, poly.normals[f + j], 1, f + j);
            if (reached()) return best;
        }
    }
#endif
    for (; f < poly.face_count; ++f) {
        if (!fast) {
            consider(poly.normals[f], 1, f);
            if (reached()) return best;
            continue;
        }
        // The polytope spans [offset - depth, offset] along its own face normal.
        const Vec3& n = poly.normals[f];
        double sign = 1.0;
        const double s = extent_gap(poly.offsets[f] - poly.depths[f], poly.offsets[f], n, a, b, c, sign);
        keep(s, sign, n, 1, f);
        if (reached()) return best;
    }
    const Vec3 te[3] = {b - a, c - b, a - c};
    // Edge pairs: only those that form a face of the Minkowski difference can be the separating
    // axis of least overlap (their arcs on the Gauss map cross). The triangle's edge k maps to the
    // half great circle of normals perpendicular to it on its outer side; the polytope's edge to the
    // arc between its two face normals. Tested in the polytope's frame.
    Vec3 e_local[3], out_local[3];
    // The polytope's turn as a matrix, for turning each crossing pair's normal x into the world
    // (a third of the quaternion's operations).
    Mat3 turn(1.0);
    if (fast && tl > 0.0) {
        turn = glm::mat3_cast(*poly.rotation);
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
        if (glm::dot(x, x) > 0.0) {  // its length is not zero
            // A face of the Minkowski difference: along its normal (x, in the edge's normal
            // cone) the polytope reaches farthest at this edge, so its extent is one dot.
            Vec3 n = u / ul;
            if (glm::dot(n, turn * x) < 0.0) n = -n;
            const double pmax = glm::dot(n, poly.vertices[poly.edges[e][0]]);
            const double tmin = std::min(glm::dot(n, a), std::min(glm::dot(n, b), glm::dot(n, c)));
            keep(tmin - pmax, -1.0, n, 2, k * poly.edge_count + e);
            return;
        }
        consider(u / ul, 2, k * poly.edge_count + e);
    };
    if (!(fast && tl > 0.0)) {
        for (int k = 0; k < 3; ++k)
            for (int e = 0; e < poly.edge_count; ++e) {
                edge_pair(k, e, Vec3(0.0));
                if (reached()) return best;
            }
        return best;
    }
    // The arcs cross where the edge's two normals are not both on one side of the plane normal to
    // the triangle's edge, and x, their blend on that plane, faces out of the triangle.
    auto arcs_cross = [&](int k, int e, double al, double be, double out_length) {
        const Vec3 x = std::abs(be) * poly.edge_normals[e][0] + std::abs(al) * poly.edge_normals[e][1];
        // (The right side is never negative: no length is needed where the left is not positive.)
        const double outward = glm::dot(x, out_local[k]);
        if (outward > 0.0 && outward > 1e-9 * glm::length(x) * out_length) return;
        edge_pair(k, e, x);
    };
    // Where the polytope's triangles fit the table, each triangle normal's dot product with the
    // triangle's edge (the same products as taken edge by edge) and its side are taken once for
    // every polytope edge at it.
    constexpr int kTableTriangles = 256, kTableEdges = 3 * kTableTriangles / 2;
    const bool table = poly.triangle_normals && poly.edge_triangles && poly.triangle_count <= kTableTriangles &&
                       poly.edge_count <= kTableEdges;
    // along[k][t]: triangle t's normal along the triangle's edge k; sides[t], bits 2k and 2k + 1:
    // above the tolerance, below it; shared[e]: the bits the two triangles at edge e share (both
    // above or both below: the arcs do not cross), padded with ones to whole registers.
    double along[3][kTableTriangles];
    uint8_t sides[kTableTriangles];
    alignas(32) uint8_t shared[kTableEdges + 32];
    const double tol[3] = {1e-12 * scale_e[0], 1e-12 * scale_e[1], 1e-12 * scale_e[2]};
    if (table) {
        int t = 0;
#if defined(__AVX2__)
        // Four triangle normals at a time, against the three edges.
        for (; four_at_a_time && t + 4 <= poly.triangle_count; t += 4) {
            __m256d nx, ny, nz;
            lanes_of_vectors(poly.triangle_normals + t, nx, ny, nz);
            // The four triangles' side bytes in one word, byte j for triangle t + j (x86 is
            // little-endian): a lane mask's bit j spread to bit 0 of byte j by a table.
            uint32_t bytes = 0;
            for (int k = 0; k < 3; ++k) {
                const __m256d d =
                    lanes_dot(nx, ny, nz, lanes_of(e_local[k].x), lanes_of(e_local[k].y), lanes_of(e_local[k].z));
                _mm256_storeu_pd(along[k] + t, d);
                const int above = _mm256_movemask_pd(_mm256_cmp_pd(d, lanes_of(tol[k]), _CMP_GT_OQ));
                const int below = _mm256_movemask_pd(_mm256_cmp_pd(d, lanes_of(-tol[k]), _CMP_LT_OQ));
                bytes |= (kLaneBytes[above] | kLaneBytes[below] << 1) << 2 * k;
            }
            std::memcpy(sides + t, &bytes, sizeof bytes);
        }
#endif
        for (; t < poly.triangle_count; ++t) {
            int bits = 0;
            for (int k = 0; k < 3; ++k) {
                const double d = glm::dot(poly.triangle_normals[t], e_local[k]);
                along[k][t] = d;
                bits |= ((d > tol[k] ? 1 : 0) | (d < -tol[k] ? 2 : 0)) << 2 * k;
            }
            sides[t] = uint8_t(bits);
        }
        for (int e = 0; e < poly.edge_count; ++e)
            shared[e] = sides[poly.edge_triangles[e][0]] & sides[poly.edge_triangles[e][1]];
        std::fill(shared + poly.edge_count, shared + ((poly.edge_count + 31) & ~31), uint8_t(0xff));
    }
    for (int k = 0; k < 3; ++k) {
        const double out_length = glm::length(out_local[k]);
        if (!table) {
            for (int e = 0; e < poly.edge_count; ++e) {
                const double al = glm::dot(poly.edge_normals[e][0], e_local[k]);
                const double be = glm::dot(poly.edge_normals[e][1], e_local[k]);
                if ((al > tol[k] && be > tol[k]) || (al < -tol[k] && be < -tol[k])) continue;
                arcs_cross(k, e, al, be, out_length);
                if (reached()) return best;
            }
            continue;
        }
        auto open = [&](int e) {
            arcs_cross(k, e, along[k][poly.edge_triangles[e][0]], along[k][poly.edge_triangles[e][1]], out_length);
        };
        int e = 0;
#if defined(__AVX2__)
        // Thirty-two edges at a time: those whose triangles share no side, in their order.
        if (four_at_a_time) {
            const __m256i side_k = _mm256_set1_epi8(char(3 << 2 * k)), zero = _mm256_setzero_si256();
            for (; e < poly.edge_count; e += 32) {
                const __m256i m = _mm256_load_si256(reinterpret_cast<const __m256i*>(shared + e));
                uint32_t crossing =
                    uint32_t(_mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_and_si256(m, side_k), zero)));
                for (; crossing != 0; crossing &= crossing - 1) {
                    open(e + __builtin_ctz(crossing));
                    if (reached()) return best;
                }
            }
        }
#endif
        for (; e < poly.edge_count; ++e)
            if (!(shared[e] >> 2 * k & 3)) {
                open(e);
                if (reached()) return best;
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
