// The servo loop on its own thread for about a second: a simulated hand presses a 5 mm cube
// onto a slab (scene built in code) through the real renderer step and safety layer, while a
// reader thread takes published snapshots and a recorder writes the session.
#include "allocation_counter.h"
#include "scene_helpers.h"

#include "sulcus/content/primitives.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/replay_device.h"
#include "sulcus/haptics/servo_loop.h"
#include "sulcus/haptics/spsc_queue.h"
#include "sulcus/haptics/sim_device.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
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
    // Late ticks on a loaded machine are not what this test is about: three in a row are a stall,
    // and a stall holds the force at zero until 0.2 s pass without a single late tick, which a
    // loaded machine with a late tick every few tens of milliseconds never gives, so the press
    // would send nothing (the stall has tests of its own).
    config.safety.stall_deadline_misses = 1 << 20;
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

TEST(SpscQueue, KeepsOrderRefusesWhenFullAndLosesNothingAcrossThreads) {
    SpscQueue<uint64_t> q(5);
    EXPECT_EQ(q.capacity(), 8u);
    for (uint64_t i = 0; i < 8; ++i) EXPECT_TRUE(q.push(i));
    EXPECT_FALSE(q.push(99));  // full: refused, nothing overwritten
    uint64_t v = 0;
    for (uint64_t i = 0; i < 8; ++i) {
        ASSERT_TRUE(q.pop(v));
        EXPECT_EQ(v, i);
    }
    EXPECT_FALSE(q.pop(v));

    // One producer, one consumer, a million values through a queue of 64: every value arrives,
    // once, in order; a full queue only makes the producer retry.
    SpscQueue<uint64_t> big(64);
    constexpr uint64_t kN = 1000000;
    std::thread producer([&] {
        for (uint64_t i = 1; i <= kN; ++i)
            while (!big.push(i)) std::this_thread::yield();
    });
    uint64_t expected = 1, out_of_order = 0;
    while (expected <= kN) {
        if (!big.pop(v)) continue;
        if (v != expected) ++out_of_order;
        expected = v + 1;
    }
    producer.join();
    EXPECT_EQ(out_of_order, 0u);
    EXPECT_FALSE(big.pop(v));
}

TEST(ServoCommand, RefusesBadCommandsWithAReason) {
    ServoCommand c;
    EXPECT_EQ(make_event_command("site_charted", R"({"tooth":11})", c), "");
    EXPECT_EQ(c.kind_view(), "site_charted");
    EXPECT_EQ(c.text_view(), R"({"tooth":11})");
    EXPECT_NE(make_event_command("", "{}", c), "");
    EXPECT_NE(make_event_command(std::string(kServoEventKindBytes + 1, 'k'), "{}", c), "");
    EXPECT_NE(make_event_command("servo.estop", "{}", c), "");  // the loop's own kinds
    EXPECT_NE(make_event_command("note", std::string(kServoEventTextBytes + 1, 'x'), c), "");
    EXPECT_NE(make_workspace_command(WorkspaceMap{Vec3(0.0), 0.0}, c), "");
    EXPECT_NE(make_workspace_command(WorkspaceMap{Vec3(NAN, 0.0, 0.0), 1.0}, c), "");

    // A map's text reads back to the same bits.
    const WorkspaceMap m{Vec3(0.1, -1.0 / 3.0, 2.5e-7), 0.7};
    char buf[160];
    const std::size_t n = format_workspace(m, buf, sizeof buf);
    ASSERT_GT(n, 0u);
    WorkspaceMap back;
    ASSERT_EQ(parse_workspace(std::string_view(buf, n), back), "");
    EXPECT_EQ(std::memcmp(&back, &m, sizeof m), 0);
    EXPECT_EQ(format_workspace(m, buf, 10), 0u);
    EXPECT_NE(parse_workspace("{\"scale\":1}", back), "");

    // The servo.begin text carries the map and every safety setting, infinities included.
    SafetyConfig sc;
    sc.limits.max_force_N = 3.3;
    sc.limits.max_torque_rate_Nm_per_s = INFINITY;
    sc.ramp_in_time_s = 1.0 / 3.0;
    sc.engage_ticks = 7;
    const std::string text = format_servo_begin(m, sc);
    SafetyConfig sb;
    bool has = false;
    ASSERT_EQ(parse_servo_begin(text, back, sb, has), "") << text;
    EXPECT_TRUE(has);
    EXPECT_EQ(std::memcmp(&back, &m, sizeof m), 0);
    EXPECT_EQ(sb.limits.max_force_N, 3.3);
    EXPECT_EQ(sb.limits.max_torque_rate_Nm_per_s, INFINITY);
    EXPECT_EQ(sb.ramp_in_time_s, 1.0 / 3.0);
    EXPECT_EQ(sb.engage_ticks, 7);
    EXPECT_EQ(sb.max_dt_s, sc.max_dt_s);
    EXPECT_NE(parse_servo_begin(R"({"offset_m":[0,0,0],"scale":1,"safety":{"max_force_N":1}})", back, sb, has), "");
}

