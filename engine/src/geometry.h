// Geometric primitives used by the servo step: closest points with their features, segment
// distances, and separating-axis tests between the convex tool and one triangle.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

namespace sulcus {

// Which feature of a triangle holds the closest point: the face, an edge (k: v[k] -> v[k+1]) or a
// vertex k.
enum class TriRegion : uint8_t { Face, Edge0, Edge1, Edge2, Vertex0, Vertex1, Vertex2 };

struct TriClosest {
    Vec3 point;
    double distance = 0.0;
    TriRegion region = TriRegion::Face;
};

// Closest point of triangle (a, b, c) to p, with the feature it lies on.
TriClosest closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// How far point `foot`, on the plane of triangle t (unit normal n), is from every point of that
// plane whose closest point on the triangle lies on edge k (t[k] to t[k + 1], TriRegion::Edge0 +
// k): the strip beyond the edge between the lines across it through its ends. 0 for a triangle
// with no area.
inline double distance_to_edge_region(const Vec3 t[3], const Vec3& n, const Vec3& foot, int k) {
    const Vec3& a = t[k];
    const Vec3 ab = t[(k + 1) % 3] - a;
    Vec3 out = glm::cross(ab, n);  // across the edge, away from the third corner
    if (glm::dot(out, t[(k + 2) % 3] - a) > 0.0) out = -out;
    const double length = std::sqrt(glm::dot(ab, ab)), width = std::sqrt(glm::dot(out, out));
    if (!(length > 0.0) || !(width > 0.0)) return 0.0;
    const Vec3 f = foot - a;
    const double along = glm::dot(f, ab) / length, over = glm::dot(f, out) / width;
    const double before = along < 0.0 ? -along : along > length ? along - length : 0.0;
    const double inside = over < 0.0 ? -over : 0.0;
    return std::sqrt(before * before + inside * inside);
}

// Whether sqrt(x) > f, as the rounded root compares, for f > 0: decided without the root where x
// is further than a part in 2^50 from f squared (there the root is more than half an ulp of f
// from f, and no rounding turns the answer), by the root itself only within that band. A NaN x
// gives false, as the root's comparison does.
inline bool root_exceeds(double x, double f) {
    const double f2 = f * f;
    if (x > f2 * (1.0 + 0x1p-49)) return true;
    if (x < f2 * (1.0 - 0x1p-49)) return false;
    return std::sqrt(x) > f;
}

// closest_on_triangle's point and feature, without the distance; ab = b - a and ac = c - a.
inline void closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& ab,
                                      const Vec3& ac, TriClosest& r) {
    // Voronoi regions of the triangle, tested in turn (vertex, edge, face).
    const Vec3 ap = p - a;
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
}

// closest_on_triangle(p, a, b, c) where its distance is no more than `within` (false, and `r`
// without its distance, where it is): the same point, feature and distance, but no square root
// for a point clearly further (root_exceeds). The caller gives the edges ab = b - a and
// ac = c - a, taken once for the several points it tests against one triangle.
// (Inline: gather calls it for some eight hundred tool vertices a tick in the tissue.)
inline bool closest_on_triangle_within(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& ab,
                                       const Vec3& ac, double within, TriClosest& r) {
    closest_point_on_triangle(p, a, b, c, ab, ac, r);
    const Vec3 d = p - r.point;
    const double d2 = glm::dot(d, d);
    if (root_exceeds(d2, within)) return false;
    r.distance = std::sqrt(d2);
    return true;
}

struct SegmentClosest {
    double s = 0.0, t = 0.0;  // parameters on [p0,p1] and [q0,q1]
    double distance = 0.0;
};

