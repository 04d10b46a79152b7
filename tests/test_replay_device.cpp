// Replay of a recorded session: a session is recorded headlessly (a simulated hand presses a
// 5 mm cube into a slab built in code, through the real step, safety layer and recorder, tick by
// tick with no clock), read back, and replayed with replay_recording on the same model. The
// replayed forces equal the recorded ones bit for bit; an edited pose changes them. The
// ReplayDevice's own contract (cursor, end of recording, no allocation) is checked directly.
#include "scene_helpers.h"

#include "sulcus/content/primitives.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/replay_device.h"
#include "sulcus/haptics/safety.h"
#include "sulcus/haptics/servo_loop.h"
#include "sulcus/haptics/sim_device.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <numbers>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "allocation_counter.h"

namespace sulcus {
namespace {

using test::mm;

constexpr double kRateHz = 1000.0;
constexpr int kTicks = 2000;

// The hand's target: rest 0.5 mm above the slab for 0.1 s, 6 mm down over 0.4 s (about 1.6 N
// through the grip, under the 3 N limit), hold, a slow 1 mm slide along x, back up from 1.4 s.
std::vector<TrajectorySample> press_script() {
    std::vector<TrajectorySample> out;
    for (int i = 0; i <= 1000; ++i) {
        const double t = i * 0.002;
        const double u = std::clamp((t - 0.1) / 0.4, 0.0, 1.0);
        const double w = std::clamp((t - 1.4) / 0.3, 0.0, 1.0);
        const double slide = std::clamp((t - 0.7) / 0.5, 0.0, 1.0);
        const double down = u * u * (3.0 - 2.0 * u) - w * w * (3.0 - 2.0 * w);
        out.push_back({t, Pose{Vec3(1.0 * mm * slide, -6.0 * mm * down, 0.0), Quat(1, 0, 0, 0)}});
    }
    return out;
}

std::unique_ptr<Model> slab_model() {
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -5.0 * mm, 0.0));
    return test::model_of(tool, {test::object("slab", slab)});
}

SafetyConfig safety_config() {
    SafetyConfig c;
    c.nominal_dt_s = 1.0 / kRateHz;
    return c;
}

std::string temp_path(const char* tag) {
    return (std::filesystem::temp_directory_path() /
            (std::string("test_replay_device_") + tag + "_" + std::to_string(::getpid()) + ".rec"))
        .string();
}

// Records kTicks ticks of the closed loop without a thread or clock: the servo loop's tick
// (read, step, safety, write, record) with dt = 1 / rate and no missed deadline.
RecordingRead record_session(const Model& model, const std::string& path) {
    HandParameters hp;
    hp.dt_s = 1.0 / kRateHz;
    SimulatedHand hand(press_script(), hp);
    EXPECT_EQ(hand.start(), "");
    SafetyLayer safety(safety_config());

    RecordingWriter recorder;
    RecordingMetadata meta;
    meta.case_path = "in-code slab";
    meta.device = "sim";
    meta.rate_hz = kRateHz;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    EXPECT_EQ(recorder.open(path, meta, ropts), "");

    DeviceSample sample;
    hand.read(sample);
    State state = make_state(sample.pose);
    StepResult result;
    result.graphic = state.graphic;
    result.status = StepStatus::Held;
    for (int tick = 0; tick < kTicks; ++tick) {
        if (tick == 1200) hand.set_buttons(1u);  // buttons are replayed too
        const bool read_ok = hand.read(sample);
        if (read_ok) result = step(model, state, sample.pose);
        SafetyInput in;
        in.force_N = result.force_N;
        in.torque_Nm = result.torque_Nm;
        in.step_ok = read_ok && result.status != StepStatus::Held && result.status != StepStatus::BadInput;
        in.deadline_missed = false;
        in.device_connected = sample.connected;
        in.device_fault = sample.fault != kDeviceFaultNone;
        in.dt_s = 1.0 / kRateHz;
        const SafetyOutput out = safety.tick(in);
        hand.write(out.force_N, out.torque_Nm);

        TickSample ts;
        ts.tick = static_cast<uint64_t>(tick);
        ts.time_s = tick / kRateHz;
        ts.device_pose = sample.pose;
        ts.buttons = sample.buttons;
        ts.force_N = out.force_N;
        ts.torque_Nm = out.torque_Nm;
        ts.status = result.status;
        EXPECT_TRUE(recorder.add_tick(ts)) << "tick " << tick;
        if (tick % 100 == 99) {
            EXPECT_EQ(recorder.flush(), "");
        }
    }
    EXPECT_EQ(recorder.close(), "");
    hand.stop();
    return read_recording(path);
}

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }

