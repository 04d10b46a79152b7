// The bundled paper scenes (content/assets/scenes/paper) run headless: every invariant of the
// renderer asserted on every scene, plus what each experiment is meant to show.
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

// Force continuity: with the haptic tool moving dp (m) in a tick, the force changes by at most
// K_t (|dp| + force_step_margin_m) (the renderer's force-continuity box). The only exception is
// a tick where the tool falls onto the next contact or out of contact (a real drop off an edge,
// reported as `released`); those must be rare.
TEST(PaperScenes, ForceChangePerTickIsBoundedByTheHapticMotion) {
    const RendererSettings defaults;
    for (const auto& [name, run] : runs()) {
        const SceneLoad load = load_scene(kSceneDir + "/" + name + ".json");
        ASSERT_TRUE(load.ok());
        const double k = load.scene.haptic.stiffness_N_per_m;
        long drops = 0;
        for (size_t i = 1; i < run.ticks.size(); ++i) {
            const TickRecord& a = run.ticks[i - 1];
            const TickRecord& b = run.ticks[i];
            const double dp = glm::length(b.haptic.position - a.haptic.position);
            const double bound = k * (dp + defaults.force_step_margin_m) * (1.0 + 1e-9);
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
