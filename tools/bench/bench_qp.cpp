// Time of one qp::solve on servo-like problems: 6 variables, 8 / 24 / 64 rows, the haptic weight
// pattern (translation 1, rotation 1e-4) and a local-solution box, from a fixed-seed generator;
// and the same problems with 10 slack variables added (compliant contacts, 16 variables), or with
// 2 and 3 (the tissue session's 8 and 9 variables), on the path compiled for their size and on
// the path for any size (qp::solve_any_size: the same answers).
//
//   bench_qp [google benchmark flags]   per-solve time via Google Benchmark
//   bench_qp --stats                    median, p99 and max over 100000 solves (steady_clock)
#include "sulcus/engine/qp.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace {

using namespace sulcus::qp;

constexpr int kPool = 256;  // distinct problems cycled through, so caches see varied data

double uniform(std::mt19937_64& g, double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(g() >> 11) * 0x1.0p-53);
}

// Rows are half-spaces holding at a centre point near the target, with margins of a fraction
// of a W-metric unit, so a handful of rows end up active, as in a contact with several
// principal contacts.
std::vector<std::unique_ptr<Problem>> make_pool(int rows, uint64_t seed) {
    std::mt19937_64 g(seed);
    std::vector<std::unique_ptr<Problem>> pool;
    for (int n = 0; n < kPool; ++n) {
        auto p = std::make_unique<Problem>();
        p->vars = kPoseVars;
        for (int j = 0; j < kPoseVars; ++j) {
            p->weight[j] = j < 3 ? 1.0 : 1e-4;
            p->target[j] = j < 3 ? uniform(g, -1e-3, 1e-3) : uniform(g, -0.05, 0.05);
            const double reach = j < 3 ? 2e-3 : 0.1;
            p->lower[j] = p->target[j] - reach;
            p->upper[j] = p->target[j] + reach * uniform(g, 0.5, 1.0);
        }
        // The centre lies inside the box and inside every row, so every problem is feasible.
        double centre[kPoseVars];
        for (int j = 0; j < kPoseVars; ++j)
            centre[j] = p->target[j] + (j < 3 ? 2e-3 : 0.1) * 0.4 * uniform(g, -1, 1);
        p->rows = rows;
        for (int i = 0; i < rows; ++i) {
            double nn = 0, ac = 0;
            for (int j = 0; j < kPoseVars; ++j) {
                // Translation rows of unit size, rotation columns like lever arms (~1 cm).
                p->a[i][j] = (j < 3 ? 1.0 : 1e-2) * uniform(g, -1, 1);
                nn += p->a[i][j] * p->a[i][j] / p->weight[j];
                ac += p->a[i][j] * centre[j];
            }
            p->b[i] = ac - 1e-4 * std::sqrt(nn) * uniform(g, 0.5, 1.0);
        }
        pool.push_back(std::move(p));
    }
    return pool;
}

void BM_Solve(benchmark::State& state) {
    const auto pool = make_pool(static_cast<int>(state.range(0)), 42);
    const Settings settings;
    Solution s;
    size_t n = 0;
    long iterations = 0, solves = 0;
    for (auto _ : state) {
        solve(*pool[n], settings, nullptr, s);
        benchmark::DoNotOptimize(s);
        iterations += s.iterations;
        ++solves;
        n = (n + 1) % pool.size();
    }
    state.counters["iters/solve"] = static_cast<double>(iterations) / static_cast<double>(solves);
    state.counters["active"] = s.active_count;
}
BENCHMARK(BM_Solve)->Arg(8)->Arg(24)->Arg(64);

// Seeded with the active set of the same problem (the previous step's answer in a steady contact).
void BM_SolveWarm(benchmark::State& state) {
    const auto pool = make_pool(static_cast<int>(state.range(0)), 42);
    const Settings settings;
    std::vector<WarmStart> warm(pool.size());
    Solution s;
    for (size_t n = 0; n < pool.size(); ++n) {
        solve(*pool[n], settings, nullptr, s);
        warm[n].count = s.active_count;
        std::memcpy(warm[n].active, s.active, sizeof s.active);
    }
    size_t n = 0;
    for (auto _ : state) {
        solve(*pool[n], settings, &warm[n], s);
        benchmark::DoNotOptimize(s);
        n = (n + 1) % pool.size();
    }
}
BENCHMARK(BM_SolveWarm)->Arg(8)->Arg(24)->Arg(64);

