// Dual active-set (Goldfarb-Idnani) solver for the servo QP with up to kMaxVars variables; see
// qp.h.
//
// Everything happens in the scaled variable u = W^(1/2)(x - t). There the objective is 1/2|u|^2,
// the unconstrained minimum is u = 0, and the Cholesky factor of the Hessian is the identity, so
// the method's J matrix is simply the orthogonal factor Q of the QR factorisation of the active
// normals N = Q R. Each constraint is normalised in the u-metric, so slacks are W-metric
// distances and one tolerance fits all rows (see Settings in qp.h for how it scales).
//
// Storage is fixed-size (plain arrays on the stack, sized for kMaxVars): no heap. Vectors and
// matrices are packed with the problem's own variable count n as their stride, so a 6-variable
// problem touches as much memory as it would in storage made for 6. The solver is a template on
// the variable count: the pose problem (n = kPoseVars, by far the most common) gets loops of
// compile-time length, every other n the same code with n read at run time.
#include "sulcus/engine/qp.h"

#include <cmath>
#include <cstring>
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

constexpr int kMaxConstraints = kMaxRows + 2 * kMaxVars;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kFree = -1;
constexpr int kSkipped = std::numeric_limits<int>::max();
constexpr int kActive = kSkipped - 1;

// The variable count: N when fixed at compile time (N > 0), else the run-time n.
template <int N>
constexpr int dim(int n) {
    if constexpr (N > 0) {
        return N;
    } else {
        return n;
    }
}

// The constraints in u-space: n_k . u >= c_k with |n_k| = 1. Slot k < rows is general row k,
// slot rows + j the lower bound of x_j, slot rows + vars + j its upper bound.
struct Scaled {
    int vars = 0;   // n, also the stride of normal
    double normal[kMaxConstraints * kMaxVars];  // unit normals, slot k at k * vars
    double c[kMaxConstraints];      // right-hand sides
    double scale[kMaxConstraints];  // |W^(-1/2) a|: converts u-multipliers to x-multipliers
    // Which slots the search for a violated constraint passes over, in one word per slot so
    // that the search tests one number: slot k is passed over while mark[k] >= generation.
    // kSkipped: always satisfied (zero row with b <= 0, infinite bound); kActive: in the
    // active set; a generation: found consistent with the active set (see solve_n), passed
    // over until the active set next loses a member, which bumps the generation.
    int mark[kMaxConstraints];
    int generation = 0;  // one per drop, so never near kActive in a run of < 2^31 iterations
    int rows = 0;        // slots from rows on are the box bounds

    bool blocked(int k) const { return mark[k] >= generation; }

    template <int N>
    double* row(int k) { return normal + k * dim<N>(vars); }
    template <int N>
    const double* row(int k) const { return normal + k * dim<N>(vars); }
};

int original_index(int slot, int rows, int n) {
    if (slot < rows) return slot;
    if (slot < rows + n) return kBoxLower + (slot - rows);
    return kBoxUpper + (slot - rows - n);
}

// Slot of an index in qp.h numbering, or -1 when it names nothing in this problem.
int slot_of(int index, int rows, int n) {
    if (index >= 0 && index < rows) return index;
    if (index >= kBoxLower && index < kBoxLower + n) return rows + (index - kBoxLower);
    if (index >= kBoxUpper && index < kBoxUpper + n) return rows + n + (index - kBoxUpper);
    return -1;
}

bool finite(double v) { return std::isfinite(v); }

// The sizes and settings; the data is checked by valid_data once vars is known to be in range.
bool valid_sizes(const Problem& p, const Settings& s, const WarmStart* warm) {
    if (p.vars < 1 || p.vars > kMaxVars) return false;
    if (p.rows < 0 || p.rows > kMaxRows) return false;
    if (!finite(s.feasibility_tol) || s.feasibility_tol < 0) return false;
    if (!finite(s.dependency_tol) || s.dependency_tol < 0) return false;
    // The capacity, not vars: a warm start may name more rows than can be active at once.
    if (warm && (warm->count < 0 || warm->count > kMaxVars)) return false;
    return true;
}

template <int N>
bool valid_data(const Problem& p) {
    const int n = dim<N>(p.vars);
    for (int j = 0; j < n; ++j) {
        if (!finite(p.weight[j]) || !(p.weight[j] > 0)) return false;
        if (!finite(p.target[j])) return false;
        // Infinite bounds are allowed only on the side where they mean "no bound".
        if (std::isnan(p.lower[j]) || std::isnan(p.upper[j])) return false;
        if (p.lower[j] == kInf || p.upper[j] == -kInf) return false;
        if (p.lower[j] > p.upper[j]) return false;
    }
    for (int i = 0; i < p.rows; ++i) {
        if (!finite(p.b[i])) return false;
        for (int j = 0; j < n; ++j)
            if (!finite(p.a[i][j])) return false;
    }
    return true;
}