// The parameters s on [p0,p1] and t on [q0,q1] of the closest points of the two segments
// (parallel segments handled), without their distance.
// The same from the segments' directions d1 = p1 - p0 and d2 = q1 - q0, w = p0 - q0, and the
// squared lengths a = d1 . d1 and e = d2 . d2, for a caller that has them.
inline void closest_segment_params(const Vec3& d1, const Vec3& d2, const Vec3& w, double a, double e, double& s,
                                   double& t) {
    const double f = glm::dot(d2, w);
    s = 0.0;
    t = 0.0;
    if (a <= 0.0 && e <= 0.0) return;
    if (a <= 0.0) {
        t = std::clamp(f / e, 0.0, 1.0);
        return;
    }
    const double c = glm::dot(d1, w);
    if (e <= 0.0) {
        s = std::clamp(-c / a, 0.0, 1.0);
        return;
    }
    const double b = glm::dot(d1, d2);
    const double denom = a * e - b * b;
    // Near-parallel segments: any s works; take the start and clamp.
    s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    t = (b * s + f) / e;
    if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
    }
}
// True where the closest points of the two segments certainly lie at an end of one of them (a
// parameter of 0 or 1 from closest_segment_params), from the same quantities taken in another
// frame or with other rounding: the parameters of the lines' closest points, each a numerator
// over denom = a e - (d1 . d2)^2, outside [0, 1] by at least 1e-8 over the squared sine of the
// angle between the segments (the least of a convex quadratic over the square lies on its
// border when its least over the plane is outside). False, deciding nothing, for segments
// within a squared sine of 1e-4 of parallel. Rounding that moves the parameters by less than
// that margin cannot make it wrong (the renderer's move into the tool's frame, measured on the
// bench scenes: at most 1e-10 at squared sines over 1e-2, 6e-9 between 1e-4 and 1e-3).
inline bool closest_at_an_end(const Vec3& d1, const Vec3& d2, const Vec3& w, double a, double e) {
    const double b = glm::dot(d1, d2), c = glm::dot(d1, w), f = glm::dot(d2, w);
    const double denom = a * e - b * b;
    const double room = 1e-8 * a * e;
    if (!(denom > 1e4 * room)) return false;
    const double s_num = b * f - c * e, t_num = a * f - b * c;
    return s_num < -room || s_num > denom + room || t_num < -room || t_num > denom + room;
}