// The loop with everything other threads can ask of it: lesson events, a workspace change, an
// emergency stop and a reset, posted from a second thread while the hand presses. Each is applied
// and recorded at a tick; replaying the recording (its clock, device state and commands) gives
// every sent force and torque bit for bit.
TEST(ServoLoop, CommandsAreAppliedRecordedAndReplayedBitForBit) {
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -5.0 * mm, 0.0));
    const std::unique_ptr<Model> model = test::model_of(tool, {test::object("slab", slab)});
    ASSERT_TRUE(model);

    ServoConfig config;
    config.duration_s = 1.2;
    config.safety.limits.max_force_N = 1.0;
    config.safety.limits.max_torque_Nm = 0.05;
    config.safety.ramp_in_time_s = 0.1;
    // Late ticks on a loaded machine are not what this test is about: three in a row would be a
    // stall, fading the force it checks before the stop for the next third of a second (the stall
    // has tests of its own, and the replay takes the setting from the recording).
    config.safety.stall_deadline_misses = 1 << 20;
    // The device's frame is 40 mm off the scene's: the anchor puts the first reading on the tool's
    // starting place (the origin).
    config.anchor = true;
    config.anchor_position_m = Vec3(0.0);
    config.trace_ticks = 2000;
    HandParameters hp;
    hp.dt_s = 1e-3;
    std::vector<TrajectorySample> script = press_script();
    for (TrajectorySample& s : script) s.pose.position += Vec3(0.0, 40 * mm, 0.0);
    SimulatedHand hand(script, hp);

    const std::string path =
        (std::filesystem::temp_directory_path() / ("test_servo_cmd_" + std::to_string(::getpid()) + ".rec")).string();
    RecordingWriter recorder;
    RecordingMetadata meta;
    meta.device = "sim";
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, meta, ropts), "");
    ASSERT_EQ(recorder.start_writer_thread(0.02), "");

    ServoLoop loop;
    EXPECT_NE(loop.post_event("note", "{}"), "");  // not running: refused
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");
    ServoSnapshot first;
    while (!loop.latest(first)) std::this_thread::yield();
    EXPECT_NEAR(first.haptic.position.y, 0.0, 1e-6);  // anchored: 40 mm off in the device frame

    auto at = [&](double t_s) {
        ServoSnapshot s;
        while (loop.running() && (!loop.latest(s) || s.time_s < t_s)) std::this_thread::sleep_for(std::chrono::microseconds(200));
    };
    at(0.1);
    EXPECT_EQ(loop.post_event("lesson_step", R"({"step":1})"), "");
    at(0.5);
    EXPECT_EQ(loop.set_workspace(WorkspaceMap{Vec3(0.3 * mm, -40 * mm, 0.0), 1.0}), "");
    EXPECT_EQ(loop.post_event("site_charted", R"({"tooth":11,"site":"MB","pd_mm":3})"), "");
    at(0.7);
    loop.emergency_stop();
    at(0.8);
    ServoSnapshot stopped;
    ASSERT_TRUE(loop.latest(stopped));
    EXPECT_EQ(stopped.safety, SafetyState::EStopped);
    EXPECT_EQ(stopped.force_N, Vec3(0.0));
    loop.reset_safety();
    loop.wait();
    ASSERT_EQ(recorder.close(), "");
    const ServoStats st = loop.stats();
    EXPECT_EQ(st.commands, 3u);
    EXPECT_EQ(st.event_drops, 0u);

    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    ASSERT_EQ(rec.ticks.size(), st.ticks);
    auto tick_of = [&](std::string_view kind) -> int64_t {
        for (const RecordingEvent& e : rec.events)
            if (e.kind == kind) return static_cast<int64_t>(e.tick);
        return -1;
    };
    EXPECT_EQ(tick_of("servo.begin"), 0);
    const int64_t step_tick = tick_of("lesson_step"), map_tick = tick_of("servo.workspace");
    const int64_t stop_tick = tick_of("servo.estop"), reset_tick = tick_of("servo.reset");
    EXPECT_GT(step_tick, 0);
    EXPECT_GT(map_tick, step_tick);
    EXPECT_EQ(tick_of("site_charted"), map_tick);
    EXPECT_GT(stop_tick, map_tick);
    EXPECT_GT(reset_tick, stop_tick);
    ASSERT_GE(stop_tick, 0);
    // The stop acted at its own tick, and the recording says so.
    EXPECT_EQ(rec.ticks[static_cast<std::size_t>(stop_tick)].safety_state, static_cast<uint8_t>(SafetyState::EStopped));
    EXPECT_EQ(rec.ticks[static_cast<std::size_t>(stop_tick)].force_N, Vec3(0.0));
    EXPECT_GT(glm::length(rec.ticks[static_cast<std::size_t>(stop_tick - 1)].force_N), 0.1);
    // The clock is recorded as the loop measured it.
    for (std::size_t i = 1; i < rec.ticks.size(); ++i) ASSERT_GT(rec.ticks[i].dt_s, 0.0) << "tick " << i;

    // The replay takes the safety settings the loop used from the recording (the device's limits
    // applied), whatever the caller passes.
    EXPECT_EQ(loop.safety_config().limits.max_torque_Nm, 0.0);  // the sim hand renders no torque
    const ReplayResult r = replay_recording(rec, *model, SafetyConfig{});
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.first_mismatch, -1);
    // Not vacuous: without the commands the replay differs (the map change moves the tool).
    RecordingRead bare = rec;
    bare.events.erase(std::remove_if(bare.events.begin(), bare.events.end(),
                                     [](const RecordingEvent& e) { return e.kind != "servo.begin"; }),
                      bare.events.end());
    const ReplayResult rb = replay_recording(bare, *model, config.safety);
    ASSERT_TRUE(rb.ok()) << rb.error;
    EXPECT_GE(rb.first_mismatch, map_tick);
    std::filesystem::remove(path);
}

