// What the closed-loop tests share: a hand script of keyframes joined by smoothstep, and the
// range of a traced value over a time window.
#pragma once

#include "sulcus/engine/scene_file.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sulcus::test {

struct Key {
    double t;  // s
    Vec3 p;    // m
};

// Keyframes joined by smoothstep, sampled every 2 ms (the hand interpolates linearly between),
// at a fixed orientation.
inline std::vector<TrajectorySample> smooth_script(const std::vector<Key>& keys, const Quat& q = Quat(1, 0, 0, 0)) {
    std::vector<TrajectorySample> out;
    for (size_t k = 0; k + 1 < keys.size(); ++k) {
        const Key& a = keys[k];
        const Key& b = keys[k + 1];
        const int rows = static_cast<int>(std::lround((b.t - a.t) / 0.002));
        for (int i = (k == 0 ? 0 : 1); i <= rows; ++i) {
            const double u = static_cast<double>(i) / rows;
            const double s = u * u * (3.0 - 2.0 * u);
            out.push_back({a.t + (b.t - a.t) * u, Pose{a.p + (b.p - a.p) * s, q}});
        }
    }
    return out;
}

struct Window {
    double from, to;  // s, [from, to)
};

struct Range {
    double lo = 1e300, hi = -1e300, sum = 0;
    int n = 0;
    double span() const { return hi - lo; }
    double mean() const { return n ? sum / n : 0.0; }
};

// The range of v[i] over the samples whose time t[i] falls in w.
inline Range range(const std::vector<double>& t, const std::vector<double>& v, Window w) {
    Range r;
    for (size_t i = 0; i < v.size(); ++i) {
        if (t[i] < w.from || t[i] >= w.to) continue;
        r.lo = std::min(r.lo, v[i]);
        r.hi = std::max(r.hi, v[i]);
        r.sum += v[i];
        ++r.n;
    }
    return r;
}

}  // namespace sulcus::test