// closest_at_an_end(line.along, d2, line.from - origin, line.length2, e) for the lines
// lines[hits[0, count)]: the hits it leaves open go to `open` in their order, and their number is
// returned. The same operations in the same order, so the same answers to the bit (the build does
// not contract products and sums); with AVX2, four lines at a time. `Line` is laid out as eight
// doubles: from (x, y, z), along (x, y, z), one unused, length2.
template <class Line>
inline int pairs_not_at_an_end(const Line* lines, const uint16_t* hits, int count, const Vec3& d2, const Vec3& origin,
                               double e, uint16_t* open) {
    static_assert(sizeof(Line) == 8 * sizeof(double), "a line is eight doubles");
    static_assert(offsetof(Line, from) == 0 && offsetof(Line, along) == 3 * sizeof(double) &&
                      offsetof(Line, length2) == 7 * sizeof(double),
                  "from, along and length2 where the four-wide loads take them");
    int n = 0, h = 0;
#if defined(__AVX2__)
    const __m256d d2x = _mm256_set1_pd(d2.x), d2y = _mm256_set1_pd(d2.y), d2z = _mm256_set1_pd(d2.z);
    const __m256d ox = _mm256_set1_pd(origin.x), oy = _mm256_set1_pd(origin.y), oz = _mm256_set1_pd(origin.z);
    const __m256d ev = _mm256_set1_pd(e);
    for (; h + 4 <= count; h += 4) {
        const double* l0 = &lines[hits[h]].from.x;
        const double* l1 = &lines[hits[h + 1]].from.x;
        const double* l2 = &lines[hits[h + 2]].from.x;
        const double* l3 = &lines[hits[h + 3]].from.x;
        // Each line's first four doubles (from, along.x) and last four (along.y, along.z, -,
        // length2), turned into one register per quantity.
        const __m256d a0 = _mm256_loadu_pd(l0), a1 = _mm256_loadu_pd(l1);
        const __m256d a2 = _mm256_loadu_pd(l2), a3 = _mm256_loadu_pd(l3);
        const __m256d b0 = _mm256_loadu_pd(l0 + 4), b1 = _mm256_loadu_pd(l1 + 4);
        const __m256d b2 = _mm256_loadu_pd(l2 + 4), b3 = _mm256_loadu_pd(l3 + 4);
        const __m256d ta = _mm256_unpacklo_pd(a0, a1), tb = _mm256_unpackhi_pd(a0, a1);
        const __m256d tc = _mm256_unpacklo_pd(a2, a3), td = _mm256_unpackhi_pd(a2, a3);
        const __m256d fx = _mm256_permute2f128_pd(ta, tc, 0x20), fz = _mm256_permute2f128_pd(ta, tc, 0x31);
        const __m256d fy = _mm256_permute2f128_pd(tb, td, 0x20), d1x = _mm256_permute2f128_pd(tb, td, 0x31);
        const __m256d ua = _mm256_unpacklo_pd(b0, b1), ub = _mm256_unpackhi_pd(b0, b1);
        const __m256d uc = _mm256_unpacklo_pd(b2, b3), ud = _mm256_unpackhi_pd(b2, b3);
        const __m256d d1y = _mm256_permute2f128_pd(ua, uc, 0x20);
        const __m256d d1z = _mm256_permute2f128_pd(ub, ud, 0x20), a = _mm256_permute2f128_pd(ub, ud, 0x31);
        const __m256d wx = _mm256_sub_pd(fx, ox), wy = _mm256_sub_pd(fy, oy), wz = _mm256_sub_pd(fz, oz);
        auto dot = [](__m256d x1, __m256d y1, __m256d z1, __m256d x2, __m256d y2, __m256d z2) {
            return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x1, x2), _mm256_mul_pd(y1, y2)), _mm256_mul_pd(z1, z2));
        };
        const __m256d b = dot(d1x, d1y, d1z, d2x, d2y, d2z);
        const __m256d c = dot(d1x, d1y, d1z, wx, wy, wz);
        const __m256d f = dot(d2x, d2y, d2z, wx, wy, wz);
        const __m256d denom = _mm256_sub_pd(_mm256_mul_pd(a, ev), _mm256_mul_pd(b, b));
        const __m256d room = _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(1e-8), a), ev);
        const __m256d decides = _mm256_cmp_pd(denom, _mm256_mul_pd(_mm256_set1_pd(1e4), room), _CMP_GT_OQ);
        const __m256d s_num = _mm256_sub_pd(_mm256_mul_pd(b, f), _mm256_mul_pd(c, ev));
        const __m256d t_num = _mm256_sub_pd(_mm256_mul_pd(a, f), _mm256_mul_pd(b, c));
        const __m256d low = _mm256_xor_pd(room, _mm256_set1_pd(-0.0)), high = _mm256_add_pd(denom, room);
        const __m256d outside = _mm256_or_pd(
            _mm256_or_pd(_mm256_cmp_pd(s_num, low, _CMP_LT_OQ), _mm256_cmp_pd(s_num, high, _CMP_GT_OQ)),
            _mm256_or_pd(_mm256_cmp_pd(t_num, low, _CMP_LT_OQ), _mm256_cmp_pd(t_num, high, _CMP_GT_OQ)));
        const int at_end = _mm256_movemask_pd(_mm256_and_pd(decides, outside));
        for (int k = 0; k < 4; ++k)
            if (!(at_end >> k & 1)) open[n++] = hits[h + k];
    }
#endif
    for (; h < count; ++h) {
        const Line& line = lines[hits[h]];
        if (!closest_at_an_end(line.along, d2, line.from - origin, line.length2, e)) open[n++] = hits[h];
    }
    return n;
}

inline void closest_segment_params(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s,
                                   double& t) {
    const Vec3 d1 = p1 - p0, d2 = q1 - q0;
    closest_segment_params(d1, d2, p0 - q0, glm::dot(d1, d1), glm::dot(d2, d2), s, t);
}