// The press scene of the tests above: a 5 mm cube tool and a slab 0.5 mm below it.
std::unique_ptr<Model> press_model() {
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -5.0 * mm, 0.0));
    return test::model_of(tool, {test::object("slab", slab)});
}

// A simulated hand whose read() busy-waits `stall_us` on every `every`-th call: ticks that overrun
// their deadline on purpose. No allocation, no sleep (the wait is on the servo thread's clock).
class StallingHand final : public Device {
public:
    StallingHand(std::vector<TrajectorySample> script, HandParameters hp, int every, int stall_us)
        : hand_(std::move(script), hp), every_(every), stall_us_(stall_us) {}
    const DeviceCapabilities& capabilities() const override { return hand_.capabilities(); }
    std::string start() override { return hand_.start(); }
    bool read(DeviceSample& sample) noexcept override {
        if (++reads_ % every_ == 0) {
            const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(stall_us_);
            while (std::chrono::steady_clock::now() < until) {
            }
        }
        return hand_.read(sample);
    }
    void write(const Vec3& f, const Vec3& t) noexcept override { hand_.write(f, t); }
    void stop() override { hand_.stop(); }

private:
    SimulatedHand hand_;
    int every_, stall_us_;
    long reads_ = 0;
};

// With a consumer draining as it goes (a queue large enough for a loaded machine), the telemetry
// holds every tick once, in order, and each sample is the tick the loop sent: its force bit for bit
// and its step time as recorded in the trace.
TEST(ServoTelemetry, EveryTickOnceInOrderWhenDrained) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.duration_s = 0.6;
    config.safety.limits.max_force_N = 1.0;
    config.trace_ticks = 2000;
    config.telemetry_queue = 2048;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);

    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model), "");
    std::vector<ServoSnapshot> got;
    got.reserve(4096);
    ServoSnapshot s;
    while (loop.running()) {
        while (loop.pop_telemetry(s)) got.push_back(s);
        std::this_thread::sleep_for(std::chrono::milliseconds(16));  // a UI frame
    }
    loop.wait();
    while (loop.pop_telemetry(s)) got.push_back(s);
    const ServoStats st = loop.stats();

    EXPECT_EQ(st.telemetry_drops, 0u);
    ASSERT_GT(st.ticks, 100u);
    ASSERT_EQ(got.size(), st.ticks);
    ASSERT_EQ(loop.trace_size(), st.ticks);
    uint64_t misses = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
        const ServoSnapshot& g = got[i];
        const TickSample& t = loop.trace()[i];
        ASSERT_EQ(g.tick, i);
        ASSERT_EQ(g.tick_check, i);
        ASSERT_EQ(g.telemetry_drops, 0u);
        ASSERT_GE(g.deadline_misses, misses) << "tick " << i;  // cumulative
        misses = g.deadline_misses;
        if (i > 0) {
            ASSERT_GT(g.time_s, got[i - 1].time_s) << "tick " << i;
        }
        ASSERT_EQ(std::memcmp(&g.force_N, &t.force_N, sizeof(Vec3)), 0) << "tick " << i;
        ASSERT_EQ(g.step_us, t.step_us) << "tick " << i;
        ASSERT_EQ(g.step_us >= 0.0f, g.device_ok) << "tick " << i;
    }
    EXPECT_EQ(misses, st.deadline_misses);
    // Not vacuous: the press reached the slab.
    EXPECT_GT(st.status_counts[static_cast<int>(StepStatus::Contact)], 0u);
    // Off by default: a loop started without telemetry gives none.
    ServoLoop quiet;
    ServoConfig off = config;
    off.telemetry_queue = 0;
    off.duration_s = 0.05;
    SimulatedHand hand2(press_script(), hp);
    ASSERT_EQ(quiet.start(off, hand2, *model), "");
    quiet.wait();
    EXPECT_GT(quiet.stats().ticks, 0u);
    EXPECT_FALSE(quiet.pop_telemetry(s));
}

