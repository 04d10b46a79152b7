// Tests of the servo QP solver (qp.h) against a brute-force KKT enumeration (qp_reference.h),
// on thousands of random problems with a fixed seed, including the degenerate and infeasible
// shapes that contact geometry produces.
#include "sulcus/engine/qp.h"

#include "qp_reference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <vector>

#include "allocation_counter.h"

namespace sulcus::qp {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Hand-written distributions on mt19937_64 bits, so the problems are the same everywhere.
class Rng {
public:
    explicit Rng(uint64_t seed) : gen_(seed) {}
    double uniform() { return static_cast<double>(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    int integer(int lo, int hi) {  // [lo, hi]
        return lo + static_cast<int>(gen_() % static_cast<uint64_t>(hi - lo + 1));
    }
    bool chance(double p) { return uniform() < p; }
    double normal() {  // Box-Muller
        const double u1 = 1.0 - uniform(), u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
    }

private:
    std::mt19937_64 gen_;
};

// Every variable free, weight 1, target 0; n variables (the pose problem by default).
std::unique_ptr<Problem> empty_problem(int n = kPoseVars) {
    auto p = std::make_unique<Problem>();
    p->vars = n;
    for (int j = 0; j < n; ++j) {
        p->weight[j] = 1;
        p->target[j] = 0;
        p->lower[j] = -kInf;
        p->upper[j] = kInf;
    }
    p->rows = 0;
    return p;
}

int finite_bounds(const Problem& p) {
    int n = 0;
    for (int j = 0; j < p.vars; ++j) n += std::isfinite(p.lower[j]) + std::isfinite(p.upper[j]);
    return n;
}

// Weights: log-uniform over six decades, or the haptic pattern (translational ~1, rotational
// ~1e-4), or near-uniform.
void random_weights(Rng& rng, Problem& p) {
    const int mode = rng.integer(0, 2);
    for (int j = 0; j < p.vars; ++j) {
        if (mode == 0) p.weight[j] = std::pow(10.0, rng.uniform(-6, 0));
        if (mode == 1) p.weight[j] = (j < 3 ? 1.0 : 1e-4) * rng.uniform(0.5, 2.0);
        if (mode == 2) p.weight[j] = rng.uniform(0.5, 2.0);
    }
}

void random_target(Rng& rng, Problem& p) {
    for (int j = 0; j < p.vars; ++j) p.target[j] = rng.uniform(-1, 1);
}

void random_normal(Rng& rng, double* a, int n = kPoseVars) {
    const double mag = std::pow(10.0, rng.uniform(-1, 1));  // rows need not be unit
    for (int j = 0; j < n; ++j) a[j] = mag * rng.normal();
    if (rng.chance(0.2)) a[rng.integer(0, n - 1)] = 0;  // sparse rows occur too
}

double dot(const double* a, const double* x, int n = kPoseVars) {
    double s = 0;
    for (int j = 0; j < n; ++j) s += a[j] * x[j];
    return s;
}

// A row through the neighbourhood of the target: mostly violated there, sometimes not.
void add_random_row(Rng& rng, Problem& p) {
    const int i = p.rows++;
    random_normal(rng, p.a[i], p.vars);
    double n = 0;
    for (int j = 0; j < p.vars; ++j) n += p.a[i][j] * p.a[i][j] / p.weight[j];
    p.b[i] = dot(p.a[i], p.target, p.vars) + std::sqrt(n) * rng.uniform(-0.3, 1.0);
}

// Box sides, each finite at random, around a point near the target; at most max_sides new
// ones. Sides already finite are kept, and a new side never crosses the opposite one.
void random_box(Rng& rng, Problem& p, int max_sides) {
    for (int j = 0; j < p.vars; ++j) {
        const double c = p.target[j] + rng.uniform(-1, 1) / std::sqrt(p.weight[j]);
        const double h = rng.uniform(0, 1) / std::sqrt(p.weight[j]);
        if (max_sides > 0 && rng.chance(0.3) && !std::isfinite(p.lower[j]) && c - h <= p.upper[j]) {
            p.lower[j] = c - h;
            --max_sides;
        }
        if (max_sides > 0 && rng.chance(0.3) && !std::isfinite(p.upper[j]) && c + h >= p.lower[j]) {
            p.upper[j] = c + h;
            --max_sides;
        }
    }
}

struct Checked {
    Status status;
    int iterations;
    int active_count;
};

// The KKT conditions of an optimal answer, checked on their own: primal feasibility, dual
// feasibility (multipliers >= 0), complementarity (active constraints hold with equality) and
// stationarity W(x - t) = sum lambda_i a_i, all over the problem's n = vars variables.
void expect_kkt(const Problem& p, const Solution& s) {
    const int n = p.vars;
    // Primal feasibility, in the original units, recomputed here: relative to the size of the
    // terms of a.x - b (their rounding scale), and in absolute terms against max_violation.
    for (const reference::Constraint& c : reference::constraints_of(p))
        EXPECT_LE(reference::violation(c, s.x), 1e-9);
    double worst = -kInf;
    for (int i = 0; i < p.rows; ++i) worst = std::max(worst, p.b[i] - dot(p.a[i], s.x, n));
    for (int j = 0; j < n; ++j) {
        if (std::isfinite(p.lower[j])) worst = std::max(worst, p.lower[j] - s.x[j]);
        if (std::isfinite(p.upper[j])) worst = std::max(worst, s.x[j] - p.upper[j]);
    }
    if (worst > -kInf) {
        EXPECT_NEAR(s.max_violation, worst, 1e-15 * (1 + std::fabs(worst)));
    }

    // Dual feasibility, complementarity and stationarity W(x - t) = sum lambda_i a_i.
    EXPECT_GE(s.active_count, 0);
    EXPECT_LE(s.active_count, n);
    double grad[kMaxVars];
    for (int j = 0; j < n; ++j) grad[j] = p.weight[j] * (s.x[j] - p.target[j]);
    double gnorm = 0;
    for (int j = 0; j < n; ++j) gnorm = std::max(gnorm, std::fabs(grad[j]));
    for (int k = 0; k < s.active_count; ++k) {
        EXPECT_GE(s.multipliers[k], 0.0);
        const int idx = s.active[k];
        reference::Constraint c{};
        c.vars = n;
        if (idx >= 0 && idx < p.rows) {
            for (int j = 0; j < n; ++j) c.a[j] = p.a[idx][j];
            c.b = p.b[idx];
        } else if (idx >= kBoxLower && idx < kBoxLower + n) {
            c.a[idx - kBoxLower] = 1;
            c.b = p.lower[idx - kBoxLower];
        } else if (idx >= kBoxUpper && idx < kBoxUpper + n) {
            c.a[idx - kBoxUpper] = -1;
            c.b = -p.upper[idx - kBoxUpper];
        } else {
            ADD_FAILURE() << "bad active index " << idx;
            continue;
        }
        EXPECT_NEAR(reference::violation(c, s.x), 0.0, 1e-9) << "active " << idx;
        for (int j = 0; j < n; ++j) grad[j] -= s.multipliers[k] * c.a[j];
    }
    for (int j = 0; j < n; ++j) EXPECT_NEAR(grad[j], 0.0, 1e-8 * (1 + gnorm)) << "j=" << j;
    for (int k = 0; k < s.active_count; ++k)
        for (int l = k + 1; l < s.active_count; ++l) EXPECT_NE(s.active[k], s.active[l]);
    // Beyond the problem's variables and active set the answer is zero.
    for (int j = n; j < kMaxVars; ++j) EXPECT_EQ(s.x[j], 0.0) << "j=" << j;
    for (int k = s.active_count; k < kMaxVars; ++k) {
        EXPECT_EQ(s.active[k], 0);
        EXPECT_EQ(s.multipliers[k], 0.0);
    }
}

// Solves, checks the KKT conditions of the answer on their own, and compares with the reference.
Checked check_problem(const Problem& p, const char* what, int id) {
    SCOPED_TRACE(testing::Message() << what << " #" << id << " (n = " << p.vars << ")");
    const int n = p.vars;
    const Settings settings;
    Solution s;
    solve(p, settings, nullptr, s);
    const reference::Result ref = reference::solve(p);

    EXPECT_NE(s.status, Status::IterationLimit);
    EXPECT_NE(s.status, Status::InvalidInput);
    EXPECT_EQ(s.status == Status::Optimal, ref.feasible) << "solver: " << to_string(s.status);
    if (s.status != Status::Optimal) return {s.status, s.iterations, s.active_count};

    double obj = 0;
    for (int j = 0; j < n; ++j)
        obj += 0.5 * p.weight[j] * (s.x[j] - p.target[j]) * (s.x[j] - p.target[j]);
    EXPECT_NEAR(s.objective, obj, 1e-12 * (1 + obj));
    if (ref.feasible) {
        // Objective agrees with the reference.
        EXPECT_NEAR(s.objective, ref.objective, 1e-9 * std::fabs(ref.objective) + 1e-13);
        // The minimiser of a strictly convex QP is unique: x agrees, measured in the W-metric.
        double dx2 = 0;
        for (int j = 0; j < n; ++j)
            dx2 += p.weight[j] * (s.x[j] - ref.x[j]) * (s.x[j] - ref.x[j]);
        EXPECT_LE(std::sqrt(dx2), 1e-7 * (1 + std::sqrt(2 * ref.objective)));
    }
    expect_kkt(p, s);
    return {s.status, s.iterations, s.active_count};
}

struct Tally {
    int optimal = 0, infeasible = 0, total = 0, most_active = 0;
    void add(Checked c) {
        ++total;
        optimal += c.status == Status::Optimal;
        infeasible += c.status == Status::Infeasible;
        if (c.status == Status::Optimal) most_active = std::max(most_active, c.active_count);
    }
};

constexpr int kPerCategory = 1000;

TEST(Qp, GenericRandomProblemsMatchReference) {
    Rng rng(0x5eed0001);
    Tally tally;
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int rows = rng.integer(0, 8);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 14 - rows);
        tally.add(check_problem(*p, "generic", n));
    }
    EXPECT_EQ(tally.total, kPerCategory);
    EXPECT_GT(tally.optimal, kPerCategory / 2);  // the set is not trivially all-infeasible
}

TEST(Qp, DuplicatedAndDependentRowsMatchReference) {
    Rng rng(0x5eed0002);
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int base = rng.integer(1, 5);
        for (int i = 0; i < base; ++i) add_random_row(rng, *p);
        const int extra = rng.integer(1, 6);
        for (int e = 0; e < extra; ++e) {
            const int i = p->rows++;
            const int r1 = rng.integer(0, base - 1), r2 = rng.integer(0, base - 1);
            const int kind = rng.integer(0, 3);
            if (kind == 0) {  // exact duplicate
                std::memcpy(p->a[i], p->a[r1], sizeof p->a[i]);
                p->b[i] = p->b[r1];
            } else if (kind == 1) {  // positive multiple of the same half-space
                const double f = rng.uniform(0.1, 10);
                for (int j = 0; j < kPoseVars; ++j) p->a[i][j] = f * p->a[r1][j];
                p->b[i] = f * p->b[r1];
            } else {  // combination of two rows: implied (kind 2) or shifted (kind 3)
                const double f = rng.uniform(-1, 1), g = rng.uniform(0, 1);
                for (int j = 0; j < kPoseVars; ++j) p->a[i][j] = f * p->a[r1][j] + g * p->a[r2][j];
                p->b[i] = f * p->b[r1] + g * p->b[r2] + (kind == 3 ? rng.uniform(-0.5, 0.5) : 0.0);
            }
        }
        random_box(rng, *p, 14 - p->rows);
        check_problem(*p, "dependent", n);
    }
}

