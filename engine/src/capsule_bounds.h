// Lower bounds on the distance between a tool piece and a triangle from the piece's bounding
// capsules (ToolPiece::capsule_points, capsule_radii_m), as detect takes them for the triangles of
// a compliant object; and the same for four triangles at once.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "geometry.h"
#include "lanes.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/renderer.h"

namespace sulcus {

// A piece's capsules lie end to end along one line, so capsule j is no nearer to a triangle's
// bounding sphere than the gap along that line between the centre's projection and the capsule's
// stretch, less the radii. The capsule the centre projects into is measured first; a capsule whose
// gap alone puts it over that (by a nanometre, for rounding) cannot give the least bound nor tie
// it, and is not measured.
//
// The capsules come placed with their chain's line (capsule_line), the same for every triangle
// measured at one placement.
struct CapsuleLine {
    const Vec3* axis = nullptr;  // the capsules' points (kToolCapsules + 1, world)
    Vec3 chain{0.0};             // from the chain's first point to its last
    double length = 0.0;         // its length
    double stretch = 0.0;        // each capsule's share of it
    double axis_norm[kToolCapsules + 1] = {};  // each point's distance from the origin (m)
};
inline CapsuleLine capsule_line(const ToolPiece& piece, const Vec3* axis) {
    const Vec3 chain = axis[piece.capsule_count] - axis[0];
    const double length = glm::length(chain);
    CapsuleLine line{axis, chain, length, length / piece.capsule_count};
    for (int j = 0; j <= piece.capsule_count; ++j) line.axis_norm[j] = glm::length(axis[j]);
    return line;
}

// The least over the piece's capsules of capsule(j) for a triangle of bounding sphere ts, where
// capsule(j) is at least the sphere's bound against capsule j: the capsule the centre projects
// into first, then only those whose gap along the chain, less the radii, comes under what that
// one gave (by a nanometre, for rounding). `nearest` receives the capsule that gave it.
// With Count > 0 the piece has that many capsules (the loop then unrolls), else
// piece.capsule_count.
template <int Count, class Capsule>
inline double least_over_capsules_of(const ToolPiece& piece, const CapsuleLine& line, const TriangleSphere& ts,
                                     Capsule&& capsule, int& nearest) {
    const Vec3* axis = line.axis;
    const int count = Count > 0 ? Count : piece.capsule_count;
    const double length = line.length, stretch = line.stretch;
    const double along = length > 0.0 ? glm::dot(ts.centre - axis[0], line.chain) / length : 0.0;
    auto gap_bound = [&](int j) {
        const double gap = std::max(std::max(0.0, j * stretch - along), along - (j + 1) * stretch);
        return gap - ts.radius - piece.capsule_radii_m[size_t(j)];
    };
    const int first = stretch > 0.0 ? std::clamp(int(std::floor(along / stretch)), 0, count - 1) : 0;
    const double first_bound = capsule(first);
    double bound = 1e300;
    nearest = 0;
    for (int j = 0; j < count; ++j) {
        if (j != first && gap_bound(j) >= first_bound + 1e-9) continue;
        const double bj = j == first ? first_bound : capsule(j);
        if (bj < bound) {
            bound = bj;
            nearest = j;
        }
    }
    return bound;
}
template <class Capsule>
inline double least_over_capsules(const ToolPiece& piece, const CapsuleLine& line, const TriangleSphere& ts,
                                  Capsule&& capsule, int& nearest) {
    // A long piece has kToolCapsules of them (ToolPiece::capsule_count).
    if (piece.capsule_count == kToolCapsules)
        return least_over_capsules_of<kToolCapsules>(piece, line, ts, capsule, nearest);
    return least_over_capsules_of<0>(piece, line, ts, capsule, nearest);
}

// A lower bound on the separation of a piece and a triangle (a, b, e) of a compliant object, which
// the tool may be inside: where the capsules' tangent bounds (capsule_tangent_lower) put the
// triangle clear of every capsule, the least of them (the distance, which is the separation where
// they are apart); else the least over the capsules of the sphere's bound (capsule_sphere_lower),
// which bounds how deep they overlap as well.
inline double piece_compliant_bound(const ToolPiece& piece, const CapsuleLine& line, const TriangleSphere& ts,
                                    const Vec3& a, const Vec3& b, const Vec3& e) {
    int nearest = 0;
    const double apart = least_over_capsules(
        piece, line, ts,
        [&](int j) {
            return capsule_tangent_lower(line.axis[j], line.axis_norm[j], line.axis[j + 1],
                                         piece.capsule_radii_m[size_t(j)], ts, a, b, e);
        },
        nearest);
    if (apart > 0.0) return apart;
    return least_over_capsules(
        piece, line, ts,
        [&](int j) {
            return capsule_sphere_lower(line.axis[j], line.axis[j + 1], piece.capsule_radii_m[size_t(j)], ts);
        },
        nearest);
}

#if defined(__AVX2__)
// piece_compliant_bound of four triangles at once (triangle k: bounding sphere ts[k], corners
// v[k][0, 3)), into bounds[0, 4): every capsule's bounds taken for every triangle, and the least
// over the capsules taken as least_over_capsules_of takes it (the same capsules, in the same
// order), each by the same operations in the same order as the scalar code (the build does not
// contract products and sums): the same bounds to the bit. For a piece with capsules.
inline void piece_compliant_bound4(const ToolPiece& piece, const CapsuleLine& line, const TriangleSphere* const ts[4],
                                   const Vec3* const v[4][3], double bounds[4]) {
    const int count = piece.capsule_count;
    auto lanes = [&](auto get) { return _mm256_set_pd(get(3), get(2), get(1), get(0)); };
    const __m256d cx = lanes([&](int k) { return ts[k]->centre.x; });
    const __m256d cy = lanes([&](int k) { return ts[k]->centre.y; });
    const __m256d cz = lanes([&](int k) { return ts[k]->centre.z; });
    const __m256d radius = lanes([&](int k) { return ts[k]->radius; });
    const __m256d centre_norm = lanes([&](int k) { return ts[k]->centre_norm_m; });
    // The triangle's corners less its centre, as triangle_drop_along takes them.
    __m256d rx[3], ry[3], rz[3];
    for (int m = 0; m < 3; ++m) {
        rx[m] = _mm256_sub_pd(lanes([&](int k) { return v[k][m]->x; }), cx);
        ry[m] = _mm256_sub_pd(lanes([&](int k) { return v[k][m]->y; }), cy);
        rz[m] = _mm256_sub_pd(lanes([&](int k) { return v[k][m]->z; }), cz);
    }
    const Vec3* axis = line.axis;
    const __m256d zero = _mm256_setzero_pd(), one = lanes_of(1.0), minus = lanes_of(-0.0);
    __m256d along = zero;
    if (line.length > 0.0)
        along = _mm256_div_pd(lanes_dot(_mm256_sub_pd(cx, lanes_of(axis[0].x)), _mm256_sub_pd(cy, lanes_of(axis[0].y)),
                                        _mm256_sub_pd(cz, lanes_of(axis[0].z)), lanes_of(line.chain.x),
                                        lanes_of(line.chain.y), lanes_of(line.chain.z)),
                              lanes_of(line.length));
    __m256d first = zero;
    if (line.stretch > 0.0) {
        const __m128i j = _mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_div_pd(along, lanes_of(line.stretch))));
        first = _mm256_cvtepi32_pd(_mm_min_epi32(_mm_max_epi32(j, _mm_setzero_si128()), _mm_set1_epi32(count - 1)));
    }
    // Per capsule: the gap along the chain less the radii; the tangent bound and the sphere's, measured
    // only for a capsule some triangle needs (the one it projects into, or one whose gap comes under
    // what that one gave).
    __m256d gap[kToolCapsules], tangent[kToolCapsules], sphere[kToolCapsules], is_first[kToolCapsules];
    bool measured[kToolCapsules] = {};
    int firsts = 0;  // bit j: capsule j is some triangle's first
    for (int j = 0; j < count; ++j) {
        gap[j] = _mm256_sub_pd(
            _mm256_sub_pd(lanes_max(lanes_max(zero, _mm256_sub_pd(lanes_of(j * line.stretch), along)),
                                    _mm256_sub_pd(along, lanes_of((j + 1) * line.stretch))),
                          radius),
            lanes_of(piece.capsule_radii_m[size_t(j)]));
        is_first[j] = _mm256_cmp_pd(first, lanes_of(j), _CMP_EQ_OQ);
        if (_mm256_movemask_pd(is_first[j]) != 0) firsts |= 1 << j;
    }
    auto measure = [&](int j) {
        const double r = piece.capsule_radii_m[size_t(j)];
        const Vec3& p0 = axis[j];
        const Vec3 d = axis[j + 1] - p0;
        const double dd = glm::dot(d, d);
        const __m256d ox = _mm256_sub_pd(cx, lanes_of(p0.x)), oy = _mm256_sub_pd(cy, lanes_of(p0.y)),
                      oz = _mm256_sub_pd(cz, lanes_of(p0.z));
        __m256d s = zero;
        if (dd > 0.0) {
            const __m256d t =
                _mm256_div_pd(lanes_dot(ox, oy, oz, lanes_of(d.x), lanes_of(d.y), lanes_of(d.z)), lanes_of(dd));
            // std::clamp(t, 0, 1)
            s = _mm256_blendv_pd(t, one, _mm256_cmp_pd(one, t, _CMP_LT_OQ));
            s = _mm256_blendv_pd(s, zero, _mm256_cmp_pd(t, zero, _CMP_LT_OQ));
        }
        const __m256d qx = _mm256_sub_pd(ox, _mm256_mul_pd(s, lanes_of(d.x)));
        const __m256d qy = _mm256_sub_pd(oy, _mm256_mul_pd(s, lanes_of(d.y)));
        const __m256d qz = _mm256_sub_pd(oz, _mm256_mul_pd(s, lanes_of(d.z)));
        const __m256d f = _mm256_sqrt_pd(lanes_dot(qx, qy, qz, qx, qy, qz));
        // capsule_sphere_lower
        sphere[j] = _mm256_sub_pd(_mm256_sub_pd(f, radius), lanes_of(r));
        // capsule_tangent_lower: where f is not above zero, the sphere's.
        const __m256d room = _mm256_add_pd(
            lanes_of(1e-9),
            _mm256_mul_pd(lanes_of(1e-12),
                          _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(centre_norm, lanes_of(line.axis_norm[j])), f), radius)));
        const __m256d gx = _mm256_div_pd(qx, f), gy = _mm256_div_pd(qy, f), gz = _mm256_div_pd(qz, f);
        const __m256d least = lanes_min(lanes_min(lanes_dot(gx, gy, gz, rx[0], ry[0], rz[0]),
                                                  lanes_dot(gx, gy, gz, rx[1], ry[1], rz[1])),
                                        lanes_dot(gx, gy, gz, rx[2], ry[2], rz[2]));
        const __m256d drop = lanes_max(least, _mm256_xor_pd(radius, minus));
        const __m256d tb = _mm256_sub_pd(_mm256_sub_pd(_mm256_add_pd(f, drop), lanes_of(r)), room);
        tangent[j] = _mm256_blendv_pd(sphere[j], tb, _mm256_cmp_pd(f, zero, _CMP_GT_OQ));
        measured[j] = true;
    };
    for (int j = 0; j < count; ++j)
        if (firsts >> j & 1) measure(j);
    // least_over_capsules_of over the capsules' bounds `of` (tangent or sphere): a capsule every
    // triangle leaves out is not measured.
    auto least = [&](const __m256d* of) {
        __m256d first_bound = zero;
        for (int j = 0; j < count; ++j)
            if (firsts >> j & 1) first_bound = _mm256_blendv_pd(first_bound, of[j], is_first[j]);
        const __m256d over = _mm256_add_pd(first_bound, lanes_of(1e-9));
        __m256d bound = lanes_of(1e300);
        for (int j = 0; j < count; ++j) {
            const __m256d skip = _mm256_andnot_pd(is_first[j], _mm256_cmp_pd(gap[j], over, _CMP_GE_OQ));
            if (_mm256_movemask_pd(skip) == 0xF) continue;
            if (!measured[j]) measure(j);
            const __m256d take = _mm256_andnot_pd(skip, _mm256_cmp_pd(of[j], bound, _CMP_LT_OQ));
            bound = _mm256_blendv_pd(bound, of[j], take);
        }
        return bound;
    };
    const __m256d apart = least(tangent);
    __m256d bound = apart;
    const __m256d is_apart = _mm256_cmp_pd(apart, zero, _CMP_GT_OQ);
    if (_mm256_movemask_pd(is_apart) != 0xF) bound = _mm256_blendv_pd(least(sphere), apart, is_apart);
    _mm256_storeu_pd(bounds, bound);
}
#endif

}  // namespace sulcus