// Nobody drains: the queue keeps the first ticks it had room for, every later tick is dropped and
// counted, and the loop keeps its rate.
TEST(ServoTelemetry, DropsAreCountedWhenNobodyDrains) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.duration_s = 0.3;
    config.telemetry_queue = 50;  // rounded up to 64
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model), "");
    loop.wait();
    const ServoStats st = loop.stats();
    ASSERT_GT(st.ticks, 200u);
    EXPECT_EQ(st.telemetry_drops, st.ticks - 64);
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_EQ(last.telemetry_drops, st.telemetry_drops);  // the published one counts its own drop

    std::vector<ServoSnapshot> got;
    ServoSnapshot s;
    while (loop.pop_telemetry(s)) got.push_back(s);
    ASSERT_EQ(got.size(), 64u);
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].tick, i);
        EXPECT_EQ(got[i].telemetry_drops, 0u);  // queued before the first drop
    }
    EXPECT_GT(st.achieved_rate_hz, 0.8 * config.rate_hz);

    ServoConfig too_big = config;
    too_big.telemetry_queue = (1u << 20) + 1;
    ServoLoop refused;
    EXPECT_NE(refused.start(too_big, hand, *model), "");
}

// Ticks that overrun on purpose (a 2.5 ms stall every 25th read at 1 kHz): the last snapshot, as
// published and as queued, carries the loop's final miss count, and the count grows by the ticks
// that overran.
TEST(ServoTelemetry, LastSnapshotCarriesTheFinalDeadlineMisses) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.telemetry_queue = 4096;
    HandParameters hp;
    hp.dt_s = 1e-3;
    StallingHand hand(press_script(), hp, 25, 2500);
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    loop.stop();  // at an arbitrary tick
    const ServoStats st = loop.stats();
    EXPECT_GE(st.deadline_misses, 8u);  // at least the stalled ticks (about 16 in 0.4 s)
    EXPECT_GT(st.skipped_slots, 0u);
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_EQ(last.tick + 1, st.ticks);
    EXPECT_EQ(last.deadline_misses, st.deadline_misses);
    ServoSnapshot s, queued_last;
    uint64_t n = 0;
    while (loop.pop_telemetry(s)) {
        queued_last = s;
        ++n;
    }
    ASSERT_EQ(n, st.ticks);
    EXPECT_EQ(queued_last.tick, last.tick);
    EXPECT_EQ(queued_last.deadline_misses, st.deadline_misses);
}