// Closest points of segments [p0,p1] and [q0,q1] (parallel segments handled).
SegmentClosest closest_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1);

// A convex polytope in world coordinates: vertices, face planes (n . x <= d inside) and edges.
struct ConvexView {
    const Vec3* vertices = nullptr;
    int vertex_count = 0;
    const Vec3* normals = nullptr;  // world unit normals
    const double* offsets = nullptr;
    int face_count = 0;
    const uint32_t (*edges)[2] = nullptr;
    int edge_count = 0;
    // Optional, for the fast separating-axis test: the polytope's extent behind each face plane
    // (offset minus the smallest projection of a vertex on the normal), the two face normals at
    // each edge in the polytope's own frame, and the rotation of that frame into the world.
    const double* depths = nullptr;
    const Vec3 (*edge_normals)[2] = nullptr;
    const Quat* rotation = nullptr;
    // Optional with edge_normals: the polytope's triangles' normals in its own frame and, for each
    // edge, the two triangles whose normals edge_normals holds (the same values). The fast test
    // then takes a direction's dot product with each triangle normal once for all its edges.
    const Vec3* triangle_normals = nullptr;
    int triangle_count = 0;
    const uint32_t (*edge_triangles)[2] = nullptr;
    // Optional bounding capsules: capsule k is the segment capsule[k]-capsule[k + 1] with radius
    // capsule_radii[k]; every point of the polytope lies in one of them. Gives cheap lower bounds
    // on distance.
    const Vec3* capsule = nullptr;
    const double* capsule_radii = nullptr;
    int capsule_count = 0;
    // Optional, for a polytope certified for it (ToolPiece::descend): each corner's neighbouring
    // corners (vertex i's are neighbours[neighbour_offsets[i], neighbour_offsets[i + 1])) and
    // the corner a descent from each vertex starts at (itself, or one of its face's for a vertex
    // inside a flat face). The vertex least along a direction is then found by descending along
    // them from a nearby vertex: a corner with no neighbour lower is the least of all.
    const uint32_t* neighbour_offsets = nullptr;
    const uint32_t* neighbours = nullptr;
    const uint32_t* start_of = nullptr;
};

// The index of the vertex least along d of the polytope's `count` vertices. With neighbours
// (ConvexView::neighbours), by descent: from vertex start_of[start] (a corner of the polytope),
// to the neighbour least along d while one is lower than where it is. Else, or when start is out
// of range, by looking at every vertex. Ties go to the first found.
inline int least_along(const Vec3* vertices, int count, const uint32_t* neighbour_offsets, const uint32_t* neighbours,
                       const uint32_t* start_of, const Vec3& d, int start) {
    if (neighbours && start >= 0 && start < count) {
        int least = int(start_of[start]);
        double best = glm::dot(d, vertices[least]);
        for (int at = -1; at != least;) {
            at = least;
            for (uint32_t k = neighbour_offsets[at]; k < neighbour_offsets[at + 1]; ++k) {
                const int u = int(neighbours[k]);
                const double s = glm::dot(d, vertices[u]);
                if (s < best) {
                    best = s;
                    least = u;
                }
            }
        }
        return least;
    }
    int least = 0;
    double best = glm::dot(d, vertices[0]);
    for (int i = 1; i < count; ++i) {
        const double s = glm::dot(d, vertices[i]);
        if (s < best) {
            best = s;
            least = i;
        }
    }
    return least;
}

// Distance between segment p0-p1 and triangle (a, b, c); 0 when the segment crosses it.
double segment_triangle_distance(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c);

// A lower bound on the distance between capsule k (axis p0-p1, radius r) and a triangle: the
// triangle's bounding sphere `ts` against the capsule. Nearly exact for the small triangles of a
// dense mesh.
inline double capsule_sphere_lower(const Vec3& p0, const Vec3& p1, double r, const TriangleSphere& ts) {
    const Vec3 d = p1 - p0, off = ts.centre - p0;
    const double dd = glm::dot(d, d);
    const double s = dd > 0.0 ? std::clamp(glm::dot(off, d) / dd, 0.0, 1.0) : 0.0;
    return glm::length(off - s * d) - ts.radius - r;
}