// Builds the u-space constraints. Returns false when a zero row demands b > 0 (infeasible).
template <int N>
bool scale_constraints(const Problem& p, const double* inv_sqrt_w, const double* sqrt_w,
                       Scaled& sc) {
    const int n = dim<N>(p.vars);
    const int rows = p.rows;
    sc.vars = n;
    sc.rows = rows;
    sc.generation = 0;
    bool feasible = true;
    for (int i = 0; i < rows; ++i) {
        double* nk = sc.row<N>(i);
        double norm2 = 0, at = 0;
        for (int j = 0; j < n; ++j) {
            const double v = p.a[i][j] * inv_sqrt_w[j];
            nk[j] = v;
            norm2 += v * v;
            at += p.a[i][j] * p.target[j];
        }
        const double norm = std::sqrt(norm2);
        if (norm == 0) {
            // 0 >= b: either always true or never.
            sc.mark[i] = kSkipped;
            sc.scale[i] = 0;
            sc.c[i] = 0;
            if (p.b[i] > 0) feasible = false;
            continue;
        }
        const double inv = 1.0 / norm;
        for (int j = 0; j < n; ++j) nk[j] *= inv;
        sc.c[i] = (p.b[i] - at) * inv;
        sc.scale[i] = norm;
        sc.mark[i] = kFree;
    }
    for (int j = 0; j < n; ++j) {
        const int lo = rows + j, hi = rows + n + j;
        double* nlo = sc.row<N>(lo);
        double* nhi = sc.row<N>(hi);
        for (int k = 0; k < n; ++k) nlo[k] = nhi[k] = 0;
        nlo[j] = 1;   //  x_j >= lower_j  <=>   u_j >=  (lower_j - t_j) sqrt(w_j)
        nhi[j] = -1;  // -x_j >= -upper_j <=>  -u_j >= -(upper_j - t_j) sqrt(w_j)
        sc.scale[lo] = sc.scale[hi] = inv_sqrt_w[j];
        const bool has_lo = finite(p.lower[j]), has_hi = finite(p.upper[j]);
        sc.mark[lo] = has_lo ? kFree : kSkipped;
        sc.mark[hi] = has_hi ? kFree : kSkipped;
        sc.c[lo] = has_lo ? (p.lower[j] - p.target[j]) * sqrt_w[j] : 0;
        sc.c[hi] = has_hi ? -(p.upper[j] - p.target[j]) * sqrt_w[j] : 0;
    }
    return feasible;
}

template <int N>
double dot(const double* a, const double* b, int n_rt) {
    const int n = dim<N>(n_rt);
    double s = 0;
    for (int j = 0; j < n; ++j) s += a[j] * b[j];
    return s;
}

// n_k . u - c_k. A box bound's normal is +-e_j, so its slack needs no product (the dense
// product gives the same number: the other terms are zeros).
template <int N>
double slack(const Scaled& sc, int k, const double* u) {
    if (k < sc.rows) return dot<N>(sc.row<N>(k), u, sc.vars) - sc.c[k];
    const int n = dim<N>(sc.vars);
    const int j = k - sc.rows;
    return (j < n ? u[j] : -u[j - n]) - sc.c[k];
}

// A row is violated when its slack is below -tol. The tolerance grows with the row's
// right-hand side so that rounding in n.u - c (of order eps |c|) never reads as a violation.
bool violated(double s, double c, double tol) { return s < -tol * (1.0 + std::fabs(c)); }

// The working set of the dual method: active slots, their multipliers (u-space), the
// orthogonal J (first q columns span the active normals) and the upper-triangular R with
// N = J[:, :q] R. J and R are n x n, column-major with stride n.
struct WorkingSet {
    int vars = 0;
    int q = 0;
    int slot[kMaxVars];
    double lambda[kMaxVars];
    double J[kMaxVars * kMaxVars];
    double R[kMaxVars * kMaxVars];

    template <int N>
    double* Jcol(int j) { return J + j * dim<N>(vars); }
    template <int N>
    double* Rcol(int j) { return R + j * dim<N>(vars); }
    template <int N>
    double& r_at(int i, int j) { return R[j * dim<N>(vars) + i]; }  // R(i, j)
};

