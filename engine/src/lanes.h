// Four lanes of doubles (AVX2) that take the scalar code's operations in its order, so that a
// loop run four at a time gives the scalar loop's answers to the bit (the build does not
// contract products and sums).
#pragma once

#if defined(__AVX2__)
#include <immintrin.h>

#include <cmath>

#include "sulcus/engine/types.h"

namespace sulcus {

// std::min and std::max as the scalar code takes them (the second where it is less, or greater;
// else the first), so that zeros keep their sign and NaN its place.
inline __m256d lanes_min(__m256d a, __m256d b) { return _mm256_blendv_pd(a, b, _mm256_cmp_pd(b, a, _CMP_LT_OQ)); }
inline __m256d lanes_max(__m256d a, __m256d b) { return _mm256_blendv_pd(a, b, _mm256_cmp_pd(a, b, _CMP_LT_OQ)); }
// glm::dot: (x1 x2 + y1 y2) + z1 z2.
inline __m256d lanes_dot(__m256d x1, __m256d y1, __m256d z1, __m256d x2, __m256d y2, __m256d z2) {
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x1, x2), _mm256_mul_pd(y1, y2)), _mm256_mul_pd(z1, z2));
}
inline __m256d lanes_of(double v) { return _mm256_set1_pd(v); }

// Four consecutive vectors (v[0, 4)) as one register per coordinate.
inline void lanes_of_vectors(const Vec3* v, __m256d& x, __m256d& y, __m256d& z) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "a vector is three doubles, packed");
    const double* p = &v[0].x;
    // r0 = (x0 y0)(z0 x1), r1 = (y1 z1)(x2 y2), r2 = (z2 x3)(y3 z3), in 128-bit halves.
    const __m256d r0 = _mm256_loadu_pd(p), r1 = _mm256_loadu_pd(p + 4), r2 = _mm256_loadu_pd(p + 8);
    const __m256d zx = _mm256_permute2f128_pd(r0, r2, 0x21);  // (z0 x1)(z2 x3)
    const __m256d xy = _mm256_permute2f128_pd(r0, r1, 0x30);  // (x0 y0)(x2 y2)
    const __m256d yz = _mm256_permute2f128_pd(r1, r2, 0x30);  // (y1 z1)(y3 z3)
    x = _mm256_shuffle_pd(xy, zx, 0xA);
    y = _mm256_shuffle_pd(xy, yz, 0x5);
    z = _mm256_shuffle_pd(zx, yz, 0xA);
}

// Four vectors from one register per coordinate back to v[0, 4), as lanes_of_vectors took them.
inline void store_lanes_as_vectors(__m256d x, __m256d y, __m256d z, Vec3* v) {
    double* p = &v[0].x;
    const __m256d xy = _mm256_unpacklo_pd(x, y);         // (x0 y0)(x2 y2)
    const __m256d zx = _mm256_shuffle_pd(z, x, 0xA);      // (z0 x1)(z2 x3)
    const __m256d yz = _mm256_unpackhi_pd(y, z);          // (y1 z1)(y3 z3)
    _mm256_storeu_pd(p, _mm256_permute2f128_pd(xy, zx, 0x20));      // x0 y0 z0 x1
    _mm256_storeu_pd(p + 4, _mm256_permute2f128_pd(yz, xy, 0x30));  // y1 z1 x2 y2
    _mm256_storeu_pd(p + 8, _mm256_permute2f128_pd(zx, yz, 0x31));  // z2 x3 y3 z3
}