class Replay : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        model_ = slab_model().release();
        path_ = new std::string(temp_path("session"));
        rec_ = new RecordingRead(record_session(*model_, *path_));
    }
    static void TearDownTestSuite() {
        std::filesystem::remove(*path_);
        delete rec_;
        delete path_;
        delete model_;
    }
    static Model* model_;
    static std::string* path_;
    static RecordingRead* rec_;
};
Model* Replay::model_ = nullptr;
std::string* Replay::path_ = nullptr;
RecordingRead* Replay::rec_ = nullptr;

TEST_F(Replay, RecordedSessionIsNotTrivial) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    ASSERT_FALSE(rec_->truncation.truncated) << rec_->truncation.reason;
    ASSERT_EQ(rec_->ticks.size(), static_cast<std::size_t>(kTicks));
    int contact = 0;
    double max_force = 0.0;
    for (const TickSample& t : rec_->ticks) {
        if (t.status == StepStatus::Contact) ++contact;
        max_force = std::max(max_force, glm::length(t.force_N));
    }
    EXPECT_GT(contact, 500);
    EXPECT_GT(max_force, 1.0);
    EXPECT_LT(max_force, 3.0);  // under the force limit: forces are not just the clamp
    std::printf("%d ticks in contact, max force %.4f N\n", contact, max_force);
}

TEST_F(Replay, ReplayedForcesEqualRecordedBitForBit) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    const ReplayResult r = replay_recording(*rec_, *model_, safety_config());
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(r.force_N.size(), rec_->ticks.size());
    ASSERT_EQ(r.torque_Nm.size(), rec_->ticks.size());
    for (std::size_t i = 0; i < rec_->ticks.size(); ++i) {
        ASSERT_TRUE(same_bits(r.force_N[i], rec_->ticks[i].force_N)) << "tick " << i;
        ASSERT_TRUE(same_bits(r.torque_Nm[i], rec_->ticks[i].torque_Nm)) << "tick " << i;
        ASSERT_EQ(r.status[i], rec_->ticks[i].status) << "tick " << i;
    }
    EXPECT_EQ(r.first_mismatch, -1);
}

TEST_F(Replay, TwoReplaysAreIdentical) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    const ReplayResult a = replay_recording(*rec_, *model_, safety_config());
    const ReplayResult b = replay_recording(*rec_, *model_, safety_config());
    ASSERT_TRUE(a.ok() && b.ok());
    ASSERT_EQ(a.force_N.size(), b.force_N.size());
    EXPECT_EQ(std::memcmp(a.force_N.data(), b.force_N.data(), a.force_N.size() * sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(a.torque_Nm.data(), b.torque_Nm.data(), a.torque_Nm.size() * sizeof(Vec3)), 0);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.safety, b.safety);
}

TEST_F(Replay, EditedPoseChangesTheForceFromThatTick) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    // A tick in steady contact, force well inside the limits.
    std::size_t k = 0;
    for (std::size_t i = 800; i < rec_->ticks.size(); ++i) {
        const TickSample& t = rec_->ticks[i];
        const double f = glm::length(t.force_N);
        if (t.status == StepStatus::Contact && f > 0.5 && f < 2.5) {
            k = i;
            break;
        }
    }
    ASSERT_GT(k, 0u) << "no tick in contact to edit";

    RecordingRead edited = *rec_;
    edited.ticks[k].device_pose.position.y -= 0.3 * mm;  // 0.3 mm deeper into the slab
    const ReplayResult r = replay_recording(edited, *model_, safety_config());
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(r.force_N.size(), rec_->ticks.size());
    for (std::size_t i = 0; i < k; ++i)
        ASSERT_TRUE(same_bits(r.force_N[i], rec_->ticks[i].force_N)) << "tick " << i << " before the edit";
    EXPECT_EQ(r.first_mismatch, static_cast<int64_t>(k));
    EXPECT_FALSE(same_bits(r.force_N[k], rec_->ticks[k].force_N));
    std::printf("edited tick %zu: recorded %.6f N, replayed %.6f N\n", k, glm::length(rec_->ticks[k].force_N),
                glm::length(r.force_N[k]));
}

