// Rotation helpers for the servo step: rotation vectors, the exponential and logarithm maps and
// the left Jacobian of SO(3). The step's rotation variable is a world-frame rotation vector about
// the previous graphic orientation (R = Exp(theta) R0), not Euler angles.
#pragma once

#include "sulcus/engine/types.h"

#include <cmath>

namespace sulcus {

inline Mat3 skew(const Vec3& v) {
    // glm matrices are column-major: m[col][row].
    Mat3 m(0.0);
    m[1][0] = -v.z; m[2][0] = v.y;
    m[0][1] = v.z;  m[2][1] = -v.x;
    m[0][2] = -v.y; m[1][2] = v.x;
    return m;
}

// Quaternion of the rotation vector v (angle |v| about v/|v|).
inline Quat quat_exp(const Vec3& v) {
    const double a = glm::length(v);
    if (a < 1e-8) {
        // Second-order series keeps the map smooth through zero.
        const Quat q(1.0 - a * a / 8.0, 0.5 * v.x, 0.5 * v.y, 0.5 * v.z);
        return glm::normalize(q);
    }
    const double s = std::sin(0.5 * a) / a;
    return Quat(std::cos(0.5 * a), s * v.x, s * v.y, s * v.z);
}

// Rotation vector of q, angle in [0, pi].
inline Vec3 quat_log(Quat q) {
    if (q.w < 0.0) q = -q;
    const Vec3 v(q.x, q.y, q.z);
    const double s = glm::length(v);
    if (s < 1e-12) return 2.0 * v;  // first order: angle ~ 2 s
    const double angle = 2.0 * std::atan2(s, q.w);
    return (angle / s) * v;
}

// Left Jacobian J_l(phi): Exp(phi + d) ~ Exp(J_l(phi) d) Exp(phi) for small d.
inline Mat3 left_jacobian(const Vec3& phi) {
    const double t2 = glm::dot(phi, phi);
    const Mat3 k = skew(phi);
    double a, b;  // J = I + a K + b K^2
    if (t2 < 1e-10) {
        a = 0.5 - t2 / 24.0;
        b = 1.0 / 6.0 - t2 / 120.0;
    } else {
        const double t = std::sqrt(t2);
        a = (1.0 - std::cos(t)) / t2;
        b = (t - std::sin(t)) / (t2 * t);
    }
    return Mat3(1.0) + a * k + b * (k * k);
}

inline bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline bool finite(const Quat& q) {
    return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

}  // namespace sulcus