// More than kPoseVars planes through one point x*, with the target placed so that all of them
// carry a positive multiplier at x*: the optimum is x* and the active set is degenerate.
TEST(Qp, ManyPlanesThroughOnePointMatchReference) {
    Rng rng(0x5eed0003);
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        double xs[kPoseVars];
        for (double& v : xs) v = rng.uniform(-1, 1);
        const int planes = rng.integer(7, 11);
        double push[kPoseVars] = {};  // sum of mu_i n_i in u-space
        for (int i = 0; i < planes; ++i) {
            random_normal(rng, p->a[i]);
            p->b[i] = dot(p->a[i], xs);
            double nn = 0;
            for (int j = 0; j < kPoseVars; ++j) nn += p->a[i][j] * p->a[i][j] / p->weight[j];
            const double mu = rng.chance(0.2) ? 0.0 : rng.uniform(0.1, 1.0);
            for (int j = 0; j < kPoseVars; ++j)
                push[j] += mu * p->a[i][j] / std::sqrt(p->weight[j]) / std::sqrt(nn);
        }
        p->rows = planes;
        for (int j = 0; j < kPoseVars; ++j) p->target[j] = xs[j] - push[j] / std::sqrt(p->weight[j]);
        // A few rows that are slack at x*.
        const int slack_rows = rng.integer(0, 2);
        for (int e = 0; e < slack_rows; ++e) {
            const int i = p->rows++;
            random_normal(rng, p->a[i]);
            p->b[i] = dot(p->a[i], xs) - rng.uniform(0.1, 1.0);
        }
        check_problem(*p, "planes through a point", n);
    }
}

