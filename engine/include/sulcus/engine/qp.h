// The small quadratic program at the heart of the servo step (seed paper eq. 1-5):
//
//   minimise   1/2 (x - t)^T W (x - t)          W = diag(weight) > 0, x in R^n, n = vars
//   subject to a_i . x >= b_i                   i < rows   (linearized non-penetration, eq. 6-8)
//              lower <= x <= upper                          (the local-solution box, eq. 5)
//
// The first kPoseVars variables are the tool's pose step; a step with compliant contacts appends
// slack variables s_k (weight w_k > 0, target 0, box [0, cap_k], cap_k possibly +infinity), so a
// row reads a_pose . x + sum_k s_k >= b and s_k is how far the contact sinks into soft tissue.
//
// Solved by a dual active-set method (Goldfarb-Idnani) for up to kMaxVars variables: fixed-size
// storage, no heap allocation, a hard iteration cap, deterministic tie-breaking and a named
// status for every way it can end. With u = W^(1/2)(x - t) the problem is the projection of the
// origin onto a polytope, which the dual method walks towards from the unconstrained minimum, so
// it needs no feasible starting point. All work runs over the n variables in use only.
#pragma once

#include <cstdint>

namespace sulcus::qp {

inline constexpr int kPoseVars = 6;   // the pose step: translation, rotation vector
inline constexpr int kMaxVars = 16;   // pose plus slack variables
// Capacity of the per-variable arrays and of an active set (kept as the name callers use).
inline constexpr int kVars = kMaxVars;
inline constexpr int kMaxRows = 192;  // general rows; the 2 * vars box rows are extra

// Entries at index vars and beyond (in every per-variable array and in each row of a) are not
// part of the problem: never read, never validated.
struct Problem {
    int vars = kPoseVars;     // variables in use, 1..kMaxVars
    double weight[kMaxVars];  // diagonal of W, each > 0
    double target[kMaxVars];  // t: the unconstrained minimiser (the haptic configuration)
    double lower[kMaxVars];   // box, lower[j] <= upper[j]; use +-infinity for no bound
    double upper[kMaxVars];
    int rows = 0;             // general rows in use, 0..kMaxRows
    double a[kMaxRows][kMaxVars];
    double b[kMaxRows];
};

enum class Status : uint8_t {
    Optimal,         // KKT point found: feasible within tolerance, multipliers >= 0
    Infeasible,      // the constraints admit no point (proved by the dual: an unbounded dual ray)
    IterationLimit,  // max_iterations reached; x is the last iterate and may be infeasible
    InvalidInput,    // NaN/Inf in the data, weight <= 0, lower > upper, rows or vars out of range
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
// box bounds of variable j < vars.
inline constexpr int kBoxLower = 1000;
inline constexpr int kBoxUpper = 2000;

// Entries of x at index vars and beyond, and of active / multipliers at active_count and
// beyond, are zero.
struct Solution {
    double x[kMaxVars] = {};
    Status status = Status::InvalidInput;
    int iterations = 0;               // constraint additions + removals performed
    int active_count = 0;             // constraints active at the solution (<= vars)
    int active[kMaxVars] = {};        // their indices (see kBoxLower/kBoxUpper)
    double multipliers[kMaxVars] = {};  // Lagrange multipliers of the active constraints (>= 0)
    double objective = 0.0;        // 1/2 (x - t)^T W (x - t)
    double max_violation = 0.0;    // largest b_i - a_i.x over all rows and bounds (<= 0 when feasible)
};

// Optional warm start: constraints tried first, in order, when they are violated. Indices that
// name nothing in the problem are passed over.
struct WarmStart {
    int count = 0;  // 0..kMaxVars
    int active[kMaxVars] = {};
};

// Solves the problem. Never allocates, never throws; the result is deterministic. Sizes up to
// the pose and four more variables run a path compiled for their size, the rest one for any size;
// both take the same operations in the same order.
Status solve(const Problem& problem, const Settings& settings, const WarmStart* warm, Solution& out);

// The path for any size, whatever the problem's: `solve`'s answer to the bit (tests compare the
// two; the benchmarks time both).
Status solve_any_size(const Problem& problem, const Settings& settings, const WarmStart* warm, Solution& out);

}  // namespace sulcus::qp
