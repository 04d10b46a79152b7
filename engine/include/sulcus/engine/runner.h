// The headless scene runner: one renderer step per servo tick along a scene's trajectory, with
// the exact checks of every tick, a summary and the per-tick table (DESIGN.md, sulcus-cli run).
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"

#include <map>
#include <string>
#include <vector>

namespace sulcus {

struct TickRecord {
    double t = 0.0;
    Pose haptic, graphic;
    Vec3 force_N{0.0}, torque_Nm{0.0};
    double step_us = 0.0;
    double penetration_m = 0.0;
    double gap_m = 0.0;  // distance to the objects on ticks with a force, else 0
    double soft_depth_m = 0.0;  // how far the tool is inside compliant objects (exact check)
    int contacts = 0;
    StepStatus status = StepStatus::Free;
    StepStats stats;
};

struct Percentiles {
    double median = 0, p99 = 0, p999 = 0, max = 0;
};
Percentiles percentiles(std::vector<double> values);

struct RunSummary {
    std::string scene;
    long steps = 0;
    long contact_steps = 0;
    double max_penetration_m = 0.0;  // into rigid objects
    double max_soft_depth_m = 0.0;   // into compliant objects (by design: force / stiffness)
    double max_friction_limit_N = 0.0;
    long sliding_steps = 0;          // ticks where friction let the tool slide
    double max_gap_in_contact_m = 0.0;
    double max_force_N = 0.0;
    double max_torque_Nm = 0.0;
    double max_force_step_N = 0.0;
    double max_torque_step_Nm = 0.0;
    Percentiles step_time_us;
    Percentiles stage_us[kStageCount];  // by stage, as kStageNames
    long nan_steps = 0;
    long status_counts[kStepStatusCount] = {};
    long max_regions = 0;
    long steps_with_vf = 0, steps_with_fv = 0, steps_with_ee = 0, steps_with_two_regions = 0;
    long released_steps = 0;  // ticks where the force-continuity limit was lifted
    long qp_solves = 0;
    long max_relinearizations = 0;
};

struct RunResult {
    RunSummary summary;
    std::vector<TickRecord> ticks;
    std::string error;  // one line when the run could not start
};

// Runs the scene at its rate from the trajectory's first time to its last.
RunResult run_scene(const SceneFile& scene, const RendererSettings& settings);

// Writes DIR/summary.json and DIR/steps.csv (each whole or not at all).
bool write_run(const RunResult& run, const std::string& dir, std::string* error);

// The one-line summary printed by `sulcus-cli run`.
std::string summary_line(const RunSummary& s);

// Writes `text` to `path` through a temporary file and a rename.
bool write_file_atomic(const std::string& path, const std::string& text, std::string* error);

}  // namespace sulcus