TEST(Qp, ZeroWidthBoxesMatchReference) {
    Rng rng(0x5eed0004);
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int pinned = rng.integer(1, 4);
        for (int k = 0; k < pinned; ++k) {
            const int j = rng.integer(0, kPoseVars - 1);
            p->lower[j] = p->upper[j] = p->target[j] + rng.uniform(-1, 1) / std::sqrt(p->weight[j]);
        }
        const int rows = rng.integer(0, 14 - finite_bounds(*p));
        for (int i = 0; i < rows && i < 6; ++i) add_random_row(rng, *p);
        check_problem(*p, "zero-width box", n);
    }
}

TEST(Qp, ZeroThicknessSlabsMatchReference) {
    Rng rng(0x5eed0005);
    Tally tally;
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int slabs = rng.integer(1, 3);
        for (int k = 0; k < slabs; ++k) {
            add_random_row(rng, *p);
            const int i = p->rows - 1, m = p->rows++;
            for (int j = 0; j < kPoseVars; ++j) p->a[m][j] = -p->a[i][j];
            p->b[m] = -p->b[i];
        }
        const int rows = rng.integer(0, 4);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 14 - p->rows);
        tally.add(check_problem(*p, "slab", n));
    }
    EXPECT_GT(tally.optimal, kPerCategory / 2);
}

// A zero-thickness slab whose second side is built in floating point with cancellation,
// a' = f a + g a with f close to -g: a' is antiparallel to a only up to rounding, and the
// slab is feasible or infeasible only by a rounding-sized gap. The solver must not call
// that infeasible.
TEST(Qp, RoundedSlabIsNotInfeasible) {
    Rng rng(0x5eed000d);
    for (int n = 0; n < 2000; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        add_random_row(rng, *p);
        p->b[0] = dot(p->a[0], p->target) + rng.uniform(0.1, 1);  // violated at the target
        const double g = rng.uniform(0.2, 1), f = -g * (1 - std::pow(10.0, rng.uniform(-6, -3)));
        for (int j = 0; j < kPoseVars; ++j) p->a[1][j] = f * p->a[0][j] + g * p->a[0][j];
        p->b[1] = f * p->b[0] + g * p->b[0];
        p->rows = 2;
        const int more = rng.integer(0, 4);
        for (int i = 0; i < more; ++i) add_random_row(rng, *p);
        Solution s;
        const Status st = solve(*p, Settings{}, nullptr, s);
        const reference::Result ref = reference::solve(*p);
        ASSERT_EQ(st == Status::Optimal, ref.feasible) << n << " " << to_string(st);
    }
}

TEST(Qp, InfeasibleProblemsAreDetected) {
    Rng rng(0x5eed0006);
    Tally tally;
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int kind = n % 4;
        if (kind == 0) {  // a.x >= 1 and a.x <= -1
            add_random_row(rng, *p);
            const int i = p->rows - 1, m = p->rows++;
            p->b[i] = 1;
            for (int j = 0; j < kPoseVars; ++j) p->a[m][j] = -p->a[i][j];
            p->b[m] = 1;
        } else if (kind == 1) {  // a row that the box cannot reach
            for (int j = 0; j < kPoseVars; ++j) {
                p->lower[j] = p->target[j] - 1;
                p->upper[j] = p->target[j] + 1;
            }
            const int i = p->rows++;
            random_normal(rng, p->a[i]);
            double reach = dot(p->a[i], p->target);
            for (int j = 0; j < kPoseVars; ++j) reach += std::fabs(p->a[i][j]);
            p->b[i] = reach + rng.uniform(1e-3, 1);
        } else if (kind == 2) {  // a1.x >= 1, a2.x >= 1, (a1 + a2).x <= 1
            add_random_row(rng, *p);
            add_random_row(rng, *p);
            p->b[0] = p->b[1] = 1;
            const int m = p->rows++;
            for (int j = 0; j < kPoseVars; ++j) p->a[m][j] = -(p->a[0][j] + p->a[1][j]);
            p->b[m] = -1;
        } else {  // a pinned variable against a row that needs it elsewhere
            const int j = rng.integer(0, kPoseVars - 1);
            p->lower[j] = p->upper[j] = 0;
            const int i = p->rows++;
            for (double& v : p->a[i]) v = 0;
            p->a[i][j] = rng.chance(0.5) ? 1 : -1;
            p->b[i] = rng.uniform(0.01, 1);
        }
        const int rows = rng.integer(0, kind == 1 ? 1 : 4);  // kind 1 has 12 bounds already
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 14 - p->rows - finite_bounds(*p));
        tally.add(check_problem(*p, "infeasible", n));
    }
    EXPECT_EQ(tally.infeasible, kPerCategory);
}

// Box bounds and rows mixed densely, near the reference's size limit.
TEST(Qp, DenseBoxAndRowProblemsMatchReference) {
    Rng rng(0x5eed0007);
    Tally tally;
    for (int n = 0; n < kPerCategory; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        for (int j = 0; j < kPoseVars; ++j) {
            const double s = 1 / std::sqrt(p->weight[j]);
            if (rng.chance(0.5)) p->lower[j] = p->target[j] + rng.uniform(-0.5, 0.3) * s;
            if (rng.chance(0.5)) p->upper[j] = p->target[j] + rng.uniform(-0.3, 0.5) * s;
            if (p->lower[j] > p->upper[j]) std::swap(p->lower[j], p->upper[j]);
        }
        const int rows = rng.integer(1, 14 - finite_bounds(*p));
        for (int i = 0; i < rows && i < 10; ++i) add_random_row(rng, *p);
        tally.add(check_problem(*p, "dense", n));
    }
    EXPECT_GT(tally.optimal, 0);
    EXPECT_GT(tally.infeasible, 0);
}