// The least over triangle (a, b, e) of the offset from the centre of its sphere `ts` along unit
// direction g, no less than minus the sphere's radius: what a tangent plane with gradient g at the
// centre drops to over the triangle (at a vertex, the triangle being their hull).
inline double triangle_drop_along(const Vec3& g, const TriangleSphere& ts, const Vec3& a, const Vec3& b,
                                  const Vec3& e) {
    const double least = std::min(std::min(glm::dot(g, a - ts.centre), glm::dot(g, b - ts.centre)),
                                  glm::dot(g, e - ts.centre));
    return std::max(least, -ts.radius);
}

// A lower bound on the distance between capsule (axis p0-p1, radius r) and triangle (a, b, e) of
// bounding sphere `ts` (round its centroid), no less than capsule_sphere_lower but for a nanometre's
// room for rounding: the distance from the axis is a convex function, so over the triangle it is no
// less than its tangent plane at the centre, whose least is at a vertex. For a small triangle
// beside the capsule, within a few nanometres of their distance.
// With p0_norm = |p0|, which a caller bounding many triangles by one capsule finds once.
inline double capsule_tangent_lower(const Vec3& p0, double p0_norm, const Vec3& p1, double r, const TriangleSphere& ts,
                                    const Vec3& a, const Vec3& b, const Vec3& e) {
    const Vec3 d = p1 - p0, off = ts.centre - p0;
    const double dd = glm::dot(d, d);
    const double s = dd > 0.0 ? std::clamp(glm::dot(off, d) / dd, 0.0, 1.0) : 0.0;
    const Vec3 q = off - s * d;
    const double f = glm::length(q);
    if (!(f > 0.0)) return f - ts.radius - r;
    const double room = 1e-9 + 1e-12 * (ts.centre_norm_m + p0_norm + f + ts.radius);
    return f + triangle_drop_along(q / f, ts, a, b, e) - r - room;
}
inline double capsule_tangent_lower(const Vec3& p0, const Vec3& p1, double r, const TriangleSphere& ts, const Vec3& a,
                                    const Vec3& b, const Vec3& e) {
    return capsule_tangent_lower(p0, glm::length(p0), p1, r, ts, a, b, e);
}

// The same for the tapered capsule round axis p0-p1: the hull of the balls of radii r0 at p0 and
// r1 at p1 (|r0 - r1| less than their distance apart). Its distance from a point off it is convex
// too: from the near ball where the point is beyond the cone that touches both, else from that
// cone along its normal. Never more than the distance from the taper to the triangle.
inline double taper_tangent_lower(const Vec3& p0, const Vec3& p1, double r0, double r1, const TriangleSphere& ts,
                                  const Vec3& a, const Vec3& b, const Vec3& e) {
    const Vec3 d = p1 - p0, off = ts.centre - p0;
    const double length = glm::length(d);
    if (!(length > 0.0) || !(std::abs(r0 - r1) < length))
        return capsule_tangent_lower(p0, p1, std::max(r0, r1), ts, a, b, e);
    const Vec3 axis = d / length;
    const double s = glm::dot(off, axis);
    const Vec3 q = off - s * axis;
    const double rho = glm::length(q);
    const double sin_a = (r0 - r1) / length, cos_a = std::sqrt(std::max(0.0, 1.0 - sin_a * sin_a));
    const double along = s * cos_a - rho * sin_a;  // along the cone's side from where it meets ball 0
    double f;
    Vec3 g;
    if (along < 0.0) {
        f = glm::length(off);
        if (!(f > 0.0)) return f - ts.radius - r0;
        g = off / f;
        f -= r0;
    } else if (along > length * cos_a) {
        const Vec3 off1 = ts.centre - p1;
        f = glm::length(off1);
        if (!(f > 0.0)) return f - ts.radius - r1;
        g = off1 / f;
        f -= r1;
    } else {
        if (!(rho > 0.0)) return capsule_sphere_lower(p0, p1, std::max(r0, r1), ts);
        g = sin_a * axis + cos_a * (q / rho);
        f = s * sin_a + rho * cos_a - r0;
    }
    const double room = 1e-9 + 1e-12 * (glm::length(ts.centre) + glm::length(p0) + glm::length(off) + ts.radius);
    return f + triangle_drop_along(g, ts, a, b, e) - room;
}

