// One timed pass of the renderer over a bench scene's ticks, shared by `bench` and `wpd`: per
// tick the step time (only the step is inside the clock), its stages and counters, heap
// allocations, the pose and force; the exact checks run outside the clock on chosen ticks.
#pragma once

#include "cli/bench_scenes.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/runner.h"

#include <memory>
#include <string>
#include <vector>

namespace sulcus::cli {

struct BenchTick {
    double step_us = 0.0;        // in the first run
    double least_step_us = 0.0;  // the least over the runs (BenchRunOptions::runs)
    StepStats stats;  // the step's own figures: stage times, counters
    StepStatus status = StepStatus::Free;
    Pose graphic;
    Vec3 force_N{0.0};
    Vec3 torque_Nm{0.0};
    long allocations = 0;
    bool contact = false;
};

struct BenchRunOptions {
    // Exact penetration and gap checks on every n-th tick with a force (0: none). Not timed.
    int check_every = 10;
    long max_ticks = 0;  // 0: every tick of the scene
    // Runs of the whole scene on the same model, each from a fresh state. Every run must give
    // every tick the same status, pose and force to the bit; per tick the least step time is kept.
    int runs = 1;
};

struct BenchRun {
    std::string error;
    std::unique_ptr<Model> model;
    std::vector<BenchTick> ticks;
    long checked_ticks = 0;
    double max_penetration_m = 0.0;   // into rigid objects, over the checked ticks
    double max_gap_in_contact_m = 0.0;  // tool to the objects while a force is rendered
};

// `settings.haptic` is replaced by the scene's.
BenchRun run_bench(const BenchScene& scene, RendererSettings settings, const BenchRunOptions& options);

// What the machine takes from a running thread: a spin on the steady clock for `seconds`, every
// gap between two readings of at least `threshold_us` counted as an interruption. A step timed
// across one is that much longer, whatever the step did.
struct Interruptions {
    double seconds = 0.0;     // spun
    long count = 0;
    double per_second = 0.0;
    double lost_fraction = 0.0;  // of the time spun
    Percentiles length_us;       // of the interruptions (zeros when none)
};
Interruptions probe_interruptions(double seconds, double threshold_us = 5.0);

}  // namespace sulcus::cli