// The KKT conditions are sufficient for a convex QP, so large problems beyond the reference's
// reach are checked by them alone.
TEST(Qp, FullSizeProblemsSatisfyKkt) {
    Rng rng(0x5eed0008);
    for (int n = 0; n < 200; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        // Half-spaces that all hold at a centre c away from the target (so the problem is
        // feasible) and many of which cut the target off.
        double c[kPoseVars];
        for (int j = 0; j < kPoseVars; ++j) c[j] = p->target[j] + rng.uniform(-1, 1) / std::sqrt(p->weight[j]);
        const int rows = n % 2 ? kMaxRows : rng.integer(20, 64);
        for (int i = 0; i < rows; ++i) {
            random_normal(rng, p->a[i]);
            double nn = 0;
            for (int j = 0; j < kPoseVars; ++j) nn += p->a[i][j] * p->a[i][j] / p->weight[j];
            p->b[i] = dot(p->a[i], c) - std::sqrt(nn) * rng.uniform(0, 0.5);
        }
        p->rows = rows;
        const Settings settings;
        Solution s;
        ASSERT_EQ(solve(*p, settings, nullptr, s), Status::Optimal) << n;
        EXPECT_GT(s.active_count, 0);
        EXPECT_LE(s.max_violation, 1e-9);
        double grad[kPoseVars];
        for (int j = 0; j < kPoseVars; ++j) grad[j] = p->weight[j] * (s.x[j] - p->target[j]);
        for (int k = 0; k < s.active_count; ++k) {
            ASSERT_LT(s.active[k], p->rows);
            EXPECT_GE(s.multipliers[k], 0.0);
            EXPECT_NEAR(dot(p->a[s.active[k]], s.x), p->b[s.active[k]], 1e-9);
            for (int j = 0; j < kPoseVars; ++j) grad[j] -= s.multipliers[k] * p->a[s.active[k]][j];
        }
        for (int j = 0; j < kPoseVars; ++j) EXPECT_NEAR(grad[j], 0.0, 1e-8) << n;
    }
}

// A warm start changes the path, never the answer.
TEST(Qp, WarmStartGivesSameAnswer) {
    Rng rng(0x5eed0009);
    const Settings settings;
    for (int n = 0; n < 1000; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int rows = rng.integer(1, 24);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 12);
        Solution cold;
        solve(*p, settings, nullptr, cold);

        // Warm starts: the answer's own active set, the previous step's (target moved a
        // little), a reversed order, and indices that name nothing in this problem.
        WarmStart own;
        own.count = cold.active_count;
        for (int k = 0; k < own.count; ++k) own.active[k] = cold.active[k];
        auto moved = empty_problem();
        *moved = *p;
        for (int j = 0; j < kPoseVars; ++j) moved->target[j] += 1e-3 * rng.uniform(-1, 1);
        Solution previous;
        solve(*moved, settings, nullptr, previous);
        WarmStart prev;
        prev.count = previous.active_count;
        for (int k = 0; k < prev.count; ++k) prev.active[k] = previous.active[k];
        WarmStart reversed = own;
        for (int k = 0; k < own.count; ++k) reversed.active[k] = own.active[own.count - 1 - k];
        WarmStart junk;
        junk.count = 4;
        junk.active[0] = -1;
        junk.active[1] = kMaxRows + 5;
        junk.active[2] = kBoxLower + kPoseVars;
        junk.active[3] = 3 * kBoxUpper;

        for (const WarmStart* w : {&own, &prev, &reversed, &junk}) {
            Solution warm;
            solve(*p, settings, w, warm);
            ASSERT_EQ(warm.status, cold.status) << n;
            if (cold.status != Status::Optimal) continue;
            EXPECT_NEAR(warm.objective, cold.objective, 1e-9 * cold.objective + 1e-13) << n;
            for (int j = 0; j < kPoseVars; ++j)
                EXPECT_NEAR(warm.x[j], cold.x[j], 1e-7 / std::sqrt(p->weight[j])) << n;
            EXPECT_LE(warm.max_violation, 1e-9);
        }
    }
}

TEST(Qp, InvalidInputIsRejected) {
    const Settings settings;
    auto check = [&](const Problem& p, const char* what, const WarmStart* w = nullptr) {
        Solution s;
        EXPECT_EQ(solve(p, settings, w, s), Status::InvalidInput) << what;
        EXPECT_EQ(s.status, Status::InvalidInput) << what;
    };
    auto base = empty_problem();
    base->rows = 1;
    base->a[0][0] = 1;
    base->b[0] = 1;
    {
        Solution s;
        ASSERT_EQ(solve(*base, settings, nullptr, s), Status::Optimal);
    }
    auto p = empty_problem();
    *p = *base; p->weight[2] = 0; check(*p, "zero weight");
    *p = *base; p->weight[2] = -1; check(*p, "negative weight");
    *p = *base; p->weight[2] = kNaN; check(*p, "NaN weight");
    *p = *base; p->weight[2] = kInf; check(*p, "infinite weight");
    *p = *base; p->target[4] = kNaN; check(*p, "NaN target");
    *p = *base; p->target[4] = -kInf; check(*p, "infinite target");
    *p = *base; p->a[0][5] = kNaN; check(*p, "NaN row");
    *p = *base; p->a[0][5] = kInf; check(*p, "infinite row");
    *p = *base; p->b[0] = kNaN; check(*p, "NaN b");
    *p = *base; p->b[0] = -kInf; check(*p, "infinite b");
    *p = *base; p->lower[1] = 2; p->upper[1] = 1; check(*p, "lower > upper");
    *p = *base; p->lower[1] = kNaN; check(*p, "NaN lower");
    *p = *base; p->upper[1] = kNaN; check(*p, "NaN upper");
    *p = *base; p->lower[1] = kInf; check(*p, "lower = +inf");
    *p = *base; p->upper[1] = -kInf; check(*p, "upper = -inf");
    *p = *base; p->rows = -1; check(*p, "negative rows");
    *p = *base; p->rows = kMaxRows + 1; check(*p, "too many rows");
    {
        WarmStart w;
        w.count = kMaxVars + 1;
        check(*base, "warm start too long", &w);
        w.count = -1;
        check(*base, "negative warm start", &w);
    }
    {
        Settings bad;
        bad.feasibility_tol = kNaN;
        Solution s;
        EXPECT_EQ(solve(*base, bad, nullptr, s), Status::InvalidInput);
    }
    // Rows beyond `rows` are not part of the problem: garbage there is fine.
    *p = *base;
    p->a[1][0] = kNaN;
    p->b[1] = kNaN;
    Solution s;
    EXPECT_EQ(solve(*p, settings, nullptr, s), Status::Optimal);
}