// A rotation quaternion applied to four vectors as glm's q * v: with u = (q.x, q.y, q.z),
// v + ((u x v) q.w + u x (u x v)) 2, the cross products as glm::cross takes them.
struct LanesRotation {
    __m256d x, y, z, w;
    explicit LanesRotation(const Quat& q) : x(lanes_of(q.x)), y(lanes_of(q.y)), z(lanes_of(q.z)), w(lanes_of(q.w)) {}
    void apply(__m256d& vx, __m256d& vy, __m256d& vz) const {
        const __m256d ux = _mm256_sub_pd(_mm256_mul_pd(y, vz), _mm256_mul_pd(vy, z));
        const __m256d uy = _mm256_sub_pd(_mm256_mul_pd(z, vx), _mm256_mul_pd(vz, x));
        const __m256d uz = _mm256_sub_pd(_mm256_mul_pd(x, vy), _mm256_mul_pd(vx, y));
        const __m256d uux = _mm256_sub_pd(_mm256_mul_pd(y, uz), _mm256_mul_pd(uy, z));
        const __m256d uuy = _mm256_sub_pd(_mm256_mul_pd(z, ux), _mm256_mul_pd(uz, x));
        const __m256d uuz = _mm256_sub_pd(_mm256_mul_pd(x, uy), _mm256_mul_pd(ux, y));
        const __m256d two = lanes_of(2.0);
        vx = _mm256_add_pd(vx, _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(ux, w), uux), two));
        vy = _mm256_add_pd(vy, _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(uy, w), uuy), two));
        vz = _mm256_add_pd(vz, _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(uz, w), uuz), two));
    }
};

// Aabb::overlaps of a box against a fixed query box, by two compares of four lanes: the query
// taken once as its upper corner (then +inf) and (-inf then) its lower corner.
struct LanesBoxQuery {
    __m256d upper, lower;
    explicit LanesBoxQuery(const Aabb& q)
        : upper(_mm256_setr_pd(q.hi.x, q.hi.y, q.hi.z, HUGE_VAL)),
          lower(_mm256_setr_pd(-HUGE_VAL, q.lo.x, q.lo.y, q.lo.z)) {}
    // box.lo <= q.hi and q.lo <= box.hi on every axis, false where any is NaN, as Aabb::overlaps.
    bool overlaps(const Aabb& box) const {
        static_assert(sizeof(Aabb) == 6 * sizeof(double), "a box is six doubles, lower corner first");
        const double* p = &box.lo.x;
        const __m256d first = _mm256_loadu_pd(p);      // lo.x lo.y lo.z hi.x
        const __m256d last = _mm256_loadu_pd(p + 2);   // lo.z hi.x hi.y hi.z
        const __m256d ok = _mm256_and_pd(_mm256_cmp_pd(first, upper, _CMP_LE_OQ), _mm256_cmp_pd(last, lower, _CMP_GE_OQ));
        return _mm256_movemask_pd(ok) == 0xF;
    }
};

// The box of v[0, n), as Aabb::grow over them in turn gives it (a NaN coordinate left out as
// there), four vectors at a time; the same numbers but for the sign of a zero coordinate, which
// the order of the comparisons may give either way.
inline Aabb lanes_bounds(const Vec3* v, int n) {
    Aabb box;
    int i = 0;
    if (n >= 4) {
        __m256d lx = lanes_of(box.lo.x), ly = lanes_of(box.lo.y), lz = lanes_of(box.lo.z);
        __m256d hx = lanes_of(box.hi.x), hy = lanes_of(box.hi.y), hz = lanes_of(box.hi.z);
        for (; i + 4 <= n; i += 4) {
            __m256d x, y, z;
            lanes_of_vectors(v + i, x, y, z);
            lx = lanes_min(lx, x), ly = lanes_min(ly, y), lz = lanes_min(lz, z);
            hx = lanes_max(hx, x), hy = lanes_max(hy, y), hz = lanes_max(hz, z);
        }
        alignas(32) double lo[3][4], hi[3][4];
        _mm256_store_pd(lo[0], lx), _mm256_store_pd(lo[1], ly), _mm256_store_pd(lo[2], lz);
        _mm256_store_pd(hi[0], hx), _mm256_store_pd(hi[1], hy), _mm256_store_pd(hi[2], hz);
        for (int k = 0; k < 4; ++k) box.grow(Aabb{Vec3(lo[0][k], lo[1][k], lo[2][k]), Vec3(hi[0][k], hi[1][k], hi[2][k])});
    }
    for (; i < n; ++i) box.grow(v[i]);
    return box;
}

}  // namespace sulcus
#endif