TEST_F(Replay, DeviceReplaysPosesAndStoresWrites) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    ReplayDevice dev(*path_);  // from the file this time
    ASSERT_EQ(dev.error(), "");
    EXPECT_EQ(dev.capabilities().name, "replay");
    EXPECT_EQ(dev.capabilities().nominal_rate_Hz, kRateHz);
    ASSERT_EQ(dev.tick_count(), rec_->ticks.size());

    DeviceSample s;
    EXPECT_FALSE(dev.read(s));  // not started
    EXPECT_EQ(s.fault, kDeviceFaultNotStarted);
    ASSERT_EQ(dev.start(), "");

    // A read with no write in between sees the same tick (the loop's read before its first tick).
    ASSERT_TRUE(dev.read(s));
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(dev.cursor(), 0u);

    const long before = sulcus::test::heap_allocations();
    for (std::size_t i = 0; i < rec_->ticks.size(); ++i) {
        const TickSample& t = rec_->ticks[i];
        ASSERT_TRUE(dev.read(s));
        ASSERT_TRUE(s.connected);
        ASSERT_EQ(s.fault, kDeviceFaultNone);
        ASSERT_TRUE(same_bits(s.pose.position, t.device_pose.position)) << "tick " << i;
        ASSERT_EQ(std::memcmp(&s.pose.orientation, &t.device_pose.orientation, sizeof(Quat)), 0) << "tick " << i;
        ASSERT_EQ(s.buttons, t.buttons) << "tick " << i;
        ASSERT_FALSE(dev.finished());
        dev.write(Vec3(double(i), 0.0, 1.0), Vec3(0.0, double(i), 0.0));
    }
    EXPECT_TRUE(dev.finished());
    // After the end: the last pose, still connected; extra writes are counted, not stored.
    ASSERT_TRUE(dev.read(s));
    EXPECT_TRUE(s.connected);
    EXPECT_TRUE(same_bits(s.pose.position, rec_->ticks.back().device_pose.position));
    dev.write(Vec3(-1.0), Vec3(-1.0));
    EXPECT_EQ(sulcus::test::heap_allocations() - before, 0) << "read()/write() allocated";
    EXPECT_EQ(dev.writes_past_end(), 1u);
    ASSERT_EQ(dev.writes_stored(), rec_->ticks.size());
    EXPECT_EQ(dev.forces_written().back(), Vec3(double(rec_->ticks.size() - 1), 0.0, 1.0));
    EXPECT_EQ(dev.torques_written()[7], Vec3(0.0, 7.0, 0.0));
    // The buttons pressed mid-session came through.
    EXPECT_EQ(rec_->ticks.back().buttons, 1u);
    EXPECT_EQ(rec_->ticks.front().buttons, 0u);

    // The counter does count: a vector allocates once.
    const long probe = sulcus::test::heap_allocations();
    std::vector<double> v(3);
    EXPECT_EQ(sulcus::test::heap_allocations() - probe, 1);
    dev.stop();
    EXPECT_FALSE(dev.read(s));
}

TEST(ReplayDeviceErrors, MissingFileAndEmptyRecordingDoNotStart) {
    ReplayDevice missing(temp_path("missing"));
    EXPECT_NE(missing.error(), "");
    EXPECT_NE(missing.start(), "");
    RecordingRead empty;
    empty.metadata.rate_hz = 1000.0;
    ReplayDevice none(empty);
    EXPECT_NE(none.start(), "");
    auto model = slab_model();
    EXPECT_FALSE(replay_recording(empty, *model, safety_config()).ok());
}