template <int N>
void init_working_set(WorkingSet& ws, int n_rt) {
    const int n = dim<N>(n_rt);
    ws.vars = n;
    ws.q = 0;
    for (int k = 0; k < n * n; ++k) ws.J[k] = ws.R[k] = 0;
    for (int k = 0; k < n; ++k) ws.J[k * n + k] = 1;
}

// Plane rotation of columns a, b of J so that (d[a], d[b]) becomes (h, 0) with h >= 0.
template <int N>
void rotate_to_zero(WorkingSet& ws, double* d, int a, int b) {
    const int n = dim<N>(ws.vars);
    const double h = std::hypot(d[a], d[b]);
    if (h == 0) return;
    const double c = d[a] / h, s = d[b] / h;
    double* ja = ws.Jcol<N>(a);
    double* jb = ws.Jcol<N>(b);
    for (int k = 0; k < n; ++k) {
        const double va = ja[k], vb = jb[k];
        ja[k] = c * va + s * vb;
        jb[k] = -s * va + c * vb;
    }
    d[a] = h;
    d[b] = 0;
}

// Appends a constraint whose d = J^T n has a non-negligible tail d[q..]: rotate the tail into
// d[q] and store d[0..q] as the new column of R.
template <int N>
void add_constraint(WorkingSet& ws, double* d, int slot, double lambda) {
    const int n = dim<N>(ws.vars);
    const int q = ws.q;
    for (int j = n - 1; j > q; --j) rotate_to_zero<N>(ws, d, j - 1, j);
    if (d[q] < 0) {  // only when q = n - 1 (no rotation): keep R's diagonal positive
        d[q] = -d[q];
        double* jq = ws.Jcol<N>(q);
        for (int k = 0; k < n; ++k) jq[k] = -jq[k];
    }
    // One loop of length n, not a copy and a fill of length q: the compiler turns those into
    // library calls, which cost more than the loop at these sizes.
    double* rq = ws.Rcol<N>(q);
    for (int i = 0; i < n; ++i) rq[i] = i <= q ? d[i] : 0.0;
    ws.slot[q] = slot;
    ws.lambda[q] = lambda;
    ws.q = q + 1;
}

// Removes active entry l: drop column l of R, then restore the triangle with rotations of
// rows (j, j+1), applied to the columns of J as well so that N = J R still holds.
template <int N>
void drop_constraint(WorkingSet& ws, int l) {
    const int n = dim<N>(ws.vars);
    const int q = ws.q;
    for (int j = l; j < q - 1; ++j) {
        // Columns do not overlap; memcpy of a compile-time size is expanded in place.
        std::memcpy(ws.Rcol<N>(j), ws.Rcol<N>(j + 1), sizeof(double) * n);
        ws.slot[j] = ws.slot[j + 1];
        ws.lambda[j] = ws.lambda[j + 1];
    }
    double* last = ws.Rcol<N>(q - 1);
    for (int i = 0; i < n; ++i) last[i] = 0;
    for (int j = l; j < q - 1; ++j) {
        const double a = ws.r_at<N>(j, j), b = ws.r_at<N>(j + 1, j);
        const double h = std::hypot(a, b);
        if (h == 0) continue;
        const double c = a / h, s = b / h;
        for (int k = j; k < q - 1; ++k) {
            const double ra = ws.r_at<N>(j, k), rb = ws.r_at<N>(j + 1, k);
            ws.r_at<N>(j, k) = c * ra + s * rb;
            ws.r_at<N>(j + 1, k) = -s * ra + c * rb;
        }
        ws.r_at<N>(j + 1, j) = 0;
        double* ja = ws.Jcol<N>(j);
        double* jb = ws.Jcol<N>(j + 1);
        for (int k = 0; k < n; ++k) {
            const double va = ja[k], vb = jb[k];
            ja[k] = c * va + s * vb;
            jb[k] = -s * va + c * vb;
        }
    }
    ws.q = q - 1;
}

