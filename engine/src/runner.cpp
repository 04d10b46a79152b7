// The headless scene runner (sulcus-cli run).
#include "sulcus/engine/runner.h"

#include "sulcus/engine/exact_check.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace sulcus {

Percentiles percentiles(std::vector<double> v) {
    Percentiles p;
    if (v.empty()) return p;
    std::sort(v.begin(), v.end());
    auto at = [&](double q) {
        const size_t i = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) ;
        return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
    };
    p.median = at(0.5);
    p.p99 = at(0.99);
    p.p999 = at(0.999);
    p.max = v.back();
    return p;
}

namespace {

bool finite3(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Largest distance checked for the gap figure, in metres.
constexpr double kGapLimit = 1e-3;

}  // namespace

RunResult run_scene(const SceneFile& scene, const RendererSettings& settings_in) {
    RunResult run;
    run.summary.scene = scene.name;
    RendererSettings settings = settings_in;
    settings.haptic = scene.haptic;
    if (scene.trajectory.size() < 2) {
        run.error = scene.trajectory_path + ": needs at least two rows";
        return run;
    }
    ModelBuild mb = build_model(scene.tool.mesh, scene.objects, settings, scene.materials);
    if (!mb.model) {
        run.error = scene.path + ": " + mb.error;
        return run;
    }
    const Model& model = *mb.model;
    // The tool must never enter a rigid object; a compliant one it enters by design, and how far
    // is measured apart.
    std::vector<PlacedMesh> placed, rigid, compliant;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& o = scene.objects[i];
        placed.push_back(PlacedMesh{&o.mesh, o.pose});
        (model.objects[i].compliant ? compliant : rigid).push_back(placed.back());
    }
    const std::vector<TriMesh> pieces = connected_components(scene.tool.mesh);

    const double t0 = scene.trajectory.front().t;
    const double t1 = scene.trajectory.back().t;
    const long n = static_cast<long>(std::floor((t1 - t0) * scene.rate_hz + 1e-9)) + 1;
    size_t cursor = 0;
    const Pose start = sample_trajectory(scene.trajectory, t0, cursor);
    {
        const ExactCheck c = exact_check(pieces, start, placed, 0.0);
        if (c.penetration_m > settings.constraint_tol_m) {
            run.error = scene.trajectory_path + ": line 2: the first pose penetrates an object by " +
                        std::to_string(c.penetration_m) + " m";
            return run;
        }
    }
    State state = make_state(start);
    {
        // Warm-up outside the statistics: the first step on a thread makes its workspace.
        State scratch = state;
        step(model, scratch, start);
    }
    run.ticks.reserve(static_cast<size_t>(n));
    std::vector<double> times, stage[kStageCount];
    times.reserve(static_cast<size_t>(n));
    RunSummary& s = run.summary;
    Vec3 prev_f(0.0), prev_tq(0.0);
    for (long i = 0; i < n; ++i) {
        TickRecord r;
        r.t = t0 + static_cast<double>(i) / scene.rate_hz;
        r.haptic = sample_trajectory(scene.trajectory, r.t, cursor);
        const auto a = std::chrono::steady_clock::now();
        const StepResult out = step(model, state, r.haptic);
        const auto b = std::chrono::steady_clock::now();
        r.step_us = std::chrono::duration<double, std::micro>(b - a).count();
        r.graphic = out.graphic;
        r.force_N = out.force_N;
        r.torque_Nm = out.torque_Nm;
        r.status = out.status;
        r.contacts = out.contacts;
        r.stats = out.stats;
        const bool has_force = glm::length(out.force_N) > 0.0 || glm::length(out.torque_Nm) > 0.0;
        const ExactCheck c = exact_check(pieces, out.graphic, rigid, has_force ? kGapLimit : 0.0);
        r.penetration_m = c.penetration_m;
        r.gap_m = has_force ? c.distance_m : 0.0;
        if (!compliant.empty()) {
            const ExactCheck soft = exact_check(pieces, out.graphic, compliant, has_force ? kGapLimit : 0.0);
            r.soft_depth_m = soft.penetration_m;
            if (has_force) r.gap_m = std::min(r.gap_m, soft.distance_m);
            s.max_soft_depth_m = std::max(s.max_soft_depth_m, r.soft_depth_m);
        }
        s.max_friction_limit_N = std::max(s.max_friction_limit_N, out.stats.friction_static_limit_N);
        if (out.stats.sliding) ++s.sliding_steps;

        ++s.steps;
        if (out.contacts > 0) ++s.contact_steps;
        if (!finite3(out.force_N) || !finite3(out.torque_Nm) || !finite3(out.graphic.position)) ++s.nan_steps;
        s.max_penetration_m = std::max(s.max_penetration_m, r.penetration_m);
        if (has_force) s.max_gap_in_contact_m = std::max(s.max_gap_in_contact_m, r.gap_m);
        s.max_force_N = std::max(s.max_force_N, glm::length(out.force_N));
        s.max_torque_Nm = std::max(s.max_torque_Nm, glm::length(out.torque_Nm));
        if (i > 0) {
            s.max_force_step_N = std::max(s.max_force_step_N, glm::length(out.force_N - prev_f));
            s.max_torque_step_Nm = std::max(s.max_torque_step_Nm, glm::length(out.torque_Nm - prev_tq));
        }
        prev_f = out.force_N;
        prev_tq = out.torque_Nm;
        ++s.status_counts[static_cast<int>(out.status)];
        s.max_regions = std::max<long>(s.max_regions, out.stats.regions);
        if (out.stats.active_vf > 0) ++s.steps_with_vf;
        if (out.stats.active_fv > 0) ++s.steps_with_fv;
        if (out.stats.active_ee > 0) ++s.steps_with_ee;
        if (out.stats.regions >= 2) ++s.steps_with_two_regions;
        if (out.stats.released) ++s.released_steps;
        s.qp_solves += out.stats.qp_solves;
        s.max_relinearizations = std::max<long>(s.max_relinearizations, out.stats.relinearizations);
        times.push_back(r.step_us);
        for (int k = 0; k < kStageCount; ++k) stage[k].push_back(stage_us(out.stats.times, k));
        run.ticks.push_back(r);
    }
    s.step_time_us = percentiles(times);
    for (int k = 0; k < kStageCount; ++k) s.stage_us[k] = percentiles(stage[k]);
    return run;
}