// --- live loop vs. replay: the stream a lesson runtime consumes ----------------------------

using EventText = std::pair<std::string, std::string>;  // kind, json

// What a consumer sees: each tick's snapshot, and the UI events delivered just before it.
struct Stream {
    std::vector<ServoSnapshot> ticks;
    std::vector<std::vector<EventText>> events_before;  // per tick
    std::vector<EventText> events_after;               // after the last tick
};

// The live side: telemetry snapshots in tick order and the events posted (accepted), in order.
// A snapshot's events are the next (events_taken - previous events_taken) of those posted.
Stream live_stream(const std::vector<ServoSnapshot>& snaps, const std::vector<EventText>& posted) {
    Stream out;
    out.ticks = snaps;
    uint64_t taken = 0;
    for (const ServoSnapshot& s : snaps) {
        std::vector<EventText> here;
        for (; taken < s.events_taken && taken < posted.size(); ++taken) here.push_back(posted[taken]);
        out.events_before.push_back(std::move(here));
    }
    return out;
}

Stream replay_stream(const RecordingRead& rec, const Model& model, ReplayResult& result) {
    Stream out;
    std::vector<EventText> pending;
    ReplayObserver observer;
    observer.on_event = [&](const RecordingEvent& e) {
        EXPECT_FALSE(is_servo_event(e.kind)) << e.kind;
        pending.emplace_back(e.kind, e.json);
    };
    observer.on_tick = [&](const ServoSnapshot& s) {
        out.ticks.push_back(s);
        out.events_before.push_back(std::move(pending));
        pending.clear();
    };
    result = replay_recording(rec, model, SafetyConfig{}, observer);
    out.events_after = std::move(pending);
    return out;
}

template <class T>
bool same(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// Field by field, bit for bit. `misses`: also the deadline-miss count (equal when no tick missed).
void expect_same_stream(const Stream& live, const Stream& replay, bool misses) {
    ASSERT_EQ(replay.ticks.size(), live.ticks.size());
    ASSERT_EQ(replay.events_before.size(), live.events_before.size());
    EXPECT_TRUE(replay.events_after.empty());
    for (std::size_t i = 0; i < live.ticks.size(); ++i) {
        const ServoSnapshot& a = live.ticks[i];
        const ServoSnapshot& b = replay.ticks[i];
        ASSERT_EQ(b.tick, a.tick) << "snapshot " << i;
        ASSERT_TRUE(same(b.time_s, a.time_s)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.haptic.position, a.haptic.position)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.haptic.orientation, a.haptic.orientation)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.graphic.position, a.graphic.position)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.graphic.orientation, a.graphic.orientation)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.force_N, a.force_N)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.torque_Nm, a.torque_Nm)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.rendered_force_N, a.rendered_force_N)) << "tick " << a.tick;
        ASSERT_TRUE(same(b.rendered_torque_Nm, a.rendered_torque_Nm)) << "tick " << a.tick;
        ASSERT_EQ(b.status, a.status) << "tick " << a.tick;
        ASSERT_EQ(b.safety, a.safety) << "tick " << a.tick;
        ASSERT_EQ(b.device_ok, a.device_ok) << "tick " << a.tick;
        ASSERT_TRUE(same(b.step_us, a.step_us)) << "tick " << a.tick;
        ASSERT_EQ(b.events_taken, a.events_taken) << "tick " << a.tick;
        ASSERT_EQ(b.tick_check, b.tick);
        if (misses) {
            ASSERT_EQ(b.deadline_misses, a.deadline_misses) << "tick " << a.tick;
        }
        ASSERT_EQ(replay.events_before[i], live.events_before[i]) << "events before tick " << a.tick;
    }
}

