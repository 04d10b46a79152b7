// A slow, independent reference for qp::solve, for tests only.
//
// For a strictly convex QP the optimum is the unique KKT point, and it satisfies the KKT
// conditions with some linearly independent subset of at most n = vars active constraints. So:
// enumerate every subset of at most n constraints (general rows and finite box bounds),
// solve the equality-constrained QP on it with a dense rank-revealing factorisation, keep the
// points that are primal feasible and have non-negative multipliers, and return the one of
// least objective (near-ties to the most feasible). No subset qualifies -> infeasible. Cost
// is exponential in the constraint count (and, up to it, in n), so keep test problems at 14
// constraints or fewer.
#pragma once

#include "sulcus/engine/qp.h"

#include <Eigen/Dense>

#include <cassert>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace sulcus::qp::reference {

struct Result {
    bool feasible = false;
    double x[kMaxVars] = {};  // zero beyond vars
    double objective = 0;
    int subset_size = 0;     // size of the subset that produced x
    int subsets_tried = 0;   // subsets with linearly independent normals
};

struct Constraint {
    int vars = 0;
    double a[kMaxVars] = {};
    double b = 0;
};

// All constraints as a.x >= b: rows first, then x_j >= lower_j, then -x_j >= -upper_j.
inline std::vector<Constraint> constraints_of(const Problem& p) {
    const int n = p.vars;
    std::vector<Constraint> out;
    for (int i = 0; i < p.rows; ++i) {
        Constraint c{};
        c.vars = n;
        for (int j = 0; j < n; ++j) c.a[j] = p.a[i][j];
        c.b = p.b[i];
        out.push_back(c);
    }
    for (int j = 0; j < n; ++j) {
        if (std::isfinite(p.lower[j])) {
            Constraint c{};
            c.vars = n;
            c.a[j] = 1;
            c.b = p.lower[j];
            out.push_back(c);
        }
    }
    for (int j = 0; j < n; ++j) {
        if (std::isfinite(p.upper[j])) {
            Constraint c{};
            c.vars = n;
            c.a[j] = -1;
            c.b = -p.upper[j];
            out.push_back(c);
        }
    }
    return out;
}

// b - a.x relative to the size of its terms, the scale of its rounding error.
inline double violation(const Constraint& c, const double* x) {
    double ax = 0, size = 1 + std::fabs(c.b);
    for (int j = 0; j < c.vars; ++j) {
        ax += c.a[j] * x[j];
        size += std::fabs(c.a[j] * x[j]);
    }
    return (c.b - ax) / size;
}

inline Result solve(const Problem& p, double tol = 1e-9) {
    using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxVars, kMaxVars>;
    using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxVars, 1>;
    const int n = p.vars;
    assert(n >= 1 && n <= kMaxVars);
    Result best;

    const std::vector<Constraint> all = constraints_of(p);
    struct Candidate {
        double x[kMaxVars];
        double objective;
        double violation;  // largest relative violation over all constraints
        int subset_size;
    };
    std::vector<Candidate> candidates;
    // Zero rows are constant: they either hold everywhere or nowhere.
    std::vector<int> usable;
    for (int i = 0; i < static_cast<int>(all.size()); ++i) {
        double n2 = 0;
        for (double v : all[i].a) n2 += v * v;
        if (n2 > 0) {
            usable.push_back(i);
        } else if (all[i].b > 0) {
            return best;
        }
    }
    const int m = static_cast<int>(usable.size());
    assert(m <= 16 && "the reference is exponential in the constraint count");

    // Equality-constrained minimiser on subset S, in the scaled variable u = W^(1/2)(x - t)
    // with unit rows n_i = W^(-1/2) a_i / |W^(-1/2) a_i|: the minimum-norm solution of
    // N u = c, u = N^T mu. With N^T P = Q R (column-pivoting Householder QR, which also
    // reveals the rank): mu = P R^-1 R^-T P^T c. Working on N rather than on the Gram matrix
    // N N^T keeps the conditioning unsquared for the rank decision.
    auto try_subset = [&](const int* idx, int k) {
        Mat Nt(n, k);
        Vec c(k), scale(k);
        for (int r = 0; r < k; ++r) {
            const Constraint& con = all[usable[idx[r]]];
            double at = 0, n2 = 0;
            for (int j = 0; j < n; ++j) {
                at += con.a[j] * p.target[j];
                n2 += con.a[j] * con.a[j] / p.weight[j];
            }
            scale[r] = 1.0 / std::sqrt(n2);
            for (int j = 0; j < n; ++j) Nt(j, r) = con.a[j] / std::sqrt(p.weight[j]) * scale[r];
            c[r] = (con.b - at) * scale[r];
        }
        Vec mu(k);
        Vec u = Vec::Zero(n);
        if (k > 0) {
            Eigen::ColPivHouseholderQR<Mat> qr(Nt);
            qr.setThreshold(1e-10);
            if (qr.rank() < k) return;
            const auto R = qr.matrixR().topLeftCorner(k, k).template triangularView<Eigen::Upper>();
            Vec y = qr.colsPermutation().transpose() * c;
            R.transpose().solveInPlace(y);
            // u = Q [y; 0] directly, rather than N^T mu, keeps its error at cond(N) eps.
            Vec full = Vec::Zero(n);
            full.head(k) = y;
            u = qr.householderQ() * full;
            R.solveInPlace(y);
            const Vec nu = qr.colsPermutation() * y;  // multipliers on the unit rows
            mu = nu.cwiseProduct(scale);                // multipliers on the rows a_i
        }
        ++best.subsets_tried;
        for (int r = 0; r < k; ++r)
            if (mu[r] < -tol) return;
        double x[kMaxVars] = {};
        for (int j = 0; j < n; ++j) x[j] = p.target[j] + u[j] / std::sqrt(p.weight[j]);
        Candidate cand{};
        cand.violation = -std::numeric_limits<double>::infinity();
        for (const Constraint& c : all) cand.violation = std::max(cand.violation, violation(c, x));
        if (cand.violation > tol) return;
        for (int j = 0; j < kMaxVars; ++j) cand.x[j] = x[j];
        for (int j = 0; j < n; ++j)
            cand.objective += 0.5 * p.weight[j] * (x[j] - p.target[j]) * (x[j] - p.target[j]);
        cand.subset_size = k;
        candidates.push_back(cand);
    };

    // Subsets in lexicographic order, sizes 0..n.
    int idx[kMaxVars];
    for (int k = 0; k <= n && k <= m; ++k) {
        for (int r = 0; r < k; ++r) idx[r] = r;
        for (;;) {
            try_subset(idx, k);
            int r = k - 1;
            while (r >= 0 && idx[r] == m - k + r) --r;
            if (r < 0) break;
            ++idx[r];
            for (int s = r + 1; s < k; ++s) idx[s] = idx[s - 1] + 1;
        }
    }
    // Least objective. A subset's point may violate another constraint by up to tol and so
    // undercut the true optimum by a hair; among near-ties the most feasible point wins.
    if (candidates.empty()) return best;
    double least = candidates[0].objective;
    for (const Candidate& c : candidates) least = std::min(least, c.objective);
    const Candidate* pick = nullptr;
    for (const Candidate& c : candidates)
        if (c.objective <= least + 1e-9 * std::fabs(least) + 1e-15 &&
            (!pick || c.violation < pick->violation))
            pick = &c;
    best.feasible = true;
    best.objective = pick->objective;
    best.subset_size = pick->subset_size;
    for (int j = 0; j < kMaxVars; ++j) best.x[j] = pick->x[j];
    return best;
}

}  // namespace sulcus::qp::reference