// Picks the next constraint to add: the first violated warm-start entry still pending, else
// the most violated constraint (ties to the lowest slot). Returns -1 when none is violated.
template <int N>
int pick_violated(const Scaled& sc, const double* u, double tol, const WarmStart* warm,
                  int& warm_next) {
    const int n = dim<N>(sc.vars);
    const int rows = sc.rows;
    if (warm) {
        while (warm_next < warm->count) {
            const int k = slot_of(warm->active[warm_next++], rows, n);
            if (k < 0 || sc.blocked(k)) continue;
            if (violated(slack<N>(sc, k, u), sc.c[k], tol)) return k;
        }
    }
    int best = -1;
    double worst = 0;
    auto consider = [&](int k, double s) {
        if (violated(s, sc.c[k], tol) && (best < 0 || s < worst)) {
            best = k;
            worst = s;
        }
    };
    // In slot order (ties go to the lowest slot): rows, lower bounds, upper bounds.
    for (int k = 0; k < rows; ++k)
        if (!sc.blocked(k)) consider(k, dot<N>(sc.row<N>(k), u, n) - sc.c[k]);
    for (int j = 0; j < n; ++j)
        if (!sc.blocked(rows + j)) consider(rows + j, u[j] - sc.c[rows + j]);
    for (int j = 0; j < n; ++j)
        if (!sc.blocked(rows + n + j)) consider(rows + n + j, -u[j] - sc.c[rows + n + j]);
    return best;
}