TEST(Qp, ZeroRowsAreSkippedOrInfeasible) {
    auto p = empty_problem();
    p->rows = 2;
    p->a[0][0] = 1;
    p->b[0] = 1;
    for (double& v : p->a[1]) v = 0;
    p->b[1] = 0;  // 0 >= 0: always true
    Solution s;
    ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
    EXPECT_EQ(s.x[0], 1.0);
    EXPECT_EQ(s.active_count, 1);
    EXPECT_EQ(s.active[0], 0);
    p->b[1] = 1e-6;  // 0 >= 1e-6: never
    EXPECT_EQ(solve(*p, Settings{}, nullptr, s), Status::Infeasible);
}

TEST(Qp, UnconstrainedReturnsTarget) {
    auto p = empty_problem();
    for (int j = 0; j < kPoseVars; ++j) p->target[j] = 0.1 * (j + 1);
    p->rows = 1;
    p->a[0][0] = 1;
    p->b[0] = -5;  // satisfied at the target
    Solution s;
    ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
    for (int j = 0; j < kPoseVars; ++j) EXPECT_EQ(s.x[j], p->target[j]);
    EXPECT_EQ(s.objective, 0.0);
    EXPECT_EQ(s.active_count, 0);
    EXPECT_EQ(s.iterations, 0);
    EXPECT_DOUBLE_EQ(s.max_violation, -5.1);
}

// A known answer: x0 + x1 >= 2 with W = diag(1, 4) (other variables free at 0).
// Stationarity gives x = (1.6, 0.4), lambda = 1.6.
TEST(Qp, KnownAnswerWithUnequalWeights) {
    auto p = empty_problem();
    p->weight[1] = 4;
    p->rows = 1;
    p->a[0][0] = p->a[0][1] = 1;
    p->b[0] = 2;
    Solution s;
    ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
    EXPECT_NEAR(s.x[0], 1.6, 1e-15);
    EXPECT_NEAR(s.x[1], 0.4, 1e-15);
    ASSERT_EQ(s.active_count, 1);
    EXPECT_NEAR(s.multipliers[0], 1.6, 1e-15);
    EXPECT_NEAR(s.objective, 0.5 * (1.6 * 1.6 + 4 * 0.4 * 0.4), 1e-15);
    EXPECT_EQ(s.iterations, 1);
}

TEST(Qp, IterationCapReturnsLastIterate) {
    Rng rng(0x5eed000a);
    auto p = empty_problem();
    random_target(rng, *p);
    for (int i = 0; i < 6; ++i) {  // six independent violated rows need at least six additions
        for (int j = 0; j < kPoseVars; ++j) p->a[i][j] = (i == j) ? 1.0 : 0.1;
        p->b[i] = dot(p->a[i], p->target) + 1.0;
    }
    p->rows = 6;
    Settings settings;
    settings.max_iterations = 3;
    Solution s;
    ASSERT_EQ(solve(*p, settings, nullptr, s), Status::IterationLimit);
    EXPECT_EQ(s.status, Status::IterationLimit);
    EXPECT_EQ(s.iterations, 3);
    EXPECT_GT(s.max_violation, 0);
    for (double v : s.x) EXPECT_TRUE(std::isfinite(v));
    settings.max_iterations = 64;
    ASSERT_EQ(solve(*p, settings, nullptr, s), Status::Optimal);
    EXPECT_GE(s.iterations, 6);
}

bool same_bits(const Solution& a, const Solution& b) {
    return std::memcmp(a.x, b.x, sizeof a.x) == 0 && a.status == b.status &&
           a.iterations == b.iterations && a.active_count == b.active_count &&
           std::memcmp(a.active, b.active, sizeof a.active) == 0 &&
           std::memcmp(a.multipliers, b.multipliers, sizeof a.multipliers) == 0 &&
           std::memcmp(&a.objective, &b.objective, sizeof a.objective) == 0 &&
           std::memcmp(&a.max_violation, &b.max_violation, sizeof a.max_violation) == 0;
}

TEST(Qp, SameInputGivesSameBits) {
    Rng rng(0x5eed000b);
    std::vector<std::unique_ptr<Problem>> problems;
    for (int n = 0; n < 300; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int rows = rng.integer(0, 40);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 12);
        problems.push_back(std::move(p));
    }
    std::vector<Solution> first(problems.size());
    for (size_t n = 0; n < problems.size(); ++n) solve(*problems[n], Settings{}, nullptr, first[n]);
    // Again in reverse order, so no state can carry over from the previous call.
    for (size_t n = problems.size(); n-- > 0;) {
        Solution again;
        solve(*problems[n], Settings{}, nullptr, again);
        EXPECT_TRUE(same_bits(first[n], again)) << n;
    }
}

TEST(Qp, SolveDoesNotAllocate) {
    Rng rng(0x5eed000c);
    std::vector<std::unique_ptr<Problem>> problems;
    for (int n = 0; n < 200; ++n) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int rows = n % 3 == 0 ? kMaxRows : rng.integer(0, 40);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 12);
        problems.push_back(std::move(p));
    }
    WarmStart warm;
    warm.count = 2;
    warm.active[0] = 0;
    warm.active[1] = kBoxUpper + 1;
    auto bad = empty_problem();
    bad->weight[0] = -1;
    Solution s;
    const long before = sulcus::test::heap_allocations();
    {  // the counter itself must work
        auto probe = std::make_unique<int>(1);
        EXPECT_EQ(sulcus::test::heap_allocations(), before + 1);
    }
    const long start = sulcus::test::heap_allocations();
    int optimal = 0;
    for (const auto& p : problems) {
        optimal += solve(*p, Settings{}, nullptr, s) == Status::Optimal;
        solve(*p, Settings{}, &warm, s);
    }
    solve(*bad, Settings{}, nullptr, s);
    const long end = sulcus::test::heap_allocations();
    EXPECT_EQ(end, start);
    EXPECT_GT(optimal, 0);
}