bool write_file_atomic(const std::string& path, const std::string& text, std::string* error) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) {
            if (error) *error = path + ": cannot write: " + std::strerror(errno);
            return false;
        }
        f.write(text.data(), static_cast<std::streamsize>(text.size()));
        f.flush();
        if (!f) {
            if (error) *error = path + ": write failed";
            std::remove(tmp.c_str());
            return false;
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        if (error) *error = path + ": cannot rename into place: " + ec.message();
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

namespace {

nlohmann::json to_json(const Percentiles& p) {
    return nlohmann::json{{"median", p.median}, {"p99", p.p99}, {"p999", p.p999}, {"max", p.max}};
}

void append(std::string& out, double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    out += buf;
}

}  // namespace

bool write_run(const RunResult& run, const std::string& dir, std::string* error) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        if (error) *error = dir + ": cannot create the output folder: " + ec.message();
        return false;
    }
    const RunSummary& s = run.summary;
    nlohmann::json j;
    j["format"] = "sulcus.summary/1";
    j["scene"] = s.scene;
    j["steps"] = s.steps;
    j["contact_steps"] = s.contact_steps;
    j["max_penetration_m"] = s.max_penetration_m;
    j["max_soft_depth_m"] = s.max_soft_depth_m;
    j["sliding_steps"] = s.sliding_steps;
    j["max_gap_in_contact_m"] = s.max_gap_in_contact_m;
    j["max_force_N"] = s.max_force_N;
    j["max_torque_Nm"] = s.max_torque_Nm;
    j["max_force_step_N"] = s.max_force_step_N;
    j["max_torque_step_Nm"] = s.max_torque_step_Nm;
    j["step_time_us"] = to_json(s.step_time_us);
    for (int k = 0; k < kStageCount; ++k) j["stage_time_us"][kStageNames[k]] = to_json(s.stage_us[k]);
    j["nan_steps"] = s.nan_steps;
    for (int k = 0; k < kStepStatusCount; ++k) j["status_counts"][to_string(static_cast<StepStatus>(k))] = s.status_counts[k];
    j["contact_types"] = {{"steps_with_vertex_face", s.steps_with_vf},
                          {"steps_with_face_vertex", s.steps_with_fv},
                          {"steps_with_edge_edge", s.steps_with_ee},
                          {"steps_with_two_or_more_regions", s.steps_with_two_regions},
                          {"max_regions", s.max_regions}};
    j["released_steps"] = s.released_steps;
    j["qp_solves"] = s.qp_solves;
    j["max_relinearizations"] = s.max_relinearizations;
    const std::string base = (std::filesystem::path(dir) / "").string();
    if (!write_file_atomic(base + "summary.json", j.dump(2) + "\n", error)) return false;

    std::string csv = "t,hx,hy,hz,hqw,hqx,hqy,hqz,gx,gy,gz,gqw,gqx,gqy,gqz,fx,fy,fz,tx,ty,tz,step_us,penetration_m,contacts,status\n";
    csv.reserve(run.ticks.size() * 400);
    for (const TickRecord& r : run.ticks) {
        const double vals[] = {r.t,
                               r.haptic.position.x, r.haptic.position.y, r.haptic.position.z,
                               r.haptic.orientation.w, r.haptic.orientation.x, r.haptic.orientation.y, r.haptic.orientation.z,
                               r.graphic.position.x, r.graphic.position.y, r.graphic.position.z,
                               r.graphic.orientation.w, r.graphic.orientation.x, r.graphic.orientation.y, r.graphic.orientation.z,
                               r.force_N.x, r.force_N.y, r.force_N.z, r.torque_Nm.x, r.torque_Nm.y, r.torque_Nm.z,
                               r.step_us, r.penetration_m};
        for (double v : vals) {
            append(csv, v);
            csv += ',';
        }
        csv += std::to_string(r.contacts);
        csv += ',';
        csv += to_string(r.status);
        csv += '\n';
    }
    return write_file_atomic(base + "steps.csv", csv, error);
}

std::string summary_line(const RunSummary& s) {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "%s: steps=%ld contact_steps=%ld max_penetration_m=%.3g max_gap_in_contact_m=%.3g "
                  "max_force_N=%.4g max_force_step_N=%.4g nan_steps=%ld step_us median=%.1f p99=%.1f max=%.1f",
                  s.scene.c_str(), s.steps, s.contact_steps, s.max_penetration_m, s.max_gap_in_contact_m,
                  s.max_force_N, s.max_force_step_N, s.nan_steps, s.step_time_us.median, s.step_time_us.p99,
                  s.step_time_us.max);
    return buf;
}

}  // namespace sulcus
