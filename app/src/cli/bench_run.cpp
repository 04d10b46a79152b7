#include "cli/bench_run.h"

#include "cli/allocation_count.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/mesh.h"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace sulcus::cli {

namespace {

// Writes and reads a buffer larger than the caches, so that a further run starts as cold as the
// first (whose model was built just before it) instead of on the last run's cache lines.
void evict_caches(std::vector<unsigned char>& buffer) {
    constexpr size_t kBytes = size_t(128) << 20;
    if (buffer.size() != kBytes) buffer.assign(kBytes, 0);
    volatile unsigned char sink = 0;
    for (size_t i = 0; i < buffer.size(); i += 64) {
        buffer[i] = static_cast<unsigned char>(buffer[i] + 1);
        sink = static_cast<unsigned char>(sink + buffer[i]);
    }
    (void)sink;
}

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool same_bits(const Pose& a, const Pose& b) {
    return same_bits(a.position, b.position) && std::memcmp(&a.orientation, &b.orientation, sizeof a.orientation) == 0;
}

}  // namespace

BenchRun run_bench(const BenchScene& b, RendererSettings settings, const BenchRunOptions& options) {
    BenchRun run;
    settings.haptic = b.scene.haptic;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    if (!mb.model) {
        run.error = b.scene.path + ": " + mb.error;
        return run;
    }
    run.model = std::move(mb.model);
    const Model& model = *run.model;
    if (b.ticks.empty()) return run;
    std::vector<PlacedMesh> rigid, compliant;
    for (size_t i = 0; i < b.scene.objects.size(); ++i)
        (model.objects[i].compliant ? compliant : rigid).push_back(PlacedMesh{&b.scene.objects[i].mesh, b.scene.objects[i].pose});
    const std::vector<TriMesh> pieces = connected_components(b.scene.tool.mesh);

    const int runs = std::max(1, options.runs);
    const size_t n = options.max_ticks > 0 ? std::min(b.ticks.size(), size_t(options.max_ticks)) : b.ticks.size();
    run.ticks.resize(n);
    State state = make_state(b.ticks.front());
    {
        // The first step on a thread makes its workspace: outside the figures.
        State scratch = state;
        step(model, scratch, b.ticks.front());
    }
    long contact_ticks = 0;
    // The exact checks run after the timed steps, so that what they read does not leave the
    // next step's caches colder than a servo loop's would be.
    std::vector<size_t> to_check;
    to_check.reserve(n);
    for (size_t i = 0; i < n; ++i) {
        const long allocs = thread_heap_allocations();
        const auto t0 = std::chrono::steady_clock::now();
        const StepResult r = step(model, state, b.ticks[i]);
        const auto t1 = std::chrono::steady_clock::now();
        BenchTick& t = run.ticks[i];
        t.allocations = thread_heap_allocations() - allocs;
        t.step_us = std::chrono::duration<double, std::micro>(t1 - t0).count();
        t.least_step_us = t.step_us;
        t.stats = r.stats;
        t.status = r.status;
        t.graphic = r.graphic;
        t.force_N = r.force_N;
        t.torque_Nm = r.torque_Nm;
        t.contact = r.contacts > 0;
        const bool has_force = glm::length(r.force_N) > 0.0 || glm::length(r.torque_Nm) > 0.0;
        if (options.check_every > 0 && has_force && contact_ticks++ % options.check_every == 0) to_check.push_back(i);
    }
    // Further runs from a fresh state (a new session: the step's caches start over), after the
    // machine's caches are flushed. The same input must give the same answer to the bit; the
    // least time per tick leaves out what the machine took from the thread in one run but not in
    // another. Each tick's work ahead of need is placed as in the first run (State::defer), whose
    // clock placed it: every run then does the same work at every tick.
    std::vector<unsigned char> evict;
    for (int k = 1; k < runs; ++k) {
        evict_caches(evict);
        state = make_state(b.ticks.front());
        {
            State scratch = state;
            step(model, scratch, b.ticks.front());
        }
        for (size_t i = 0; i < n; ++i) {
            BenchTick& t = run.ticks[i];
            state.defer = t.stats.deferred ? 1 : 0;
            const long allocs = thread_heap_allocations();
            const auto t0 = std::chrono::steady_clock::now();
            const StepResult r = step(model, state, b.ticks[i]);
            const auto t1 = std::chrono::steady_clock::now();
            t.allocations = std::max(t.allocations, thread_heap_allocations() - allocs);
            t.least_step_us = std::min(t.least_step_us, std::chrono::duration<double, std::micro>(t1 - t0).count());
            if (r.status != t.status || !same_bits(r.graphic, t.graphic) || !same_bits(r.force_N, t.force_N) ||
                !same_bits(r.torque_Nm, t.torque_Nm)) {
                run.error = b.scene.path + ": run " + std::to_string(k + 1) + ", tick " + std::to_string(i) +
                            ": the answer differs from run 1's (the step is not deterministic)";
                return run;
            }
        }
    }
    for (const size_t i : to_check) {
        constexpr double kGapLimit = 1e-3;
        const Pose& graphic = run.ticks[i].graphic;
        const ExactCheck c = exact_check(pieces, graphic, rigid, kGapLimit);
        double gap = c.distance_m;
        if (!compliant.empty()) gap = std::min(gap, exact_check(pieces, graphic, compliant, kGapLimit).distance_m);
        run.max_penetration_m = std::max(run.max_penetration_m, c.penetration_m);
        run.max_gap_in_contact_m = std::max(run.max_gap_in_contact_m, gap);
        ++run.checked_ticks;
    }
    return run;
}

Interruptions probe_interruptions(double seconds, double threshold_us) {
    using Clock = std::chrono::steady_clock;
    Interruptions out;
    if (!(seconds > 0.0)) return out;
    std::vector<double> lengths;
    // Room for every gap there can be: none is shorter than the threshold.
    lengths.reserve(size_t(seconds * 1e6 / std::max(threshold_us, 1.0)) + 16);
    const Clock::time_point start = Clock::now();
    Clock::time_point prev = start;
    const auto span = std::chrono::duration<double>(seconds);
    for (;;) {
        const Clock::time_point t = Clock::now();
        const double gap_us = std::chrono::duration<double, std::micro>(t - prev).count();
        if (gap_us >= threshold_us && lengths.size() < lengths.capacity()) lengths.push_back(gap_us);
        prev = t;
        if (t - start >= span) break;
    }
    out.seconds = std::chrono::duration<double>(prev - start).count();
    out.count = long(lengths.size());
    out.per_second = double(out.count) / out.seconds;
    double lost = 0.0;
    for (const double l : lengths) lost += l;
    out.lost_fraction = lost * 1e-6 / out.seconds;
    if (!lengths.empty()) out.length_us = percentiles(lengths);
    return out;
}

}  // namespace sulcus::cli