// ---- Any number of variables: the pose plus slack variables of compliant contacts ----

constexpr int kSizes[] = {1, 3, 6, 9, 12, 16};

TEST(Qp, RandomProblemsOfEverySizeMatchReference) {
    Rng rng(0x5eed0101);
    for (const int n : kSizes) {
        Tally tally;
        const int count = n <= 6 ? 500 : 200;  // the reference's cost grows with n
        for (int k = 0; k < count; ++k) {
            auto p = empty_problem(n);
            random_weights(rng, *p);
            random_target(rng, *p);
            const int rows = rng.integer(0, 8);
            for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
            random_box(rng, *p, 12 - rows);
            tally.add(check_problem(*p, "every size", k));
        }
        EXPECT_EQ(tally.total, count) << n;
        EXPECT_GT(tally.optimal, count / 3) << n;
        // Active sets as large as the problem allows occur: more than six once n is larger.
        EXPECT_GE(tally.most_active, std::min(n, 7)) << n;
    }
}

// Variables kPoseVars to vars - 1 as the step's slacks: springs (weight 1e-2 to 1e3) at rest at
// 0, never negative, half of them capped.
void random_slacks(Rng& rng, Problem& p) {
    for (int j = kPoseVars; j < p.vars; ++j) {
        p.weight[j] = std::pow(10.0, rng.uniform(-2, 3));
        p.target[j] = 0;
        p.lower[j] = 0;
        if (rng.chance(0.5)) p.upper[j] = rng.uniform(0, 1) / std::sqrt(p.weight[j]);
    }
}

// A pose row that may sink in by one of the slacks, a_pose . x + s_k >= b.
void add_slack_row(Rng& rng, Problem& p) {
    const int i = p.rows++;
    random_normal(rng, p.a[i], kPoseVars);
    for (int j = kPoseVars; j < p.vars; ++j) p.a[i][j] = 0;
    // A compliant contact, or else a rigid one.
    if (rng.chance(0.7)) p.a[i][rng.integer(kPoseVars, p.vars - 1)] = 1;
    double nn = 0;
    for (int j = 0; j < kPoseVars; ++j) nn += p.a[i][j] * p.a[i][j] / p.weight[j];
    p.b[i] = dot(p.a[i], p.target, p.vars) + std::sqrt(nn) * rng.uniform(-0.3, 1.0);
}

// The paths compiled for sizes 6 to 10 give the any-size path's answer to the bit, on problems of
// the step's shape (pose rows sinking in by slacks) and on generic ones, cold and warm started.
TEST(Qp, SizedPathsGiveTheAnySizeAnswerToTheBit) {
    Rng rng(0x5eed0103);
    for (int n = kPoseVars; n <= kPoseVars + 4; ++n) {
        int optimal = 0, warm_used = 0;
        for (int k = 0; k < 300; ++k) {
            auto p = empty_problem(n);
            random_weights(rng, *p);
            random_target(rng, *p);
            const bool slacks = k % 2 == 0 && n > kPoseVars;
            if (slacks) random_slacks(rng, *p);
            const int rows = rng.integer(1, 12);
            for (int i = 0; i < rows; ++i) {
                if (slacks) add_slack_row(rng, *p);
                else add_random_row(rng, *p);
            }
            if (!slacks) random_box(rng, *p, 12 - rows);
            Solution sized, any;
            const Status st = solve(*p, Settings{}, nullptr, sized);
            ASSERT_EQ(solve_any_size(*p, Settings{}, nullptr, any), st) << n << " #" << k;
            EXPECT_TRUE(same_bits(sized, any)) << n << " #" << k;
            optimal += st == Status::Optimal;
            // Warm started from the answer's active set.
            WarmStart warm;
            warm.count = std::min(sized.active_count, kMaxVars);
            for (int i = 0; i < warm.count; ++i) warm.active[i] = sized.active[i];
            warm_used += warm.count > 0;
            Solution sized_warm, any_warm;
            solve(*p, Settings{}, &warm, sized_warm);
            solve_any_size(*p, Settings{}, &warm, any_warm);
            EXPECT_TRUE(same_bits(sized_warm, any_warm)) << n << " #" << k << " warm";
        }
        EXPECT_GT(optimal, 100) << n;
        EXPECT_GT(warm_used, 50) << n;
    }
}

// The shape the step builds: pose rows that may sink in by a slack s_k >= 0 (weight k_k,
// target 0, sometimes capped), a_pose . x + s_k >= b; several rows may share a slack.
TEST(Qp, RandomSlackProblemsMatchReference) {
    Rng rng(0x5eed0102);
    Tally tally;
    for (int k = 0; k < 300; ++k) {
        const int slacks = rng.integer(1, 3);
        const int n = kPoseVars + slacks;
        auto p = empty_problem(n);
        random_weights(rng, *p);
        random_target(rng, *p);
        random_slacks(rng, *p);
        const int rows = rng.integer(1, 5);
        for (int i = 0; i < rows; ++i) add_slack_row(rng, *p);
        tally.add(check_problem(*p, "slacks", k));
    }
    EXPECT_GT(tally.optimal, 200);
}