// A lower bound on the distance between the polytope and the triangle from its bounding capsules
// (-infinity without them); <= 0 says nothing.
double capsule_lower_bound(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c);

// Largest separation of the convex polytope and triangle (a, b, c) over the separating-axis
// candidates (triangle normal, polytope face normals, edge cross products), in metres;
// negative when they overlap (then minus the smallest overlap over those axes).
// Reports the winning axis (unit, pointing from the triangle towards the polytope).
struct SatResult {
    double separation = 0.0;
    Vec3 axis{0.0};
    int kind = 0;   // 0 triangle normal, 1 polytope face, 2 edge pair
    int index = 0;  // face index (kind 1), or tri_edge * edge_count + poly_edge (kind 2)
};
// With AVX2 the fast test takes the face normals and the table four at a time, the scalar code's
// operations in its order: the same answer to the bit as `four_at_a_time = false`.
SatResult separate_convex_triangle(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                   bool four_at_a_time = true);
// The same test, stopped at the first axis (in the test's order) whose gap reaches `enough`: the
// answer is then that axis and its gap (at least `enough`, not always the largest); where none
// does, the whole test's answer. For a caller that only asks whether the separation reaches
// `enough`, which the answer says as the whole test's would.
SatResult separate_convex_triangle_until(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                         double enough, bool four_at_a_time = true);
// The gap between the polytope and triangle (a, b, c) along unit axis n, the larger of its two
// orientations (< 0: overlap along n). No more than their separation where they overlap (the
// least overlap over all axes), nor than their distance where they are apart.
// With `extremes` and a polytope certified for descent (ConvexView::neighbours): of one of at most
// kScanVertices vertices, every vertex four at a time (extremes untouched); of a larger one,
// gap_along_axis_by_descent. The same gap either way.
double gap_along_axis(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                      int* extremes = nullptr);
// gap_along_axis with the polytope's least and greatest vertices along n found by descending from
// extremes[0] and extremes[1] (vertex indices; out of range: by looking at every vertex), which
// receive them: the same gap, from a few vertices where the axis changes little from one call to
// the next. Needs a polytope certified for descent.
double gap_along_axis_by_descent(const ConvexView& poly, const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c,
                                 int* extremes);
// The most vertices of a polytope whose extent gap_along_axis takes by looking at every vertex.
inline constexpr int kScanVertices = 64;
// Whether a vertex of triangle (a, b, c) lies below `floor` (< 0) over every face plane of the
// polytope, i.e. inside it deeper than -floor. The ball of that radius round the vertex is then
// inside the polytope, so along every axis the two overlap by more: their separation is below
// floor (what separate_convex_triangle would find), for a few dot products. With `rejecting`, the
// face that last showed a vertex not that deep (an index, or -1) is tried first and receives the
// next such face: a triangle beside the polytope is settled by one face per vertex.
bool vertex_deep_inside(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c, double floor,
                        int* rejecting = nullptr);

