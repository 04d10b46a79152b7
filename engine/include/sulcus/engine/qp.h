// The small quadratic program at the heart of the servo step (seed paper eq. 1-5):
//
//   minimise   1/2 (x - t)^T W (x - t)          W = diag(weight) > 0, x in R^6
//   subject to a_i . x >= b_i                   i < rows   (linearized non-penetration, eq. 6-8)
//              lower <= x <= upper                          (the local-solution box, eq. 5)
//
// Solved by a dual active-set method (Goldfarb-Idnani) written for this 6-variable problem:
// fixed-size storage, no heap allocation, a hard iteration cap, deterministic tie-breaking and a
// named status for every way it can end. With u = W^(1/2)(x - t) the problem is the projection
// of the origin onto a polytope, which the dual method walks towards from the unconstrained
// minimum, so it needs no feasible starting point.
#pragma once

#include <cstdint>

namespace sulcus::qp {

inline constexpr int kVars = 6;
inline constexpr int kMaxRows = 192;  // general rows; the 12 box rows are extra

struct Problem {
    double weight[kVars];  // diagonal of W, each > 0
    double target[kVars];  // t: the unconstrained minimiser (the haptic configuration)
    double lower[kVars];   // box, lower[j] <= upper[j]; use +-infinity for no bound
    double upper[kVars];
    int rows = 0;          // general rows in use, 0..kMaxRows
    double a[kMaxRows][kVars];
    double b[kMaxRows];
};

enum class Status : uint8_t {
    Optimal,         // KKT point found: feasible within tolerance, multipliers >= 0
    Infeasible,      // the constraints admit no point (proved by the dual: an unbounded dual ray)
    IterationLimit,  // max_iterations reached; x is the last iterate and may be infeasible
    InvalidInput,    // NaN/Inf in the data, weight <= 0, lower > upper or rows out of range
};

const char* to_string(Status s);

struct Settings {
    // A row counts as satisfied when its scaled slack (a.x - b)/|W^(-1/2) a| >= -feasibility_tol.
    // The slack is then a distance in the W-metric. The tolerance is scaled by (1 + |c|), c the
    // row's scaled right-hand side (b - a.t)/|W^(-1/2) a|, so rounding is never a violation; a
    // row linearly dependent on the active set may also fall short by its dependency_tol-sized
    // tilt times |u| (it is then consistent with the active rows up to rounding).
    double feasibility_tol = 1e-12;
    // Relative threshold under which a new constraint is taken as linearly dependent on the
    // active set.
    double dependency_tol = 1e-12;
    int max_iterations = 64;
};

// Indices of constraints: 0..rows-1 are general rows; kBoxLower + j and kBoxUpper + j are the
// box bounds of variable j.
inline constexpr int kBoxLower = 1000;
inline constexpr int kBoxUpper = 2000;

struct Solution {
    double x[kVars] = {0, 0, 0, 0, 0, 0};
    Status status = Status::InvalidInput;
    int iterations = 0;            // constraint additions + removals performed
    int active_count = 0;          // constraints active at the solution (<= kVars)
    int active[kVars] = {};        // their indices (see kBoxLower/kBoxUpper)
    double multipliers[kVars] = {};  // Lagrange multipliers of the active constraints (>= 0)
    double objective = 0.0;        // 1/2 (x - t)^T W (x - t)
    double max_violation = 0.0;    // largest b_i - a_i.x over all rows and bounds (<= 0 when feasible)
};

// Optional warm start: constraints tried first, in order, when they are violated.
struct WarmStart {
    int count = 0;
    int active[kVars] = {};
};

// Solves the problem. Never allocates, never throws; the result is deterministic.
Status solve(const Problem& problem, const Settings& settings, const WarmStart* warm, Solution& out);

}  // namespace sulcus::qp
