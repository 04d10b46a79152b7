// The bundled paper scenes (content/assets/scenes/paper) run headless: every invariant of the
// renderer asserted on every scene, plus what each experiment is meant to show.
#include "so3.h"
#include "sulcus/engine/runner.h"
#include "sulcus/engine/scene_file.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <map>

using namespace sulcus;

namespace {

const std::string kSceneDir = std::string(SULCUS_SOURCE_DIR) + "/content/assets/scenes/paper";

std::vector<std::string> scene_files() {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(kSceneDir))
        if (e.path().extension() == ".json") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// Runs each scene once and keeps the result for all tests.
const std::map<std::string, RunResult>& runs() {
    static const std::map<std::string, RunResult> all = [] {
        std::map<std::string, RunResult> m;
        for (const std::string& f : scene_files()) {
            const SceneLoad load = load_scene(f);
            EXPECT_TRUE(load.ok()) << f << ": " << (load.errors.empty() ? "" : load.errors[0]);
            if (!load.ok()) continue;
            m[load.scene.name] = run_scene(load.scene, RendererSettings{});
        }
        return m;
    }();
    return all;
}

const RunResult& run_of(const std::string& name) {
    const auto& r = runs();
    const auto it = r.find(name);
    if (it == r.end()) {
        ADD_FAILURE() << "scene " << name << " missing";
        static const RunResult empty;
        return empty;
    }
    return it->second;
}

}  // namespace

TEST(PaperScenes, AtLeastSixSceneFiles) { EXPECT_GE(scene_files().size(), 6u); }

TEST(PaperScenes, NoPenetrationNoNanNoGap) {
    for (const auto& [name, run] : runs()) {
        ASSERT_TRUE(run.error.empty()) << name << ": " << run.error;
        EXPECT_GT(run.summary.steps, 100) << name;
        EXPECT_LE(run.summary.max_penetration_m, 1e-6) << name;
        EXPECT_EQ(run.summary.nan_steps, 0) << name;
        EXPECT_LE(run.summary.max_gap_in_contact_m, 1e-6) << name;
        EXPECT_EQ(run.summary.status_counts[static_cast<int>(StepStatus::Held)], 0) << name;
    }
}

// Force continuity: with the haptic tool moving dp (m) and turning dtheta (rad) in a tick, the
// force changes by at most K_t (|dp| + radius |dtheta| + force_step_margin_m) (the renderer's
// force-continuity box; radius * dtheta is how far the turn moves the tool's points). The only exception is
// a tick where the tool falls onto the next contact or out of contact (a real drop off an edge,
// reported as `released`); those must be rare.
TEST(PaperScenes, ForceChangePerTickIsBoundedByTheHapticMotion) {
    const RendererSettings defaults;
    for (const auto& [name, run] : runs()) {
        const SceneLoad load = load_scene(kSceneDir + "/" + name + ".json");
        ASSERT_TRUE(load.ok());
        const double k = load.scene.haptic.stiffness_N_per_m;
        double radius = 0.0;  // the renderer's tool radius: farthest vertex from the tool origin
        for (const Vec3& v : load.scene.tool.mesh.vertices) radius = std::max(radius, glm::length(v));
        long drops = 0;
        for (size_t i = 1; i < run.ticks.size(); ++i) {
            const TickRecord& a = run.ticks[i - 1];
            const TickRecord& b = run.ticks[i];
            const double dp = glm::length(b.haptic.position - a.haptic.position);
            const double dt = glm::length(quat_log(b.haptic.orientation * glm::conjugate(a.haptic.orientation)));
            const double bound = k * (dp + radius * dt + defaults.force_step_margin_m) * (1.0 + 1e-9);
            const double df = glm::length(b.force_N - a.force_N);
            if (b.stats.released && df > bound) {
                ++drops;
                continue;
            }
            EXPECT_LE(df, bound) << name << " tick " << i << " t=" << b.t;
        }
        // A drop is a single tick at a contact switch, not a habit.
        EXPECT_LE(drops * 1000, std::max<long>(1000, static_cast<long>(run.ticks.size()))) << name;
    }
}

TEST(PaperScenes, GraphicFollowsTheHapticToolInFreeSpace) {
    for (const auto& [name, run] : runs()) {
        for (const TickRecord& r : run.ticks) {
            if (r.status != StepStatus::Free) continue;
            EXPECT_EQ(std::memcmp(&r.graphic.position, &r.haptic.position, sizeof(Vec3)), 0) << name << " " << r.t;
            EXPECT_EQ(glm::length(r.force_N), 0.0) << name;
        }
    }
}