// Bounds on the distance between a convex polytope (the hull of `count` points) and triangle
// (a, b, c), by the GJK iteration: lower <= distance <= upper, both 0 when they overlap or touch.
// Stops once the lower bound reaches `cutoff` (callers after the least distance over many
// triangles pass the least so far) or the bounds are within `tolerance` (m) of each other. The
// lower bound is a separating gap along a direction, so it holds whatever rounding did.
//
// The simplex GJK ends on names, for each of its points, the polytope vertex and the triangle
// vertex whose difference it is. A search for the same pair at a nearby pose can start from it
// (`warm`): the points are taken at the new pose, so whatever it holds only changes where the
// search starts, never a bound.
struct GjkSimplex {
    uint8_t count = 0;
    uint8_t tri[4] = {};
    uint16_t poly[4] = {};
};
struct DistanceBounds {
    double lower = 0.0;
    double upper = 1e300;
    int iterations = 0;
    // The last search direction (from the triangle towards the polytope; zero when they touch):
    // a good hint for the same pair at a nearby pose.
    Vec3 direction{0.0};
    // The gap along `direction` (unit): the least of (p - t) . direction / |direction| over the
    // polytope's points p and the triangle's t, a lower bound on their distance that a motion of the
    // polytope changes by its displacement along the direction and the turn times its radius
    // (NearCacheEntry::direction_gap). -1e300 where there is no direction.
    double direction_gap = -1e300;
    // The largest gap along any direction the search took: a lower bound on their separation, the
    // distance when apart and less than 0 by how far they overlap (-1e300 before a direction).
    double separation = -1e300;
    GjkSimplex simplex;  // the last simplex (count 0 when the hint alone settled it)
};
// `hint`, when given, is a direction roughly from the triangle towards the polytope: the search
// starts there; `warm`, when it has points, is the simplex an earlier search ended on (indices
// out of range are ignored). With max_iterations 0 there is no search: the bounds are the gap
// along the hint (0 without one) and the distance of the nearer of the hint's point of D and the
// warm simplex's closest point, a few hundred operations, tight for a pair that has hardly moved
// since the search that gave the hint and the simplex.
DistanceBounds convex_triangle_distance(const Vec3* poly, int count, const Vec3& a, const Vec3& b, const Vec3& c,
                                        double cutoff = 1e300, double tolerance = 1e-13, int max_iterations = 64,
                                        const Vec3* hint = nullptr, const GjkSimplex* warm = nullptr);
// The same for a polytope's view (its vertices).
DistanceBounds convex_triangle_distance(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                        double cutoff = 1e300, double tolerance = 1e-13, int max_iterations = 64,
                                        const Vec3* hint = nullptr, const GjkSimplex* warm = nullptr);

// The same search, for whether their separation is at least `settle_at` (which may be less than 0,
// an overlap that is allowed): it stops as soon as the gap along a search direction says so
// (DistanceBounds::separation >= settle_at), once the upper bound on the distance is under
// `give_up_below` (the separation is too), or where the distance search would stop. A pair resting
// in contact along the hint is settled by the hint's gap alone, where the distance search would
// go on to prove them apart or touching. With max_iterations 0 the answer is the hint's gap
// alone (-1e300 without a hint).
DistanceBounds convex_triangle_separation(const ConvexView& poly, const Vec3& a, const Vec3& b, const Vec3& c,
                                          double settle_at, double give_up_below = -1e300,
                                          const Vec3* hint = nullptr, const GjkSimplex* warm = nullptr,
                                          int max_iterations = 64);

// Distance between the convex polytope and a triangle: 0 when they touch or overlap; to within
// 1e-13 m (GJK), or exactly from the polytope's triangles when rounding stalls GJK. With a
// bounding capsule or a finite `cutoff`, a lower bound of at least `cutoff` is returned as soon as
// it is known (callers after the least distance over many triangles pass the least so far).
// `triangles` index poly.vertices.
double distance_convex_triangle(const ConvexView& poly, const uint32_t (*triangles)[3], int triangle_count,
                                const Vec3& a, const Vec3& b, const Vec3& c, double cutoff = 1e300);

// The same distance from the separating-axis test and the distances to the polytope's triangles
// it faces: the slow reference.
double distance_convex_triangle_by_faces(const ConvexView& poly, const uint32_t (*triangles)[3], int triangle_count,
                                         const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace sulcus
