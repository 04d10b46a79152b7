// Dual active-set (Goldfarb-Idnani) solver for the 6-variable servo QP; see qp.h.
//
// Everything happens in the scaled variable u = W^(1/2)(x - t). There the objective is 1/2|u|^2,
// the unconstrained minimum is u = 0, and the Cholesky factor of the Hessian is the identity, so
// the method's J matrix is simply the orthogonal factor Q of the QR factorisation of the active
// normals N = Q R. Each constraint is normalised in the u-metric, so slacks are W-metric
// distances and one tolerance fits all rows (see Settings in qp.h for how it scales).
//
// Storage is fixed-size (Eigen fixed matrices and plain arrays on the stack): no heap.
#include "sulcus/engine/qp.h"

#include <Eigen/Core>

#include <cmath>
#include <limits>

namespace sulcus::qp {

const char* to_string(Status s) {
    switch (s) {
        case Status::Optimal: return "optimal";
        case Status::Infeasible: return "infeasible";
        case Status::IterationLimit: return "iteration_limit";
        case Status::InvalidInput: return "invalid_input";
    }
    return "unknown";
}

namespace {

using Vec6 = Eigen::Matrix<double, kVars, 1>;
using Mat6 = Eigen::Matrix<double, kVars, kVars>;

constexpr int kMaxConstraints = kMaxRows + 2 * kVars;
constexpr double kInf = std::numeric_limits<double>::infinity();

// The constraints in u-space: n_k . u >= c_k with |n_k| = 1. Slot k < rows is general row k,
// slot rows + j the lower bound of x_j, slot rows + kVars + j its upper bound.
struct Scaled {
    int count = 0;                       // slots in use: rows + 2 * kVars
    double n[kMaxConstraints][kVars];    // unit normals
    double c[kMaxConstraints];           // right-hand sides
    double scale[kMaxConstraints];       // |W^(-1/2) a|: converts u-multipliers to x-multipliers
    bool skip[kMaxConstraints];          // always satisfied (zero row with b <= 0, infinite bound)
    bool active[kMaxConstraints];
    // Rows found consistent with the active set (see solve) are passed over until the active
    // set next loses a member: excluded[k] == generation, bumped on every drop.
    int excluded[kMaxConstraints];
    int generation = 0;
};

int original_index(int slot, int rows) {
    if (slot < rows) return slot;
    if (slot < rows + kVars) return kBoxLower + (slot - rows);
    return kBoxUpper + (slot - rows - kVars);
}

// Slot of an index in qp.h numbering, or -1 when it names nothing in this problem.
int slot_of(int index, int rows) {
    if (index >= 0 && index < rows) return index;
    if (index >= kBoxLower && index < kBoxLower + kVars) return rows + (index - kBoxLower);
    if (index >= kBoxUpper && index < kBoxUpper + kVars) return rows + kVars + (index - kBoxUpper);
    return -1;
}

bool finite(double v) { return std::isfinite(v); }

bool valid(const Problem& p, const Settings& s, const WarmStart* warm) {
    if (p.rows < 0 || p.rows > kMaxRows) return false;
    if (!finite(s.feasibility_tol) || s.feasibility_tol < 0) return false;
    if (!finite(s.dependency_tol) || s.dependency_tol < 0) return false;
    if (warm && (warm->count < 0 || warm->count > kVars)) return false;
    for (int j = 0; j < kVars; ++j) {
        if (!finite(p.weight[j]) || !(p.weight[j] > 0)) return false;
        if (!finite(p.target[j])) return false;
        // Infinite bounds are allowed only on the side where they mean "no bound".
        if (std::isnan(p.lower[j]) || std::isnan(p.upper[j])) return false;
        if (p.lower[j] == kInf || p.upper[j] == -kInf) return false;
        if (p.lower[j] > p.upper[j]) return false;
    }
    for (int i = 0; i < p.rows; ++i) {
        if (!finite(p.b[i])) return false;
        for (int j = 0; j < kVars; ++j)
            if (!finite(p.a[i][j])) return false;
    }
    return true;
}

// Builds the u-space constraints. Returns false when a zero row demands b > 0 (infeasible).
bool scale_constraints(const Problem& p, const double (&inv_sqrt_w)[kVars],
                       const double (&sqrt_w)[kVars], Scaled& sc) {
    const int rows = p.rows;
    sc.count = rows + 2 * kVars;
    bool feasible = true;
    for (int i = 0; i < rows; ++i) {
        double norm2 = 0, at = 0;
        for (int j = 0; j < kVars; ++j) {
            const double v = p.a[i][j] * inv_sqrt_w[j];
            sc.n[i][j] = v;
            norm2 += v * v;
            at += p.a[i][j] * p.target[j];
        }
        sc.active[i] = false;
        sc.excluded[i] = -1;
        const double norm = std::sqrt(norm2);
        if (norm == 0) {
            // 0 >= b: either always true or never.
            sc.skip[i] = true;
            sc.scale[i] = 0;
            sc.c[i] = 0;
            if (p.b[i] > 0) feasible = false;
            continue;
        }
        const double inv = 1.0 / norm;
        for (int j = 0; j < kVars; ++j) sc.n[i][j] *= inv;
        sc.c[i] = (p.b[i] - at) * inv;
        sc.scale[i] = norm;
        sc.skip[i] = false;
    }
    for (int j = 0; j < kVars; ++j) {
        const int lo = rows + j, hi = rows + kVars + j;
        for (int k = 0; k < kVars; ++k) sc.n[lo][k] = sc.n[hi][k] = 0;
        sc.n[lo][j] = 1;   //  x_j >= lower_j  <=>   u_j >=  (lower_j - t_j) sqrt(w_j)
        sc.n[hi][j] = -1;  // -x_j >= -upper_j <=>  -u_j >= -(upper_j - t_j) sqrt(w_j)
        sc.scale[lo] = sc.scale[hi] = inv_sqrt_w[j];
        sc.active[lo] = sc.active[hi] = false;
        sc.excluded[lo] = sc.excluded[hi] = -1;
        sc.skip[lo] = !finite(p.lower[j]);
        sc.skip[hi] = !finite(p.upper[j]);
        sc.c[lo] = sc.skip[lo] ? 0 : (p.lower[j] - p.target[j]) * sqrt_w[j];
        sc.c[hi] = sc.skip[hi] ? 0 : -(p.upper[j] - p.target[j]) * sqrt_w[j];
    }
    return feasible;
}

double slack(const Scaled& sc, int k, const Vec6& u) {
    double s = 0;
    for (int j = 0; j < kVars; ++j) s += sc.n[k][j] * u[j];
    return s - sc.c[k];
}

// A row is violated when its slack is below -tol. The tolerance grows with the row's
// right-hand side so that rounding in n.u - c (of order eps |c|) never reads as a violation.
bool violated(double s, double c, double tol) { return s < -tol * (1.0 + std::fabs(c)); }

// The working set of the dual method: active slots, their multipliers (u-space), the
// orthogonal J (first q columns span the active normals) and the upper-triangular R with
// N = J[:, :q] R.
struct WorkingSet {
    int q = 0;
    int slot[kVars];
    double lambda[kVars];
    Mat6 J = Mat6::Identity();
    Mat6 R = Mat6::Zero();
};

// Plane rotation of columns a, b of J so that (d[a], d[b]) becomes (h, 0) with h >= 0.
void rotate_to_zero(Mat6& J, Vec6& d, int a, int b) {
    const double h = std::hypot(d[a], d[b]);
    if (h == 0) return;
    const double c = d[a] / h, s = d[b] / h;
    for (int k = 0; k < kVars; ++k) {
        const double ja = J(k, a), jb = J(k, b);
        J(k, a) = c * ja + s * jb;
        J(k, b) = -s * ja + c * jb;
    }
    d[a] = h;
    d[b] = 0;
}

// Appends a constraint whose d = J^T n has a non-negligible tail d[q..]: rotate the tail into
// d[q] and store d[0..q] as the new column of R.
void add_constraint(WorkingSet& ws, Vec6& d, int slot, double lambda) {
    const int q = ws.q;
    for (int j = kVars - 1; j > q; --j) rotate_to_zero(ws.J, d, j - 1, j);
    if (d[q] < 0) {  // only when q = kVars - 1 (no rotation): keep R's diagonal positive
        d[q] = -d[q];
        ws.J.col(q) = -ws.J.col(q);
    }
    for (int i = 0; i <= q; ++i) ws.R(i, q) = d[i];
    for (int i = q + 1; i < kVars; ++i) ws.R(i, q) = 0;
    ws.slot[q] = slot;
    ws.lambda[q] = lambda;
    ws.q = q + 1;
}

// Removes active entry l: drop column l of R, then restore the triangle with rotations of
// rows (j, j+1), applied to the columns of J as well so that N = J R still holds.
void drop_constraint(WorkingSet& ws, int l) {
    const int q = ws.q;
    for (int j = l; j < q - 1; ++j) {
        ws.R.col(j) = ws.R.col(j + 1);
        ws.slot[j] = ws.slot[j + 1];
        ws.lambda[j] = ws.lambda[j + 1];
    }
    ws.R.col(q - 1).setZero();
    for (int j = l; j < q - 1; ++j) {
        const double a = ws.R(j, j), b = ws.R(j + 1, j);
        const double h = std::hypot(a, b);
        if (h == 0) continue;
        const double c = a / h, s = b / h;
        for (int k = j; k < q - 1; ++k) {
            const double ra = ws.R(j, k), rb = ws.R(j + 1, k);
            ws.R(j, k) = c * ra + s * rb;
            ws.R(j + 1, k) = -s * ra + c * rb;
        }
        ws.R(j + 1, j) = 0;
        for (int k = 0; k < kVars; ++k) {
            const double ja = ws.J(k, j), jb = ws.J(k, j + 1);
            ws.J(k, j) = c * ja + s * jb;
            ws.J(k, j + 1) = -s * ja + c * jb;
        }
    }
    ws.q = q - 1;
}

// Picks the next constraint to add: the first violated warm-start entry still pending, else
// the most violated constraint (ties to the lowest slot). Returns -1 when none is violated.
int pick_violated(const Scaled& sc, const Vec6& u, double tol, const WarmStart* warm,
                  int rows, int& warm_next) {
    if (warm) {
        while (warm_next < warm->count) {
            const int k = slot_of(warm->active[warm_next++], rows);
            if (k < 0 || sc.skip[k] || sc.active[k] || sc.excluded[k] == sc.generation) continue;
            if (violated(slack(sc, k, u), sc.c[k], tol)) return k;
        }
    }
    int best = -1;
    double worst = 0;
    for (int k = 0; k < sc.count; ++k) {
        if (sc.skip[k] || sc.active[k] || sc.excluded[k] == sc.generation) continue;
        const double s = slack(sc, k, u);
        if (violated(s, sc.c[k], tol) && (best < 0 || s < worst)) {
            best = k;
            worst = s;
        }
    }
    return best;
}

void fill_solution(const Problem& p, const Scaled& sc, const WorkingSet& ws, const Vec6& u,
                   const double (&inv_sqrt_w)[kVars], Status status, int iterations,
                   Solution& out) {
    for (int j = 0; j < kVars; ++j) out.x[j] = p.target[j] + u[j] * inv_sqrt_w[j];
    out.active_count = ws.q;
    for (int i = 0; i < kVars; ++i) {
        out.active[i] = 0;
        out.multipliers[i] = 0;
    }
    for (int i = 0; i < ws.q; ++i) {
        const int k = ws.slot[i];
        out.active[i] = original_index(k, p.rows);
        // u-space multiplier mu on a unit normal n = W^(-1/2) a / |W^(-1/2) a| is
        // mu / |W^(-1/2) a| on a in x-space: W (x - t) = sum lambda_i a_i.
        out.multipliers[i] = ws.lambda[i] / sc.scale[k];
        // An active bound holds exactly; this removes the rounding of t + u / sqrt(w).
        if (k >= p.rows) {
            const int j = (k - p.rows) % kVars;
            out.x[j] = (k < p.rows + kVars) ? p.lower[j] : p.upper[j];
        }
    }
    double obj = 0;
    for (int j = 0; j < kVars; ++j) {
        const double e = out.x[j] - p.target[j];
        obj += p.weight[j] * e * e;
    }
    out.objective = 0.5 * obj;
    double viol = -kInf;
    bool any = false;
    for (int i = 0; i < p.rows; ++i) {
        double ax = 0;
        for (int j = 0; j < kVars; ++j) ax += p.a[i][j] * out.x[j];
        const double v = p.b[i] - ax;
        if (!any || v > viol) viol = v;
        any = true;
    }
    for (int j = 0; j < kVars; ++j) {
        if (finite(p.lower[j])) {
            const double v = p.lower[j] - out.x[j];
            if (!any || v > viol) viol = v;
            any = true;
        }
        if (finite(p.upper[j])) {
            const double v = out.x[j] - p.upper[j];
            if (!any || v > viol) viol = v;
            any = true;
        }
    }
    out.max_violation = any ? viol : 0.0;
    out.iterations = iterations;
    out.status = status;
}

}  // namespace

Status solve(const Problem& problem, const Settings& settings, const WarmStart* warm,
             Solution& out) {
    if (!valid(problem, settings, warm)) {
        out = Solution{};
        out.status = Status::InvalidInput;
        return out.status;
    }
    double sqrt_w[kVars], inv_sqrt_w[kVars];
    for (int j = 0; j < kVars; ++j) {
        sqrt_w[j] = std::sqrt(problem.weight[j]);
        inv_sqrt_w[j] = 1.0 / sqrt_w[j];
    }
    Scaled sc;
    WorkingSet ws;
    Vec6 u = Vec6::Zero();
    const bool zero_rows_ok = scale_constraints(problem, inv_sqrt_w, sqrt_w, sc);
    if (!zero_rows_ok) {
        fill_solution(problem, sc, ws, u, inv_sqrt_w, Status::Infeasible, 0, out);
        return out.status;
    }

    const double tol = settings.feasibility_tol;
    const double dep_tol = settings.dependency_tol;
    int iterations = 0;
    int warm_next = 0;
    Status status = Status::Optimal;

    for (;;) {
        // Step 1: choose a violated constraint p; none left means u is optimal.
        const int p = pick_violated(sc, u, tol, warm, problem.rows, warm_next);
        if (p < 0) break;
        if (iterations >= settings.max_iterations) {
            status = Status::IterationLimit;
            break;
        }
        Vec6 np;
        for (int j = 0; j < kVars; ++j) np[j] = sc.n[p][j];
        double lambda_p = 0;  // the multiplier p accumulates before it joins the active set
        double s_p = slack(sc, p, u);

        // Step 2: move along the primal direction z and the dual direction (-r, 1) until p is
        // satisfied (full step) or an active multiplier reaches zero (partial step, drop it).
        bool added = false;
        bool first = true;
        while (!added) {
            const int q = ws.q;
            Vec6 d = ws.J.transpose() * np;
            // Primal direction z = J2 d2 (the part of n_p orthogonal to the active normals).
            double tail2 = 0;
            for (int j = q; j < kVars; ++j) tail2 += d[j] * d[j];
            const double tail = std::sqrt(tail2);
            const bool dependent = tail <= dep_tol;
            if (dependent && first) {
                // n_p lies in the span of the active normals, whose slacks are zero, so s_p is
                // fixed by them. When it is short of zero only by what the tilt of n_p out of
                // the span (tail) and rounding can account for, p is consistent with the
                // active set: pass it over rather than swap constraints or report infeasible
                // over a rounding-sized gap (e.g. a slab a.x >= b, -a.x >= -b built in floats).
                const double gap = tol * (1.0 + std::fabs(sc.c[p])) +
                                   (tail + dep_tol) * (u.norm() + std::fabs(sc.c[p]));
                if (s_p >= -gap) {
                    sc.excluded[p] = sc.generation;
                    break;
                }
            }
            first = false;
            Vec6 z = Vec6::Zero();
            if (!dependent)
                for (int j = q; j < kVars; ++j) z += ws.J.col(j) * d[j];
            // r = R^-1 d1, the change of the active multipliers per unit of lambda_p.
            double r[kVars];
            for (int i = q - 1; i >= 0; --i) {
                double v = d[i];
                for (int k = i + 1; k < q; ++k) v -= ws.R(i, k) * r[k];
                r[i] = v / ws.R(i, i);
            }
            // Partial step: the first multiplier to reach zero (ties to the earliest entry).
            double t1 = kInf;
            int drop = -1;
            for (int i = 0; i < q; ++i) {
                if (r[i] > 0) {
                    const double ti = ws.lambda[i] / r[i];
                    if (ti < t1) {
                        t1 = ti;
                        drop = i;
                    }
                }
            }
            // Full step: the length that makes p's slack zero.
            double t2 = kInf;
            if (!dependent) {
                const double zn = z.dot(np);
                // Rounding can leave s_p a hair positive after a partial step: never step back.
                if (zn > 0) t2 = s_p < 0 ? -s_p / zn : 0.0;
            }
            if (t1 == kInf && t2 == kInf) {
                // n_p lies in the cone of the active normals' negatives: the dual is unbounded.
                status = Status::Infeasible;
                break;
            }
            if (iterations >= settings.max_iterations) {
                status = Status::IterationLimit;
                break;
            }
            const double t = t1 < t2 ? t1 : t2;
            // The min-ratio rule keeps every multiplier >= 0; clamp the rounding below zero.
            for (int i = 0; i < q; ++i) {
                const double li = ws.lambda[i] - t * r[i];
                ws.lambda[i] = li > 0 ? li : 0.0;
            }
            lambda_p += t;
            if (t2 != kInf) u += t * z;
            ++iterations;
            if (t2 <= t1) {
                sc.active[p] = true;
                add_constraint(ws, d, p, lambda_p);
                added = true;
            } else {
                sc.active[ws.slot[drop]] = false;
                drop_constraint(ws, drop);
                ++sc.generation;
                // p keeps its partial multiplier, so it must still join the active set.
                s_p = slack(sc, p, u);
            }
        }
        if (status != Status::Optimal) break;
    }
    fill_solution(problem, sc, ws, u, inv_sqrt_w, status, iterations, out);
    return status;
}

}  // namespace sulcus::qp
