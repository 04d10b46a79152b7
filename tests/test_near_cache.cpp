// The step's near cache (RendererSettings::near_cache) changes what the step measures, not what it
// finds: with and without it, the bench scenes' probing gives the same graphic poses, forces and
// statuses bit for bit. And what it carries from tick to tick stays within one session: sessions
// interleaved on one thread, or a session run again after another, repeat their lone runs exactly.
#include "cli/bench_scenes.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

using namespace sulcus;

namespace {

struct Tick {
    Pose graphic;
    Vec3 force, torque;
    StepStatus status;
    int near;
};

bool same_bits(const Tick& a, const Tick& b) {
    return std::memcmp(&a.graphic.position, &b.graphic.position, sizeof(Vec3)) == 0 &&
           std::memcmp(&a.graphic.orientation, &b.graphic.orientation, sizeof(Quat)) == 0 &&
           std::memcmp(&a.force, &b.force, sizeof(Vec3)) == 0 && std::memcmp(&a.torque, &b.torque, sizeof(Vec3)) == 0 &&
           a.status == b.status && a.near == b.near;
}

cli::BenchScene load(const std::string& name) {
    cli::BenchScenes s =
        cli::load_bench_scenes({name}, std::string(SULCUS_SOURCE_DIR) + "/content/assets",
                                 std::string(SULCUS_BINARY_DIR) + "/cases");
    EXPECT_EQ(s.error, "");
    EXPECT_EQ(s.scenes.size(), 1u);
    return s.scenes.empty() ? cli::BenchScene{} : std::move(s.scenes.front());
}

std::unique_ptr<Model> model_for(const cli::BenchScene& b, bool near_cache) {
    RendererSettings settings;
    settings.haptic = b.scene.haptic;
    settings.near_cache = near_cache;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    EXPECT_TRUE(mb.model) << mb.error;
    return std::move(mb.model);
}

Tick tick_of(const StepResult& r) {
    return Tick{r.graphic, r.force_N, r.torque_Nm, r.status, r.stats.triangles_near};
}

std::vector<Tick> run(const Model& model, const std::vector<Pose>& poses, size_t count) {
    std::vector<Tick> out;
    State state = make_state(poses.front());
    for (size_t i = 0; i < count && i < poses.size(); ++i) out.push_back(tick_of(step(model, state, poses[i])));
    return out;
}

// Where two runs first differ (-1: nowhere).
long first_difference(const std::vector<Tick>& a, const std::vector<Tick>& b) {
    if (a.size() != b.size()) return 0;
    for (size_t i = 0; i < a.size(); ++i)
        if (!same_bits(a[i], b[i])) return long(i);
    return -1;
}

int contact_ticks(const std::vector<Tick>& t) {
    int n = 0;
    for (const Tick& k : t) n += k.status == StepStatus::Contact;
    return n;
}

void expect_cache_changes_nothing(const std::string& name, size_t count) {
    const cli::BenchScene b = load(name);
    ASSERT_FALSE(b.ticks.empty()) << name;
    const auto with = model_for(b, true), without = model_for(b, false);
    const std::vector<Tick> a = run(*with, b.ticks, count), c = run(*without, b.ticks, count);
    EXPECT_GT(contact_ticks(a), 100) << name;  // the probe is in contact for much of the run
    EXPECT_EQ(first_difference(a, c), -1) << name;
}

}  // namespace

TEST(NearCache, DenseWedgeProbingIsTheSameWithAndWithoutIt) {
    expect_cache_changes_nothing("dense_wedge_250k", 100000);
}

TEST(NearCache, QuadrantTwoRegionSessionIsTheSameWithAndWithoutIt) {
    expect_cache_changes_nothing("quadrant_two_regions", 100000);
}

TEST(NearCache, PaperScenesAreTheSameWithAndWithoutIt) {
    for (const std::string& name : cli::bench_scene_names()) {
        if (name.rfind("paper/", 0) != 0) continue;
        const cli::BenchScene b = load(name);
        ASSERT_FALSE(b.ticks.empty()) << name;
        const auto with = model_for(b, true), without = model_for(b, false);
        EXPECT_EQ(first_difference(run(*with, b.ticks, 100000), run(*without, b.ticks, 100000)), -1) << name;
    }
}

// Two sessions stepped in turn on one thread (the second a stroke behind the first), and the
// first again after both: each repeats its lone run bit for bit.
TEST(NearCache, InterleavedSessionsRepeatTheirLoneRuns) {
    const cli::BenchScene b = load("dense_wedge_250k");
    ASSERT_GT(b.ticks.size(), 2500u);
    const auto model = model_for(b, true);
    const size_t n = 2000, lag = 400;
    const std::vector<Pose> first(b.ticks.begin(), b.ticks.begin() + n);
    const std::vector<Pose> second(b.ticks.begin() + lag, b.ticks.begin() + lag + n);
    const std::vector<Tick> alone_first = run(*model, first, n), alone_second = run(*model, second, n);
    ASSERT_GT(contact_ticks(alone_first), 100);
    ASSERT_GT(contact_ticks(alone_second), 100);
    State s1 = make_state(first.front()), s2 = make_state(second.front());
    std::vector<Tick> mixed_first, mixed_second;
    for (size_t i = 0; i < n; ++i) {
        mixed_first.push_back(tick_of(step(*model, s1, first[i])));
        mixed_second.push_back(tick_of(step(*model, s2, second[i])));
    }
    EXPECT_EQ(first_difference(mixed_first, alone_first), -1);
    EXPECT_EQ(first_difference(mixed_second, alone_second), -1);
    EXPECT_EQ(first_difference(run(*model, first, n), alone_first), -1);
    // A copy of a state stepped on its own, then the original going on: the original's ticks do
    // not depend on the copy's.
    State a = make_state(first.front());
    std::vector<Tick> with_copy;
    for (size_t i = 0; i < n; ++i) {
        if (i == n / 2) {
            State copy = a;
            for (size_t j = i; j < i + 50; ++j) step(*model, copy, second[j]);
        }
        with_copy.push_back(tick_of(step(*model, a, first[i])));
    }
    EXPECT_EQ(first_difference(with_copy, alone_first), -1);
}