// The pose problems with every row made compliant: `slacks` slack variables (weight 10, a
// stiffer spring than the pose's, box [0, inf)), row i sinking by slack i mod their count.
std::vector<std::unique_ptr<Problem>> make_slack_pool(int rows, uint64_t seed, int slacks = kMaxVars - kPoseVars) {
    auto pool = make_pool(rows, seed);
    const int vars = kPoseVars + slacks;
    for (auto& p : pool) {
        p->vars = vars;
        for (int j = kPoseVars; j < vars; ++j) {
            p->weight[j] = 10.0;
            p->target[j] = 0.0;
            p->lower[j] = 0.0;
            p->upper[j] = std::numeric_limits<double>::infinity();
        }
        for (int i = 0; i < rows; ++i)
            for (int j = kPoseVars; j < vars; ++j)
                p->a[i][j] = (j - kPoseVars == i % slacks) ? 1.0 : 0.0;
    }
    return pool;
}

void BM_SolveSlacks(benchmark::State& state) {
    const auto pool = make_slack_pool(static_cast<int>(state.range(0)), 42);
    const Settings settings;
    Solution s;
    size_t n = 0;
    long iterations = 0, solves = 0;
    for (auto _ : state) {
        solve(*pool[n], settings, nullptr, s);
        benchmark::DoNotOptimize(s);
        iterations += s.iterations;
        ++solves;
        n = (n + 1) % pool.size();
    }
    state.counters["iters/solve"] = static_cast<double>(iterations) / static_cast<double>(solves);
    state.counters["active"] = s.active_count;
}
BENCHMARK(BM_SolveSlacks)->Arg(8)->Arg(24)->Arg(64);

// 24 rows with 2 or 3 slacks (8 or 9 variables): range(1) 0 on the path compiled for the size,
// 1 on the path for any size.
void BM_SolveTissue(benchmark::State& state) {
    const auto pool = make_slack_pool(24, 42, static_cast<int>(state.range(0)));
    const bool any_size = state.range(1) != 0;
    const Settings settings;
    Solution s;
    size_t n = 0;
    for (auto _ : state) {
        if (any_size) solve_any_size(*pool[n], settings, nullptr, s);
        else solve(*pool[n], settings, nullptr, s);
        benchmark::DoNotOptimize(s);
        n = (n + 1) % pool.size();
    }
}
BENCHMARK(BM_SolveTissue)->Args({2, 0})->Args({2, 1})->Args({3, 0})->Args({3, 1});

int run_stats() {
    constexpr int kSolves = 100000;
    std::printf("%-6s %10s %10s %10s %10s %8s %s\n", "rows", "median_us", "p99_us", "max_us",
                "mean_iter", "max_iter", "status(opt/infeas/limit)");
    for (int rows : {8, 24, 64}) {
        const auto pool = make_pool(rows, 42);
        const Settings settings;
        Solution s;
        std::vector<double> us(kSolves);
        long iterations = 0;
        int max_iter = 0, counts[4] = {0, 0, 0, 0};
        for (int k = 0; k < kSolves; ++k) {
            const Problem& p = *pool[k % kPool];
            const auto t0 = std::chrono::steady_clock::now();
            solve(p, settings, nullptr, s);
            const auto t1 = std::chrono::steady_clock::now();
            us[k] = std::chrono::duration<double, std::micro>(t1 - t0).count();
            iterations += s.iterations;
            max_iter = std::max(max_iter, s.iterations);
            ++counts[static_cast<int>(s.status)];
        }
        std::sort(us.begin(), us.end());
        std::printf("%-6d %10.3f %10.3f %10.3f %10.2f %8d %d/%d/%d\n", rows, us[kSolves / 2],
                    us[static_cast<size_t>(kSolves * 0.99)], us.back(),
                    static_cast<double>(iterations) / kSolves, max_iter, counts[0], counts[1],
                    counts[2]);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--stats") == 0) return run_stats();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