// One compliant contact. Three translational variables (weight 1) pulled to t = (0, 0, -d),
// against the surface z >= 0 whose tissue gives way by s (weight k, target 0, s >= 0):
// x_z + s >= 0. At the optimum the row is active and one force lambda stretches both springs,
// x_z - t_z = lambda = k s with x_z = -s, so
//   s = d / (1 + k),  x_z = -d / (1 + k),  lambda = d k / (1 + k),
//   objective = d^2 k / (2 (1 + k)).
TEST(Qp, SingleSlackMatchesClosedForm) {
    for (const double d : {1e-3, 0.3, 2.0}) {
        for (const double k : {1e-2, 1.0, 4.0, 1e3}) {
            SCOPED_TRACE(testing::Message() << "d=" << d << " k=" << k);
            auto p = empty_problem(4);
            p->target[2] = -d;
            p->weight[3] = k;
            p->lower[3] = 0;
            p->rows = 1;
            p->a[0][0] = p->a[0][1] = 0;
            p->a[0][2] = p->a[0][3] = 1;
            p->b[0] = 0;
            Solution s;
            ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
            EXPECT_NEAR(s.x[0], 0.0, 1e-12);
            EXPECT_NEAR(s.x[1], 0.0, 1e-12);
            EXPECT_NEAR(s.x[2], -d / (1 + k), 1e-12);
            EXPECT_NEAR(s.x[3], d / (1 + k), 1e-12);
            ASSERT_EQ(s.active_count, 1);
            EXPECT_EQ(s.active[0], 0);
            EXPECT_NEAR(s.multipliers[0], d * k / (1 + k), 1e-12);
            EXPECT_NEAR(s.objective, d * d * k / (2 * (1 + k)), 1e-12);
        }
    }
    // One case by hand: d = 0.3, k = 4 gives x_z = -0.06, s = 0.06, lambda = 0.24.
    auto p = empty_problem(4);
    p->target[2] = -0.3;
    p->weight[3] = 4;
    p->lower[3] = 0;
    p->rows = 1;
    p->a[0][0] = p->a[0][1] = 0;
    p->a[0][2] = p->a[0][3] = 1;
    p->b[0] = 0;
    Solution s;
    ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
    EXPECT_NEAR(s.x[2], -0.06, 1e-12);
    EXPECT_NEAR(s.x[3], 0.06, 1e-12);
    EXPECT_NEAR(s.multipliers[0], 0.24, 1e-12);
}

// Two slacks in series on one row, x_z + s1 + s2 >= 0, with the tool pulled to t_z = -d = -1:
// s1 (weight k1 = 2, box [0, c1]) and s2 (weight k2 = 3, box [0, inf)).
// Below the cap the three springs carry one force: x_z + d = k1 s1 = k2 s2 = lambda, so
//   lambda = d / (1 + 1/k1 + 1/k2) = 6/11, s1 = 3/11, s2 = 2/11, x_z = -5/11,
// which holds while s1 = 3/11 <= c1. Above it s1 sits at c1 and its cap takes the rest:
//   lambda = (d - c1) k2 / (1 + k2), s2 = lambda / k2, x_z = lambda - d, cap multiplier
//   mu = lambda - k1 c1; for c1 = 0.1: lambda = 0.675, s2 = 0.225, x_z = -0.325, mu = 0.475.
TEST(Qp, SeriesSlacksShareTheLoadBelowTheCapAndSaturateAboveIt) {
    auto make = [](double c1) {
        auto p = empty_problem(5);
        p->target[2] = -1;
        p->weight[3] = 2;
        p->lower[3] = 0;
        p->upper[3] = c1;
        p->weight[4] = 3;
        p->lower[4] = 0;
        p->rows = 1;
        p->a[0][0] = p->a[0][1] = 0;
        p->a[0][2] = p->a[0][3] = p->a[0][4] = 1;
        p->b[0] = 0;
        return p;
    };
    {  // below the cap: both slacks share the load, the cap is not active
        const auto p = make(0.5);
        Solution s;
        ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
        EXPECT_NEAR(s.x[0], 0.0, 1e-12);
        EXPECT_NEAR(s.x[1], 0.0, 1e-12);
        EXPECT_NEAR(s.x[2], -5.0 / 11, 1e-12);
        EXPECT_NEAR(s.x[3], 3.0 / 11, 1e-12);
        EXPECT_NEAR(s.x[4], 2.0 / 11, 1e-12);
        ASSERT_EQ(s.active_count, 1);
        EXPECT_EQ(s.active[0], 0);
        EXPECT_NEAR(s.multipliers[0], 6.0 / 11, 1e-12);
        const double obj = 0.5 * (6.0 / 11) * (6.0 / 11) + 0.5 * 2 * (3.0 / 11) * (3.0 / 11) +
                           0.5 * 3 * (2.0 / 11) * (2.0 / 11);
        EXPECT_NEAR(s.objective, obj, 1e-12);
    }
    {  // above it: s1 at its cap, s2 takes the rest
        const auto p = make(0.1);
        Solution s;
        ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
        EXPECT_NEAR(s.x[0], 0.0, 1e-12);
        EXPECT_NEAR(s.x[1], 0.0, 1e-12);
        EXPECT_NEAR(s.x[2], -0.325, 1e-12);
        EXPECT_EQ(s.x[3], 0.1);  // an active bound holds exactly
        EXPECT_NEAR(s.x[4], 0.225, 1e-12);
        ASSERT_EQ(s.active_count, 2);
        double row = -1, cap = -1;
        for (int k = 0; k < 2; ++k) {
            if (s.active[k] == 0) row = s.multipliers[k];
            if (s.active[k] == kBoxUpper + 3) cap = s.multipliers[k];
        }
        EXPECT_NEAR(row, 0.675, 1e-12);
        EXPECT_NEAR(cap, 0.475, 1e-12);
        const double obj = 0.5 * 0.675 * 0.675 + 0.5 * 2 * 0.1 * 0.1 + 0.5 * 3 * 0.225 * 0.225;
        EXPECT_NEAR(s.objective, obj, 1e-12);
    }
}

TEST(Qp, VariableCountOutOfRangeIsRejected) {
    auto p = empty_problem(kMaxVars);
    p->rows = 1;
    p->a[0][0] = 1;
    p->b[0] = 1;
    Solution s;
    for (const int vars : {0, kMaxVars + 1, -1}) {
        p->vars = vars;
        EXPECT_EQ(solve(*p, Settings{}, nullptr, s), Status::InvalidInput) << vars;
        EXPECT_EQ(s.status, Status::InvalidInput) << vars;
    }
    for (const int vars : {1, kMaxVars}) {  // the limits themselves are fine
        p->vars = vars;
        EXPECT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal) << vars;
    }
}

