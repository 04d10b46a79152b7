// Magnitude clamp and rate limit of the wrench sent to the device.
#include "sulcus/haptics/force_limits.h"

#include <algorithm>
#include <cmath>

namespace sulcus {
namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A usable limit: NaN and non-positive values fail safe to 0.
double usable(double limit) { return limit > 0.0 ? limit : 0.0; }

// Length without overflow for huge finite components (scaled by the largest one), so that the
// clamp keeps the direction even for values like 1e200.
double length(const Vec3& v) {
    const double m = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (m == 0.0) return 0.0;
    const Vec3 u = v / m;
    return m * std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
}

// Scales v down to length `limit` when longer; returns whether it did.
bool clamp_length(Vec3& v, double limit) {
    const double len = length(v);
    if (!(len > limit)) return false;
    if (limit == 0.0)
        v = Vec3(0.0);
    else
        v *= limit / len;
    return true;
}

// Moves from `prev` toward `target` by at most `step`; returns whether it was cut short.
bool limit_change(Vec3& target, const Vec3& prev, double step) {
    const Vec3 delta = target - prev;
    const double len = length(delta);
    if (!(len > step)) return false;
    target = step == 0.0 ? prev : prev + delta * (step / len);
    return true;
}

}  // namespace

WrenchOut limit_wrench(const ForceLimits& limits, Vec3 force_N, Vec3 torque_Nm, const Vec3& prev_force_N,
                       const Vec3& prev_torque_Nm, double dt_s) noexcept {
    WrenchOut out;
    if (!finite(force_N) || !finite(torque_Nm)) {
        // A NaN anywhere means the wrench cannot be trusted in any component: send nothing.
        out.non_finite_input = true;
        return out;
    }
    const double max_force = usable(limits.max_force_N);
    const double max_torque = usable(limits.max_torque_Nm);
    out.force_clamped = clamp_length(force_N, max_force);
    out.torque_clamped = clamp_length(torque_Nm, max_torque);

    // The previous output is ours and should be finite; if not, start again from zero.
    const Vec3 prev_f = finite(prev_force_N) ? prev_force_N : Vec3(0.0);
    const Vec3 prev_t = finite(prev_torque_Nm) ? prev_torque_Nm : Vec3(0.0);
    const double dt = (std::isfinite(dt_s) && dt_s > 0.0) ? dt_s : 0.0;
    const double force_step = dt > 0.0 ? usable(limits.max_force_rate_N_per_s) * dt : 0.0;
    const double torque_step = dt > 0.0 ? usable(limits.max_torque_rate_Nm_per_s) * dt : 0.0;
    const bool f_rate = limit_change(force_N, prev_f, force_step);
    const bool t_rate = limit_change(torque_Nm, prev_t, torque_step);
    out.rate_limited = f_rate || t_rate;

    // Stepping from a previous output inside the limit toward a clamped target stays inside
    // (the ball is convex); this only bites when the previous output came from looser limits.
    out.force_clamped = clamp_length(force_N, max_force) || out.force_clamped;
    out.torque_clamped = clamp_length(torque_Nm, max_torque) || out.torque_clamped;
    out.force_N = force_N;
    out.torque_Nm = torque_Nm;
    return out;
}

}  // namespace sulcus