template <int N>
void fill_solution(const Problem& p, const Scaled& sc, const WorkingSet& ws, const double* u,
                   const double* inv_sqrt_w, Status status, int iterations, Solution& out) {
    const int n = dim<N>(p.vars);
    for (int j = 0; j < n; ++j) out.x[j] = p.target[j] + u[j] * inv_sqrt_w[j];
    for (int j = n; j < kMaxVars; ++j) out.x[j] = 0;
    out.active_count = ws.q;
    for (int i = 0; i < kMaxVars; ++i) {
        out.active[i] = 0;
        out.multipliers[i] = 0;
    }
    for (int i = 0; i < ws.q; ++i) {
        const int k = ws.slot[i];
        out.active[i] = original_index(k, p.rows, n);
        // u-space multiplier mu on a unit normal n = W^(-1/2) a / |W^(-1/2) a| is
        // mu / |W^(-1/2) a| on a in x-space: W (x - t) = sum lambda_i a_i.
        out.multipliers[i] = ws.lambda[i] / sc.scale[k];
        // An active bound holds exactly; this removes the rounding of t + u / sqrt(w).
        if (k >= p.rows) {
            const int j = (k - p.rows) % n;
            out.x[j] = (k < p.rows + n) ? p.lower[j] : p.upper[j];
        }
    }
    double obj = 0;
    for (int j = 0; j < n; ++j) {
        const double e = out.x[j] - p.target[j];
        obj += p.weight[j] * e * e;
    }
    out.objective = 0.5 * obj;
    double viol = -kInf;
    bool any = false;
    for (int i = 0; i < p.rows; ++i) {
        double ax = 0;
        for (int j = 0; j < n; ++j) ax += p.a[i][j] * out.x[j];
        const double v = p.b[i] - ax;
        if (!any || v > viol) viol = v;
        any = true;
    }
    for (int j = 0; j < n; ++j) {
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

// The solver proper; N > 0 fixes the variable count at compile time.
template <int N>
Status solve_n(const Problem& problem, const Settings& settings, const WarmStart* warm,
               Solution& out) {
    if (!valid_data<N>(problem)) {
        out = Solution{};
        out.status = Status::InvalidInput;
        return out.status;
    }
    const int n = dim<N>(problem.vars);
    double sqrt_w[kMaxVars], inv_sqrt_w[kMaxVars];
    for (int j = 0; j < n; ++j) {
        sqrt_w[j] = std::sqrt(problem.weight[j]);
        inv_sqrt_w[j] = 1.0 / sqrt_w[j];
    }
    Scaled sc;
    WorkingSet ws;
    init_working_set<N>(ws, n);
    double u[kMaxVars];
    for (int j = 0; j < n; ++j) u[j] = 0;
    const bool zero_rows_ok = scale_constraints<N>(problem, inv_sqrt_w, sqrt_w, sc);
    if (!zero_rows_ok) {
        fill_solution<N>(problem, sc, ws, u, inv_sqrt_w, Status::Infeasible, 0, out);
        return out.status;
    }

    const double tol = settings.feasibility_tol;
    const double dep_tol = settings.dependency_tol;
    int iterations = 0;
    int warm_next = 0;
    Status status = Status::Optimal;

    for (;;) {
        // Step 1: choose a violated constraint p; none left means u is optimal.
        const int p = pick_violated<N>(sc, u, tol, warm, warm_next);
        if (p < 0) break;
        if (iterations >= settings.max_iterations) {
            status = Status::IterationLimit;
            break;
        }
        const double* np = sc.row<N>(p);
        double lambda_p = 0;  // the multiplier p accumulates before it joins the active set
        double s_p = slack<N>(sc, p, u);

        // Step 2: move along the primal direction z and the dual direction (-r, 1) until p is
        // satisfied (full step) or an active multiplier reaches zero (partial step, drop it).
        bool added = false;
        bool first = true;
        while (!added) {
            const int q = ws.q;
            double d[kMaxVars];  // J^T n_p
            for (int i = 0; i < n; ++i) d[i] = dot<N>(ws.Jcol<N>(i), np, n);
            // Primal direction z = J2 d2 (the part of n_p orthogonal to the active normals).
            double tail2 = 0;
            for (int j = q; j < n; ++j) tail2 += d[j] * d[j];
            const double tail = std::sqrt(tail2);
            const bool dependent = tail <= dep_tol;
            if (dependent && first) {
                // n_p lies in the span of the active normals, whose slacks are zero, so s_p is
                // fixed by them. When it is short of zero only by what the tilt of n_p out of
                // the span (tail) and rounding can account for, p is consistent with the
                // active set: pass it over rather than swap constraints or report infeasible
                // over a rounding-sized gap (e.g. a slab a.x >= b, -a.x >= -b built in floats).
                const double unorm = std::sqrt(dot<N>(u, u, n));
                const double gap = tol * (1.0 + std::fabs(sc.c[p])) +
                                   (tail + dep_tol) * (unorm + std::fabs(sc.c[p]));
                if (s_p >= -gap) {
                    sc.mark[p] = sc.generation;
                    break;
                }
            }
            first = false;
            double z[kMaxVars];
            for (int k = 0; k < n; ++k) z[k] = 0;
            if (!dependent)
                for (int j = q; j < n; ++j) {
                    const double* jj = ws.Jcol<N>(j);
                    for (int k = 0; k < n; ++k) z[k] += jj[k] * d[j];
                }
            // r = R^-1 d1, the change of the active multipliers per unit of lambda_p.
            double r[kMaxVars];
            for (int i = q - 1; i >= 0; --i) {
                double v = d[i];
                for (int k = i + 1; k < q; ++k) v -= ws.r_at<N>(i, k) * r[k];
                r[i] = v / ws.r_at<N>(i, i);
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
                const double zn = dot<N>(z, np, n);
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
            if (t2 != kInf)
                for (int k = 0; k < n; ++k) u[k] += t * z[k];
            ++iterations;
            if (t2 <= t1) {
                sc.mark[p] = kActive;
                add_constraint<N>(ws, d, p, lambda_p);
                added = true;
            } else {
                sc.mark[ws.slot[drop]] = kFree;
                drop_constraint<N>(ws, drop);
                ++sc.generation;
                // p keeps its partial multiplier, so it must still join the active set.
                s_p = slack<N>(sc, p, u);
            }
        }
        if (status != Status::Optimal) break;
    }
    fill_solution<N>(problem, sc, ws, u, inv_sqrt_w, status, iterations, out);
    return status;
}

// The answer to a problem of invalid sizes.
Status refuse(Solution& out) {
    out = Solution{};
    out.status = Status::InvalidInput;
    return out.status;
}

}  // namespace

Status solve(const Problem& problem, const Settings& settings, const WarmStart* warm,
             Solution& out) {
    if (!valid_sizes(problem, settings, warm)) return refuse(out);
    // A path compiled for each size up to the pose and four springs (the tissue's zones: the
    // bench's two-region session solves 8 and 9 variables); the same operations in the same order
    // at every size, so the same answer to the bit.
    switch (problem.vars) {
        case kPoseVars: return solve_n<kPoseVars>(problem, settings, warm, out);
        case kPoseVars + 1: return solve_n<kPoseVars + 1>(problem, settings, warm, out);
        case kPoseVars + 2: return solve_n<kPoseVars + 2>(problem, settings, warm, out);
        case kPoseVars + 3: return solve_n<kPoseVars + 3>(problem, settings, warm, out);
        case kPoseVars + 4: return solve_n<kPoseVars + 4>(problem, settings, warm, out);
        default: return solve_n<0>(problem, settings, warm, out);
    }
}

Status solve_any_size(const Problem& problem, const Settings& settings, const WarmStart* warm, Solution& out) {
    if (!valid_sizes(problem, settings, warm)) return refuse(out);
    return solve_n<0>(problem, settings, warm, out);
}

}  // namespace sulcus::qp