// Entries beyond vars are not part of the problem: garbage there changes no bit of the answer,
// and the answer's own entries beyond vars are zero whatever the Solution held before.
TEST(Qp, EntriesBeyondVarsAreIgnored) {
    Rng rng(0x5eed0103);
    for (const int n : {1, 3, 6, 9, 15}) {
        for (int k = 0; k < 50; ++k) {
            auto p = empty_problem(n);
            random_weights(rng, *p);
            random_target(rng, *p);
            const int rows = rng.integer(0, 20);
            for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
            random_box(rng, *p, 2 * n);
            Solution clean;
            solve(*p, Settings{}, nullptr, clean);
            auto dirty = empty_problem(n);
            *dirty = *p;
            for (int j = n; j < kMaxVars; ++j) {
                dirty->weight[j] = j % 2 ? kNaN : -1;
                dirty->target[j] = kInf;
                dirty->lower[j] = 1;
                dirty->upper[j] = j % 2 ? -1 : kNaN;
                for (int i = 0; i < kMaxRows; ++i) dirty->a[i][j] = kNaN;
            }
            Solution s;  // left over from a larger problem
            for (double& v : s.x) v = 7;
            for (int& a : s.active) a = 7;
            for (double& m : s.multipliers) m = 7;
            solve(*dirty, Settings{}, nullptr, s);
            EXPECT_TRUE(same_bits(clean, s)) << n << " #" << k;
            for (int j = n; j < kMaxVars; ++j) EXPECT_EQ(s.x[j], 0.0);
            for (int i = s.active_count; i < kMaxVars; ++i) EXPECT_EQ(s.active[i], 0);
        }
    }
}

// A variable in no row and with no bound stays at its target and changes nothing else: the
// 6-variable problem (the solver's fixed-size path) and the same problem with a seventh such
// variable (the run-time-size path) give the same status, active set and point.
TEST(Qp, UnusedVariableChangesNothing) {
    Rng rng(0x5eed0104);
    int optimal = 0;
    for (int k = 0; k < 1000; ++k) {
        auto p = empty_problem();
        random_weights(rng, *p);
        random_target(rng, *p);
        const int rows = rng.integer(0, 24);
        for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
        random_box(rng, *p, 12);
        auto q = empty_problem(kPoseVars + 1);
        *q = *p;
        q->vars = kPoseVars + 1;
        q->weight[kPoseVars] = 0.5;
        q->target[kPoseVars] = 0.25;
        q->lower[kPoseVars] = -kInf;
        q->upper[kPoseVars] = kInf;
        for (int i = 0; i < rows; ++i) q->a[i][kPoseVars] = 0;
        Solution a, b;
        solve(*p, Settings{}, nullptr, a);
        solve(*q, Settings{}, nullptr, b);
        ASSERT_EQ(a.status, b.status) << k;
        if (a.status != Status::Optimal) continue;
        ++optimal;
        ASSERT_EQ(a.active_count, b.active_count) << k;
        for (int i = 0; i < a.active_count; ++i) EXPECT_EQ(a.active[i], b.active[i]) << k;
        for (int j = 0; j < kPoseVars; ++j)
            EXPECT_NEAR(a.x[j], b.x[j], 1e-12 * (1 + std::fabs(a.x[j])) / std::sqrt(p->weight[j]))
                << k;
        EXPECT_EQ(b.x[kPoseVars], 0.25);
        EXPECT_NEAR(a.objective, b.objective, 1e-12 * (1 + a.objective)) << k;
    }
    EXPECT_GT(optimal, 300);
}

// Many rows, beyond the reference's reach, at every size: checked by the KKT conditions.
TEST(Qp, FullSizeProblemsOfEverySizeSatisfyKkt) {
    Rng rng(0x5eed0105);
    for (const int n : kSizes) {
        for (int k = 0; k < 60; ++k) {
            SCOPED_TRACE(testing::Message() << "n=" << n << " #" << k);
            auto p = empty_problem(n);
            random_weights(rng, *p);
            random_target(rng, *p);
            // Half-spaces that all hold at a centre away from the target (so the problem is
            // feasible), many of which cut the target off.
            double c[kMaxVars];
            for (int j = 0; j < n; ++j)
                c[j] = p->target[j] + rng.uniform(-1, 1) / std::sqrt(p->weight[j]);
            const int rows = k % 2 ? kMaxRows : rng.integer(20, 64);
            for (int i = 0; i < rows; ++i) {
                random_normal(rng, p->a[i], n);
                double nn = 0;
                for (int j = 0; j < n; ++j) nn += p->a[i][j] * p->a[i][j] / p->weight[j];
                p->b[i] = dot(p->a[i], c, n) - std::sqrt(nn) * rng.uniform(0, 0.5);
            }
            p->rows = rows;
            Solution s;
            ASSERT_EQ(solve(*p, Settings{}, nullptr, s), Status::Optimal);
            EXPECT_GT(s.active_count, 0);
            EXPECT_LE(s.max_violation, 1e-9);
            expect_kkt(*p, s);
        }
    }
}

// Same input, same bits, and no allocation, at every size.
TEST(Qp, EverySizeIsDeterministicAndDoesNotAllocate) {
    Rng rng(0x5eed0106);
    std::vector<std::unique_ptr<Problem>> problems;
    for (const int n : kSizes) {
        for (int k = 0; k < 40; ++k) {
            auto p = empty_problem(n);
            random_weights(rng, *p);
            random_target(rng, *p);
            const int rows = k % 4 == 0 ? kMaxRows : rng.integer(0, 40);
            for (int i = 0; i < rows; ++i) add_random_row(rng, *p);
            random_box(rng, *p, 2 * n);
            problems.push_back(std::move(p));
        }
    }
    std::vector<Solution> first(problems.size());
    for (size_t k = 0; k < problems.size(); ++k) solve(*problems[k], Settings{}, nullptr, first[k]);
    WarmStart warm;
    warm.count = kMaxVars;
    for (int k = 0; k < kMaxVars; ++k) warm.active[k] = k % 3 ? k : kBoxLower + k;
    Solution again, warmed;
    const long start = sulcus::test::heap_allocations();
    int same = 0, optimal = 0;
    // In reverse order, so no state can carry over from the previous call.
    for (size_t k = problems.size(); k-- > 0;) {
        solve(*problems[k], Settings{}, nullptr, again);
        same += same_bits(first[k], again);
        optimal += solve(*problems[k], Settings{}, &warm, warmed) == Status::Optimal;
    }
    const long end = sulcus::test::heap_allocations();
    EXPECT_EQ(end, start);
    EXPECT_EQ(same, static_cast<int>(problems.size()));
    EXPECT_GT(optimal, 0);
}

TEST(Qp, StatusNames) {
    EXPECT_STREQ(to_string(Status::Optimal), "optimal");
    EXPECT_STREQ(to_string(Status::Infeasible), "infeasible");
    EXPECT_STREQ(to_string(Status::IterationLimit), "iteration_limit");
    EXPECT_STREQ(to_string(Status::InvalidInput), "invalid_input");
}

}  // namespace
}  // namespace sulcus::qp
