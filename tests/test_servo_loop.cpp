// The servo loop on its own thread for about a second: a simulated hand presses a 5 mm cube
// onto a slab (scene built in code) through the real renderer step and safety layer, while a
// reader thread takes published snapshots and a recorder writes the session.
#include "scene_helpers.h"

#include "sulcus/content/primitives.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/servo_loop.h"
#include "sulcus/haptics/sim_device.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace sulcus {
namespace {

using test::mm;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The hand's target: rest 0.5 mm above the slab for 0.1 s, then 8 mm down over 0.3 s (7.5 mm
// past the surface: about 2 N through the grip, above the 1 N force limit), then hold.
std::vector<TrajectorySample> press_script() {
    std::vector<TrajectorySample> out;
    for (int i = 0; i <= 600; ++i) {
        const double t = i * 0.002;
        const double u = std::clamp((t - 0.1) / 0.3, 0.0, 1.0);
        const double s = u * u * (3.0 - 2.0 * u);
        out.push_back({t, Pose{Vec3(0.0, -8.0 * mm * s, 0.0), Quat(1, 0, 0, 0)}});
    }
    return out;
}

struct ReaderResult {
    uint64_t reads = 0;
    uint64_t torn = 0;           // tick != tick_check
    uint64_t backwards = 0;      // a tick older than one seen before
    uint64_t distinct = 0;       // distinct ticks seen
    uint64_t bad_force = 0;      // non-finite or above the limit
};

TEST(ServoLoop, RunsAtRatePublishesWholeSnapshotsAndRecordsWhatItSends) {
    // Tool: 5 mm cube at the origin; slab top 0.5 mm below it.
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -5.0 * mm, 0.0));
    const std::unique_ptr<Model> model = test::model_of(tool, {test::object("slab", slab)});
    ASSERT_TRUE(model);

    ServoConfig config;
    config.rate_hz = 1000.0;
    config.duration_s = 1.0;
    config.safety.limits.max_force_N = 1.0;
    config.safety.limits.max_torque_Nm = 0.05;
    config.trace_ticks = 4000;

    HandParameters hand_parameters;
    hand_parameters.dt_s = 1.0 / config.rate_hz;
    SimulatedHand hand(press_script(), hand_parameters);

    const std::string path =
        (std::filesystem::temp_directory_path() / ("test_servo_loop_" + std::to_string(::getpid()) + ".rec")).string();
    RecordingWriter recorder;
    RecordingMetadata meta;
    meta.case_path = "in-code slab";
    meta.device = "sim";
    meta.rate_hz = config.rate_hz;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, meta, ropts), "");
    ASSERT_EQ(recorder.start_writer_thread(0.02), "");

    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");

    ReaderResult rr;
    std::thread reader([&] {
        uint64_t last = 0;
        bool any = false;
        ServoSnapshot s;
        while (loop.running()) {
            if (!loop.latest(s)) continue;
            ++rr.reads;
            if (s.tick != s.tick_check) ++rr.torn;
            if (any && s.tick < last) ++rr.backwards;
            if (!any || s.tick != last) ++rr.distinct;
            if (!finite(s.force_N) || glm::length(s.force_N) > config.safety.limits.max_force_N * (1 + 1e-12))
                ++rr.bad_force;
            any = true;
            last = s.tick;
            std::this_thread::yield();
        }
    });
    loop.wait();
    reader.join();
    ASSERT_EQ(recorder.close(), "");

    const ServoStats st = loop.stats();
    std::printf("ticks %llu  rate %.1f Hz  jitter p50/p99/max %.1f/%.1f/%.1f us  misses %llu  step p50/p99/max "
                "%.1f/%.1f/%.1f us  max force %.3f N  %s\n",
                static_cast<unsigned long long>(st.ticks), st.achieved_rate_hz, st.jitter_us.p50, st.jitter_us.p99,
                st.jitter_us.max, static_cast<unsigned long long>(st.deadline_misses), st.step_us.p50,
                st.step_us.p99, st.step_us.max, st.max_force_sent_N,
                st.realtime ? "SCHED_FIFO" : st.realtime_message.c_str());

    // Rate: the tick count within 20 % of rate x seconds.
    const double expected = config.rate_hz * config.duration_s;
    EXPECT_GT(static_cast<double>(st.ticks), 0.8 * expected);
    EXPECT_LT(static_cast<double>(st.ticks), 1.2 * expected);

    // Published snapshots: never torn, never going back, and the reader saw the loop move.
    EXPECT_GT(rr.reads, 0u);
    EXPECT_GT(rr.distinct, 10u);
    EXPECT_EQ(rr.torn, 0u);
    EXPECT_EQ(rr.backwards, 0u);
    EXPECT_EQ(rr.bad_force, 0u);
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_EQ(last.tick + 1, st.ticks);

    // Forces sent: finite and within the limits, on every tick; and the press did reach the limit
    // region (the check is not vacuous).
    ASSERT_EQ(loop.trace_size(), st.ticks);
    double max_force = 0.0;
    for (std::size_t i = 0; i < loop.trace_size(); ++i) {
        const TickSample& t = loop.trace()[i];
        ASSERT_TRUE(finite(t.force_N) && finite(t.torque_Nm)) << "tick " << i;
        ASSERT_LE(glm::length(t.force_N), config.safety.limits.max_force_N * (1 + 1e-12)) << "tick " << i;
        ASSERT_LE(glm::length(t.torque_Nm), config.safety.limits.max_torque_Nm * (1 + 1e-12)) << "tick " << i;
        max_force = std::max(max_force, glm::length(t.force_N));
    }
    EXPECT_FALSE(st.non_finite_sent);
    EXPECT_GT(max_force, 0.5);
    EXPECT_GT(st.status_counts[static_cast<int>(StepStatus::Contact)], 0u);

    // The recording reads back with every tick and the same forces, bit for bit.
    EXPECT_EQ(st.record_drops, 0u);
    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    EXPECT_FALSE(rec.truncation.truncated) << rec.truncation.reason;
    ASSERT_EQ(rec.ticks.size(), st.ticks);
    for (std::size_t i = 0; i < rec.ticks.size(); ++i) {
        const TickSample& a = rec.ticks[i];
        const TickSample& b = loop.trace()[i];
        ASSERT_EQ(a.tick, b.tick);
        ASSERT_EQ(std::memcmp(&a.force_N, &b.force_N, sizeof(Vec3)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.torque_Nm, &b.torque_Nm, sizeof(Vec3)), 0) << "tick " << i;
        ASSERT_EQ(a.status, b.status) << "tick " << i;
    }
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace sulcus