// The lesson runtime's guarantee: a manual-clock session (a hand probing into contact, UI events
// posted between ticks, a workspace change) and the replay of its recording give the same stream,
// snapshot for snapshot bit for bit, each UI event immediately before the same tick.
TEST(ReplayObserver, ManualClockSessionReplaysToTheSameStream) {
    const std::unique_ptr<Model> model = slab_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.manual_clock = true;
    config.telemetry_queue = 64;
    HandParameters hp;
    hp.dt_s = 1.0 / kRateHz;
    SimulatedHand hand(press_script(), hp);
    const std::string path = temp_path("observer_manual");
    RecordingWriter recorder;
    RecordingMetadata meta;
    meta.device = "sim";
    meta.lesson = "lessons/test.json";
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, meta, ropts), "");

    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");
    std::vector<ServoSnapshot> snaps;
    std::vector<EventText> posted;
    auto post = [&](const std::string& kind, const std::string& json) {
        ASSERT_EQ(loop.post_event(kind, json), "");
        posted.emplace_back(kind, json);
    };
    constexpr int kLiveTicks = 1500;
    for (int i = 0; i < kLiveTicks; ++i) {
        if (i == 0) post("lesson_step", R"({"step":0})");
        if (i == 200) post("chart.depth", R"({"tooth":11,"site":"MB","mm":2.5})");
        if (i == 700) {
            post("chart.depth", R"({"tooth":11,"site":"B","mm":3.0})");
            post("chart.bleeding", R"({"tooth":11,"site":"B"})");
        }
        if (i == 900) {
            ASSERT_EQ(loop.set_workspace(WorkspaceMap{Vec3(0.1 * mm, 0.0, 0.0), 1.0}), "");
        }
        if (i == 1499) post("lesson_step", R"({"step":1})");
        ASSERT_TRUE(loop.step_manual());
        ServoSnapshot s;
        while (loop.pop_telemetry(s)) snaps.push_back(s);
        if (recorder.pending_ticks() >= 100) {
            ASSERT_EQ(recorder.flush(), "");
        }
    }
    loop.stop();
    ASSERT_EQ(recorder.close(), "");
    const ServoStats st = loop.stats();
    EXPECT_EQ(st.telemetry_drops, 0u);
    EXPECT_EQ(st.event_drops, 0u);
    EXPECT_EQ(st.record_drops, 0u);
    ASSERT_EQ(snaps.size(), static_cast<std::size_t>(kLiveTicks));
    EXPECT_GT(st.status_counts[static_cast<int>(StepStatus::Contact)], 500u);  // not vacuous

    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    EXPECT_EQ(rec.metadata.lesson, "lessons/test.json");
    ReplayResult r;
    const Stream replay = replay_stream(rec, *model, r);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.first_mismatch, -1);
    const Stream live = live_stream(snaps, posted);
    expect_same_stream(live, replay, true);
    // The events did arrive where posted: tick 0, 200, 700 (two, in order), 1499.
    EXPECT_EQ(replay.events_before[0].size(), 1u);
    EXPECT_EQ(replay.events_before[200].size(), 1u);
    ASSERT_EQ(replay.events_before[700].size(), 2u);
    EXPECT_EQ(replay.events_before[700][1].first, "chart.bleeding");
    EXPECT_EQ(replay.events_before[1499].size(), 1u);
    EXPECT_EQ(replay.ticks.back().events_taken, 5u);

    // Not vacuous: a recording with one edited pose gives a different stream from that tick.
    RecordingRead edited = rec;
    edited.ticks[1000].device_pose.position.y -= 0.2 * mm;
    ReplayResult re;
    const Stream other = replay_stream(edited, *model, re);
    ASSERT_EQ(other.ticks.size(), live.ticks.size());
    EXPECT_TRUE(same(other.ticks[999].force_N, live.ticks[999].force_N));
    EXPECT_FALSE(same(other.ticks[1000].haptic.position, live.ticks[1000].haptic.position));
    EXPECT_FALSE(same(other.ticks[1000].rendered_force_N, live.ticks[1000].rendered_force_N));
    std::filesystem::remove(path);
}