// The servo thread allocates nothing while it ticks with telemetry on and a consumer draining it
// (the queue is allocated in start()).
TEST(ServoTelemetry, NoAllocationInTicksWithTelemetry) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.telemetry_queue = 256;
    config.try_realtime = false;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model), "");
    ServoSnapshot s;
    while (!loop.latest(s)) std::this_thread::yield();
    const long before = test::heap_allocations();
    uint64_t taken = 0;
    for (int frame = 0; frame < 30; ++frame) {  // about 0.5 s of contact and drops-free draining
        while (loop.pop_telemetry(s)) ++taken;
        std::this_thread::sleep_for(std::chrono::milliseconds(16));
    }
    const long during = test::heap_allocations() - before;
    loop.stop();
    EXPECT_EQ(during, 0);
    EXPECT_GT(taken, 300u);
    const long probe = test::heap_allocations();  // the counter does count here
    std::vector<double> v(3);
    EXPECT_EQ(test::heap_allocations() - probe, 1);
    EXPECT_GT(loop.stats().status_counts[static_cast<int>(StepStatus::Contact)], 0u);
}

// events_taken counts the UI and lesson events the loop took, this tick's included: its change
// from one queued snapshot to the next is the number recorded at that tick. A workspace change is
// a command but not an event, and does not count.
TEST(ServoTelemetry, EventsTakenCountsPostedEventsAtTheirTick) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.duration_s = 0.5;
    config.telemetry_queue = 4096;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("test_servo_events_taken_" + std::to_string(::getpid()) + ".rec"))
                                 .string();
    RecordingWriter recorder;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, RecordingMetadata{}, ropts), "");
    ASSERT_EQ(recorder.start_writer_thread(0.02), "");
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(loop.post_event("chart.depth", R"({"mm":2})"), "");
    EXPECT_EQ(loop.post_event("chart.depth", R"({"mm":3})"), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(loop.set_workspace(WorkspaceMap{Vec3(0.0), 1.0}), "");
    EXPECT_EQ(loop.post_event("lesson_step", R"({"step":2})"), "");
    loop.wait();
    ASSERT_EQ(recorder.close(), "");
    const ServoStats st = loop.stats();
    EXPECT_EQ(st.commands, 4u);
    EXPECT_EQ(st.events_taken, 3u);

    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    std::vector<uint64_t> recorded_at(st.ticks, 0);  // UI/lesson events recorded per tick
    for (const RecordingEvent& e : rec.events)
        if (!is_servo_event(e.kind)) ++recorded_at[e.tick];
    ServoSnapshot s;
    uint64_t prev = 0, n = 0;
    while (loop.pop_telemetry(s)) {
        ASSERT_EQ(s.tick, n) << "telemetry dropped a tick";
        ASSERT_EQ(s.events_taken - prev, recorded_at[s.tick]) << "tick " << s.tick;
        prev = s.events_taken;
        ++n;
    }
    EXPECT_EQ(n, st.ticks);
    EXPECT_EQ(prev, 3u);
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_EQ(last.events_taken, 3u);
    std::filesystem::remove(path);
}

// A manual-clock run of `ticks` ticks of the press with a recorder flushed every 100 ticks from
// this thread; returns the recording read back.
RecordingRead manual_press(const Model& model, int ticks, const std::string& path) {
    ServoConfig config;
    config.manual_clock = true;
    config.safety.limits.max_force_N = 1.0;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);
    RecordingWriter recorder;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    EXPECT_EQ(recorder.open(path, RecordingMetadata{}, ropts), "");
    ServoLoop loop;
    EXPECT_EQ(loop.start(config, hand, model, &recorder), "");
    for (int i = 0; i < ticks; ++i) {
        if (i == 300) {
            EXPECT_EQ(loop.post_event("chart.depth", R"({"mm":1.5})"), "");
        }
        EXPECT_TRUE(loop.step_manual());
        if (recorder.pending_ticks() >= 100) {
            EXPECT_EQ(recorder.flush(), "");
        }
    }
    loop.stop();
    EXPECT_EQ(recorder.close(), "");
    return read_recording(path);
}