TEST(PaperScenes, ReplayIsBitIdentical) {
    for (const std::string& f : scene_files()) {
        const SceneLoad load = load_scene(f);
        ASSERT_TRUE(load.ok());
        const RunResult again = run_scene(load.scene, RendererSettings{});
        const RunResult& first = run_of(load.scene.name);
        ASSERT_EQ(again.ticks.size(), first.ticks.size());
        for (size_t i = 0; i < again.ticks.size(); ++i) {
            const TickRecord &a = first.ticks[i], &b = again.ticks[i];
            ASSERT_EQ(std::memcmp(&a.graphic, &b.graphic, sizeof(Pose)), 0) << f << " tick " << i;
            ASSERT_EQ(std::memcmp(&a.force_N, &b.force_N, sizeof(Vec3)), 0) << f << " tick " << i;
            ASSERT_EQ(std::memcmp(&a.torque_Nm, &b.torque_Nm, sizeof(Vec3)), 0) << f << " tick " << i;
            ASSERT_EQ(a.status, b.status);
            ASSERT_EQ(a.contacts, b.contacts);
            ASSERT_EQ(a.penetration_m, b.penetration_m);
        }
    }
}

// Fig. 12-13: the line-shaped tool meets V-F, E-E and two contact regions at once.
TEST(PaperScenes, LineToolMeetsVertexFaceEdgeEdgeAndTwoRegions) {
    const RunSummary& s = run_of("line_tool").summary;
    EXPECT_GT(s.steps_with_vf, 100);
    EXPECT_GT(s.steps_with_ee, 100);
    EXPECT_GT(s.steps_with_two_regions, 50);
    EXPECT_GE(s.max_regions, 2);
}

// Fig. 5a: the haptic tool goes through a 0.05 mm plate at 1 and 5 m/s (turning, in the fast
// one); the graphic tool stays on top of it on every tick.
TEST(PaperScenes, ThinPlateIsNeverPoppedThrough) {
    const double top = 0.025e-3 + 2.5e-3;  // plate half thickness + cube half size
    for (const char* name : {"thin_plate", "thin_plate_fast"}) {
        const RunResult& run = run_of(name);
        double lowest_haptic = 1.0;
        for (const TickRecord& r : run.ticks) {
            lowest_haptic = std::min(lowest_haptic, r.haptic.position.y);
            EXPECT_GE(r.graphic.position.y, top - 1e-7) << name << " t=" << r.t;
        }
        EXPECT_LT(lowest_haptic, -5e-3) << name;  // the haptic tool did go through
    }
}

// Fig. 5b: sunk past a sharp ridge to where the nearest free pose is on the other flank, the
// graphic tool keeps to the flank it came from (the local solution), with a force up-left.
TEST(PaperScenes, SharpCornerKeepsTheLocalSolution) {
    const RunResult& run = run_of("sharp_corner");
    bool went_past = false;
    for (const TickRecord& r : run.ticks) {
        if (r.haptic.position.x > 2e-3) went_past = true;
        EXPECT_LE(r.graphic.position.x, 0.0) << r.t;  // the cube's centre never crosses the apex line
    }
    EXPECT_TRUE(went_past);
    const TickRecord& deepest = *std::min_element(run.ticks.begin(), run.ticks.end(),
                                                  [](const TickRecord& a, const TickRecord& b) {
                                                      return a.haptic.position.y < b.haptic.position.y;
                                                  });
    EXPECT_LT(deepest.force_N.x, 0.0);
    EXPECT_GT(deepest.force_N.y, 0.0);
}

// Fig. 10-11: in the 1 mm cavity the cube turns freely up to a(cos t + sin t) = h, then the
// walls hold it and a torque resists; at zero clearance it cannot turn at all.
TEST(PaperScenes, CavityLimitsTheTurnAndRendersTorque) {
    const double limit = std::asin(1.1 / std::sqrt(2.0)) - std::atan(1.0);  // 5 mm (cos t + sin t) = 5.5 mm
    const RunResult& wide = run_of("cavity_1mm");
    double most = 0.0;
    for (const TickRecord& r : wide.ticks) most = std::max(most, glm::angle(r.graphic.orientation));
    EXPECT_LE(most, limit + 1e-7);
    EXPECT_GE(most, limit - 1e-3);
    EXPECT_GT(wide.summary.max_torque_Nm, 0.005);
    const RunResult& tight = run_of("cavity_0mm");
    for (const TickRecord& r : tight.ticks) EXPECT_LE(glm::angle(r.graphic.orientation), 1e-6) << r.t;
    EXPECT_GT(tight.summary.max_torque_Nm, 0.005);
}

TEST(PaperScenes, FreeMotionNeverTouches) {
    const RunResult& run = run_of("free_motion");
    EXPECT_EQ(run.summary.contact_steps, 0);
    EXPECT_EQ(run.summary.max_force_N, 0.0);
    EXPECT_EQ(run.summary.status_counts[static_cast<int>(StepStatus::Free)], run.summary.steps);
}