// The same with the real clock on its own thread (its jitter, and any missed deadline, are in the
// recording): a free-space session of about a second, with events posted from this thread.
TEST(ReplayObserver, ThreadedSessionReplaysToTheSameStream) {
    const std::unique_ptr<Model> model = slab_model();
    ASSERT_TRUE(model);
    ServoConfig config;
    config.duration_s = 1.0;
    config.telemetry_queue = 4096;
    HandParameters hp;
    hp.dt_s = 1.0 / kRateHz;
    // A 3 mm circle 2 mm above the tool's start, clear of the slab.
    std::vector<TrajectorySample> script;
    for (int i = 0; i <= 600; ++i) {
        const double t = i * 0.002, a = 2.0 * std::numbers::pi * t / 0.5;
        script.push_back({t, Pose{Vec3(3 * mm * std::sin(a), 2 * mm, 3 * mm * (1.0 - std::cos(a))), Quat(1, 0, 0, 0)}});
    }
    SimulatedHand hand(script, hp);
    const std::string path = temp_path("observer_threaded");
    RecordingWriter recorder;
    RecordingOptions ropts;
    ropts.sync = SyncPolicy::None;
    ASSERT_EQ(recorder.open(path, RecordingMetadata{}, ropts), "");
    ASSERT_EQ(recorder.start_writer_thread(0.02), "");
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, hand, *model, &recorder), "");
    std::vector<EventText> posted;
    auto post = [&](const std::string& kind, const std::string& json) {
        ASSERT_EQ(loop.post_event(kind, json), "");
        posted.emplace_back(kind, json);
    };
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    post("chart.depth", R"({"tooth":21,"site":"DB","mm":1.0})");
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    post("chart.depth", R"({"tooth":21,"site":"B","mm":2.0})");
    post("lesson_step", R"({"step":4})");
    loop.wait();
    ASSERT_EQ(recorder.close(), "");
    const ServoStats st = loop.stats();
    EXPECT_EQ(st.telemetry_drops, 0u);
    EXPECT_EQ(st.event_drops, 0u);
    EXPECT_EQ(st.record_drops, 0u);
    std::vector<ServoSnapshot> snaps;
    ServoSnapshot s;
    while (loop.pop_telemetry(s)) snaps.push_back(s);
    ASSERT_EQ(snaps.size(), st.ticks);
    ASSERT_GT(st.ticks, 500u);
    EXPECT_EQ(snaps.back().events_taken, 3u);
    std::printf("threaded: %llu ticks, %llu deadline misses\n", static_cast<unsigned long long>(st.ticks),
                static_cast<unsigned long long>(st.deadline_misses));

    const RecordingRead rec = read_recording(path);
    ASSERT_TRUE(rec.ok()) << rec.error;
    ReplayResult r;
    const Stream replay = replay_stream(rec, *model, r);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.first_mismatch, -1);
    expect_same_stream(live_stream(snaps, posted), replay, st.deadline_misses == 0);
    std::filesystem::remove(path);
}

// An event stamped past the last tick comes after the last on_tick; the three-argument replay is
// the observer's with no observer.
TEST_F(Replay, ObserverGetsLateEventsAtTheEnd) {
    ASSERT_TRUE(rec_->ok()) << rec_->error;
    RecordingRead rec = *rec_;
    rec.events.push_back({5, "chart.depth", R"({"mm":1})"});
    rec.events.push_back({rec.ticks.back().tick + 10, "lesson_end", "{}"});
    ReplayResult r;
    const Stream st = replay_stream(rec, *model_, r);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(st.ticks.size(), rec.ticks.size());
    ASSERT_EQ(st.events_before[5].size(), 1u);
    EXPECT_EQ(st.ticks[4].events_taken, 0u);
    EXPECT_EQ(st.ticks[5].events_taken, 1u);
    ASSERT_EQ(st.events_after.size(), 1u);
    EXPECT_EQ(st.events_after[0].first, "lesson_end");
    EXPECT_EQ(st.ticks.back().events_taken, 1u);
    // time and step time as recorded; the same forces as without an observer.
    EXPECT_EQ(st.ticks[7].time_s, rec.ticks[7].time_s);
    const ReplayResult plain = replay_recording(rec, *model_, safety_config());
    ASSERT_EQ(plain.force_N.size(), st.ticks.size());
    for (std::size_t i = 0; i < st.ticks.size(); ++i)
        ASSERT_TRUE(same_bits(plain.force_N[i], st.ticks[i].force_N)) << "tick " << i;
}

}  // namespace
}  // namespace sulcus