// The manual clock: no thread, every tick on this thread at time tick / rate with dt 1 / rate, no
// deadline missed, no sleeping; the same tick body as the threaded loop (recording, trace,
// telemetry, latest(), statistics), period statistics left zero; stop() ends it.
TEST(ServoManualClock, TicksOnTheCallersClockWithNoMisses) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.manual_clock = true;
    config.safety.limits.max_force_N = 1.0;
    config.trace_ticks = 1000;
    config.telemetry_queue = 64;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);

    ServoLoop loop;
    EXPECT_FALSE(loop.step_manual());  // not started
    ASSERT_EQ(loop.start(config, hand, *model), "");
    EXPECT_TRUE(loop.running());
    EXPECT_TRUE(loop.manual());
    EXPECT_FALSE(loop.realtime());
    ServoSnapshot s;
    EXPECT_FALSE(loop.latest(s));  // prepared, no tick yet
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<ServoSnapshot> got;
    for (int i = 0; i < 800; ++i) {
        ASSERT_TRUE(loop.step_manual()) << "tick " << i;
        ASSERT_TRUE(loop.latest(s));
        ASSERT_EQ(s.tick, static_cast<uint64_t>(i));
        while (loop.pop_telemetry(s)) got.push_back(s);
    }
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    loop.stop();
    EXPECT_FALSE(loop.running());
    EXPECT_FALSE(loop.step_manual());  // after stop()
    loop.stop();                       // twice is harmless

    const ServoStats st = loop.stats();
    EXPECT_EQ(st.ticks, 800u);
    EXPECT_EQ(st.deadline_misses, 0u);
    EXPECT_EQ(st.skipped_slots, 0u);
    EXPECT_EQ(st.elapsed_s, 0.0);
    EXPECT_EQ(st.period_us.max, 0.0);
    EXPECT_EQ(st.jitter_us.max, 0.0);
    EXPECT_GT(st.step_us.max, 0.0);  // the step's own wall time is still measured
    EXPECT_GT(st.status_counts[static_cast<int>(StepStatus::Contact)], 0u);
    EXPECT_FALSE(st.non_finite_sent);
    ASSERT_EQ(loop.trace_size(), 800u);
    ASSERT_EQ(got.size(), 800u);
    for (std::size_t i = 0; i < 800; ++i) {
        const TickSample& t = loop.trace()[i];
        ASSERT_EQ(t.tick, i);
        ASSERT_EQ(t.time_s, static_cast<double>(i) / 1000.0) << "tick " << i;
        ASSERT_EQ(t.dt_s, 1.0 / 1000.0) << "tick " << i;
        ASSERT_FALSE(t.deadline_missed) << "tick " << i;
        ASSERT_EQ(got[i].time_s, t.time_s);
        ASSERT_EQ(got[i].deadline_misses, 0u);
        ASSERT_EQ(std::memcmp(&got[i].force_N, &t.force_N, sizeof(Vec3)), 0) << "tick " << i;
    }
    // Faster than the real clock would allow: nothing sleeps (0.8 s of session).
    std::printf("800 manual ticks in %.3f s of wall time\n", wall_s);
    EXPECT_LT(wall_s, 0.8);

    // A threaded loop does not step by hand; a manual one with a duration ends by itself.
    ServoConfig timed = config;
    timed.duration_s = 0.1;
    SimulatedHand hand2(press_script(), hp);
    ServoLoop short_loop;
    ASSERT_EQ(short_loop.start(timed, hand2, *model), "");
    int n = 0;
    while (short_loop.step_manual()) ++n;
    EXPECT_EQ(n, 100);
    EXPECT_FALSE(short_loop.running());
    short_loop.wait();
    EXPECT_EQ(short_loop.stats().ticks, 100u);
    ServoConfig threaded = config;
    threaded.manual_clock = false;
    threaded.duration_s = 0.02;
    SimulatedHand hand3(press_script(), hp);
    ServoLoop live;
    ASSERT_EQ(live.start(threaded, hand3, *model), "");
    EXPECT_FALSE(live.step_manual());
    live.wait();
}

