// The last guard before a wrench reaches the device (DESIGN.md, "Errors, safety and data"):
// whatever the simulation produced, the force and torque sent out are finite, within the
// device's magnitude limits, and change by no more than a bounded rate per servo tick.
#pragma once

#include "sulcus/engine/types.h"

namespace sulcus {

// Device limits. A limit that is not positive (or NaN) is taken as 0, which holds the output at
// zero: a broken configuration fails safe. +infinity switches a limit off.
struct ForceLimits {
    double max_force_N = 3.0;                // largest force magnitude sent to the device
    double max_torque_Nm = 0.1;              // largest torque magnitude sent to the device
    double max_force_rate_N_per_s = 1000.0;  // largest change of the force vector per second
    double max_torque_rate_Nm_per_s = 30.0;  // largest change of the torque vector per second
};

struct WrenchOut {
    Vec3 force_N{0.0};
    Vec3 torque_Nm{0.0};
    bool non_finite_input = false;  // the input had a NaN or infinity: the output is zero
    bool force_clamped = false;     // the force magnitude was cut to max_force_N
    bool torque_clamped = false;    // the torque magnitude was cut to max_torque_Nm
    bool rate_limited = false;      // force or torque changed slower than asked this tick
};

// Limits one tick's wrench. `prev_force`/`prev_torque` are what was sent last tick (the previous
// output of this function) and `dt_s` the tick length in seconds; a non-finite or non-positive
// dt_s allows no change this tick. Non-finite input gives a zero wrench with the flag set.
// Otherwise the magnitude is clamped keeping the direction, then the change from the previous
// output is cut to rate * dt_s (keeping the direction of the change). Never allocates or throws.
WrenchOut limit_wrench(const ForceLimits& limits, Vec3 force_N, Vec3 torque_Nm, const Vec3& prev_force_N,
                       const Vec3& prev_torque_Nm, double dt_s) noexcept;

}  // namespace sulcus