// Two manual runs of the same script record the same ticks: every field bit for bit but the step's
// wall time (a measurement of this machine, not an outcome).
TEST(ServoManualClock, TwoRunsRecordIdenticalTicks) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    const std::string base = (std::filesystem::temp_directory_path() /
                              ("test_servo_manual_" + std::to_string(::getpid()))).string();
    const RecordingRead a = manual_press(*model, 1000, base + "_a.rec");
    const RecordingRead b = manual_press(*model, 1000, base + "_b.rec");
    ASSERT_TRUE(a.ok() && b.ok()) << a.error << b.error;
    ASSERT_EQ(a.ticks.size(), 1000u);
    ASSERT_EQ(b.ticks.size(), 1000u);
    int contact = 0;
    for (std::size_t i = 0; i < a.ticks.size(); ++i) {
        TickSample x = a.ticks[i], y = b.ticks[i];
        x.step_us = y.step_us = 0.0f;
        // Compare the fields as stored (no padding compared).
        const double dx[] = {x.time_s, x.dt_s, x.device_pose.position.x, x.device_pose.position.y,
                             x.device_pose.position.z, x.device_pose.orientation.w, x.device_pose.orientation.x,
                             x.device_pose.orientation.y, x.device_pose.orientation.z, x.force_N.x, x.force_N.y,
                             x.force_N.z, x.torque_Nm.x, x.torque_Nm.y, x.torque_Nm.z};
        const double dy[] = {y.time_s, y.dt_s, y.device_pose.position.x, y.device_pose.position.y,
                             y.device_pose.position.z, y.device_pose.orientation.w, y.device_pose.orientation.x,
                             y.device_pose.orientation.y, y.device_pose.orientation.z, y.force_N.x, y.force_N.y,
                             y.force_N.z, y.torque_Nm.x, y.torque_Nm.y, y.torque_Nm.z};
        ASSERT_EQ(std::memcmp(dx, dy, sizeof dx), 0) << "tick " << i;
        ASSERT_EQ(x.tick, y.tick);
        ASSERT_EQ(x.buttons, y.buttons);
        ASSERT_EQ(x.status, y.status) << "tick " << i;
        ASSERT_EQ(x.safety_state, y.safety_state) << "tick " << i;
        ASSERT_EQ(x.device_read, y.device_read);
        ASSERT_EQ(x.connected, y.connected);
        ASSERT_EQ(x.deadline_missed, y.deadline_missed);
        ASSERT_EQ(x.device_fault, y.device_fault);
        if (x.status == StepStatus::Contact) ++contact;
    }
    EXPECT_GT(contact, 100);
    ASSERT_EQ(a.events.size(), b.events.size());
    for (std::size_t i = 0; i < a.events.size(); ++i) {
        EXPECT_EQ(a.events[i].tick, b.events[i].tick);
        EXPECT_EQ(a.events[i].kind, b.events[i].kind);
        EXPECT_EQ(a.events[i].json, b.events[i].json);
    }
    std::filesystem::remove(base + "_a.rec");
    std::filesystem::remove(base + "_b.rec");
}

// An event posted between two step_manual() calls is taken, and recorded, at the next tick.
TEST(ServoManualClock, EventPostedBetweenStepsIsRecordedAtTheNextTick) {
    const std::unique_ptr<Model> model = press_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.manual_clock = true;
    HandParameters hp;
    hp.dt_s = 1e-3;
    SimulatedHand hand(press_script(), hp);
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("test_servo_manual_event_" + std::to_string(::getpid()) + ".rec"))
                                 .string();
    RecordingWriter recorder;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, RecordingMetadata{}, ropts), "");
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");
    ServoSnapshot s;
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(loop.step_manual());
    ASSERT_TRUE(loop.latest(s));
    EXPECT_EQ(s.tick, 9u);
    EXPECT_EQ(s.events_taken, 0u);
    ASSERT_EQ(loop.post_event("chart.depth", R"({"mm":4})"), "");
    ASSERT_EQ(loop.post_event("lesson_step", R"({"step":3})"), "");
    ASSERT_TRUE(loop.step_manual());
    ASSERT_TRUE(loop.latest(s));
    EXPECT_EQ(s.tick, 10u);
    EXPECT_EQ(s.events_taken, 2u);
    loop.emergency_stop();
    ASSERT_TRUE(loop.step_manual());
    ASSERT_TRUE(loop.latest(s));
    EXPECT_EQ(s.safety, SafetyState::EStopped);
    EXPECT_EQ(s.events_taken, 2u);  // a servo command is not a UI event
    loop.stop();
    ASSERT_EQ(recorder.close(), "");
    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    ASSERT_EQ(rec.ticks.size(), 12u);
    ASSERT_EQ(rec.events.size(), 4u);
    EXPECT_EQ(rec.events[0].kind, "servo.begin");
    EXPECT_EQ(rec.events[0].tick, 0u);
    EXPECT_EQ(rec.events[1].kind, "chart.depth");
    EXPECT_EQ(rec.events[1].tick, 10u);
    EXPECT_EQ(rec.events[2].kind, "lesson_step");
    EXPECT_EQ(rec.events[2].tick, 10u);
    EXPECT_EQ(rec.events[3].kind, "servo.estop");
    EXPECT_EQ(rec.events[3].tick, 11u);
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace sulcus
