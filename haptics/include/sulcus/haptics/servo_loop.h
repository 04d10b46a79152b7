// The servo loop: one thread ticking at a fixed rate (1 kHz by default) on absolute deadlines.
// Each tick: device.read -> renderer step -> safety layer -> device.write -> recorder.add_tick,
// then the tick's outcome is published to other threads through a seqlock. Nothing in a tick
// allocates, locks or does I/O: buffers are sized at start(), statistics live in fixed arrays,
// and percentiles are computed after stop(). With ServoConfig::manual_clock there is no thread:
// the caller runs the same tick body one tick at a time (ServoLoop::step_manual) on a fixed clock.
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/haptics/device.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/safety.h"
#include "sulcus/haptics/servo_command.h"
#include "sulcus/haptics/spsc_queue.h"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

namespace sulcus {

// Single-writer, many-reader publication of a small trivially copyable value. The writer never
// waits; a reader retries while a write is in progress, so every value it returns was written
// whole by one store(). The payload is kept in atomic words so no access is a data race.
// The work of one servo tick, shared by the threaded loop and the headless replay so the two
// cannot drift apart: device.read -> workspace map -> renderer step -> safety layer ->
// device.write. The clock (deadlines, tick length) stays with the caller.
class ServoTick {
public:
    struct Out {
        bool read_ok = false;
        bool step_ok = false;     // read, and the step gave a safe answer (not held, not bad input)
        double step_us = -1.0;    // the step's wall time; < 0 when the read failed and no step ran
        SafetyOutput sent;        // what was written to the device
    };

    // Reads the device once and starts the renderer state at its mapped pose; one throwaway step
    // on a copy makes the step's first-call allocations (thread-local scratch) here, on the
    // calling thread, not in a tick. With `anchor`, the map's offset is first set so that this
    // reading lands on `anchor`'s position (map.scale kept); workspace() then gives the map used.
    void begin(Device& device, const Model& model, const WorkspaceMap& map = {},
               const Vec3* anchor = nullptr) noexcept;
    Out run(Device& device, const Model& model, SafetyLayer& safety, bool deadline_missed, double dt_s) noexcept;

    // Takes effect at the next run(). The caller checks valid_workspace().
    void set_workspace(const WorkspaceMap& map) noexcept { map_ = map; }
    const WorkspaceMap& workspace() const noexcept { return map_; }

    const DeviceSample& sample() const noexcept { return sample_; }
    const Pose& haptic() const noexcept { return haptic_; }  // the sample's pose in the world frame
    const StepResult& result() const noexcept { return result_; }

private:
    DeviceSample sample_;
    WorkspaceMap map_;
    Pose haptic_;
    State state_;
    StepResult result_;
};

template <class T>
class Seqlock {
    static_assert(std::is_trivially_copyable_v<T>, "Seqlock holds trivially copyable values");
    static constexpr std::size_t kWords = (sizeof(T) + sizeof(uint64_t) - 1) / sizeof(uint64_t);

public:
    // Writer side (one thread only).
    void store(const T& value) noexcept {
        uint64_t buf[kWords] = {};
        std::memcpy(buf, &value, sizeof(T));
        const uint64_t s = seq_.load(std::memory_order_relaxed);
        seq_.store(s + 1, std::memory_order_relaxed);  // odd: write in progress
        std::atomic_thread_fence(std::memory_order_release);
        for (std::size_t i = 0; i < kWords; ++i) words_[i].store(buf[i], std::memory_order_relaxed);
        seq_.store(s + 2, std::memory_order_release);
    }
    // Reader side (any thread). False when nothing has been stored yet.
    bool load(T& out) const noexcept {
        uint64_t buf[kWords];
        for (;;) {
            const uint64_t s1 = seq_.load(std::memory_order_acquire);
            if (s1 & 1u) continue;
            for (std::size_t i = 0; i < kWords; ++i) buf[i] = words_[i].load(std::memory_order_relaxed);
            std::atomic_thread_fence(std::memory_order_acquire);
            if (seq_.load(std::memory_order_relaxed) != s1) continue;
            if (s1 == 0) return false;
            std::memcpy(&out, buf, sizeof(T));
            return true;
        }
    }

private:
    std::atomic<uint64_t> seq_{0};
    std::atomic<uint64_t> words_[kWords] = {};
};

// What the loop publishes after each tick. `tick` is written first and `tick_check` last in the
// struct, so a torn copy would show them different (the seqlock prevents it; tests check it).
struct ServoSnapshot {
    uint64_t tick = 0;
    double time_s = 0.0;       // since the loop's first tick (wall clock, CLOCK_MONOTONIC)
    Pose haptic;               // pose read from the device this tick, mapped to the world frame
    Pose graphic;              // the renderer's graphic pose
    Vec3 force_N{0.0};         // sent to the device (after the safety layer)
    Vec3 torque_Nm{0.0};
    // The renderer's wrench this tick (eq. 4, before the safety layer): what the probe presses on
    // the tooth or tissue with, whether or not the device renders it (a mouse renders nothing, a
    // fading safety layer less).
    Vec3 rendered_force_N{0.0};
    Vec3 rendered_torque_Nm{0.0};
    SafetyState safety = SafetyState::Idle;
    StepStatus status = StepStatus::Free;
    bool device_ok = false;    // read() gave a sample
    // Live figures for a UI. Ticks whose work ended after the next deadline, so far (this tick
    // included); the renderer step's wall time this tick (us; < 0 when no step ran); telemetry
    // samples dropped so far because the queue was full (ServoConfig::telemetry_queue).
    uint64_t deadline_misses = 0;
    float step_us = -1.0f;
    uint64_t telemetry_drops = 0;
    // UI and lesson events (ServoLoop::post_event) taken so far, this tick's included: the change
    // from the previous snapshot is how many were recorded at this tick, in the order posted.
    uint64_t events_taken = 0;
    uint64_t tick_check = 0;   // == tick
};

// The snapshot of one tick's work as the loop publishes it: tick, time, haptic and graphic pose,
// sent and rendered wrench, safety and step status, device_ok, step_us and tick_check. The
// counters (deadline_misses, telemetry_drops, events_taken) are left zero for the caller. The
// live loop and the headless replay both make theirs here, so a replay's snapshot equals the
// live one field by field.
ServoSnapshot make_snapshot(const ServoTick& work, const ServoTick::Out& out, uint64_t tick, double time_s) noexcept;

struct ServoConfig {
    double rate_hz = 1000.0;
    // Stop by itself after this long (s, wall clock from the first tick); <= 0: run until stop().
    double duration_s = 0.0;
    // Ask for SCHED_FIFO at this priority; a refusal is recorded (ServoLoop::realtime_message)
    // and the loop runs at normal priority.
    bool try_realtime = true;
    int realtime_priority = 80;
    // The safety layer's settings; its nominal_dt_s is set to 1 / rate_hz, and its force and torque
    // limits are cut to the device's (ServoLoop::safety_config() gives what was used).
    SafetyConfig safety;
    // Keep the first `trace_ticks` ticks as sent (the same TickSample handed to the recorder),
    // preallocated at start; 0 keeps none.
    std::size_t trace_ticks = 0;
    // Step-time samples kept (the latest ones, a ring).
    std::size_t step_time_ring = 1u << 16;
    // Device -> world map at the start. With `anchor`, its offset is replaced so that the device's
    // first reading lands on `anchor_position_m` (e.g. the scene's starting tool position).
    WorkspaceMap workspace;
    bool anchor = false;
    Vec3 anchor_position_m{0.0};
    // Commands (ServoLoop::post_event, set_workspace) that may wait between two ticks.
    std::size_t command_queue = 256;
    // At most this many queued commands are taken per tick; the rest wait for the next.
    int commands_per_tick = 8;
    // Telemetry: when > 0, every tick's snapshot is also queued (capacity rounded up to a power of
    // two, at most 1 << 20) for one consumer thread (ServoLoop::pop_telemetry), e.g. a UI that
    // drains it each frame to plot forces. The servo thread never waits for it: a full queue drops
    // the sample and counts it (ServoStats::telemetry_drops). 0: no telemetry.
    std::size_t telemetry_queue = 0;
    // Manual clock: start() prepares everything (device started, servo.begin recorded, step warmed
    // up, anchor applied) but spawns no thread; each ServoLoop::step_manual() runs one tick on the
    // caller's thread with time_s = tick / rate_hz, dt_s = 1 / rate_hz and no deadline missed.
    // try_realtime is ignored; period and jitter statistics stay zero. For headless runs and tests
    // that must be reproducible bit for bit.
    bool manual_clock = false;
};

// Period histogram: 0 .. 5 ms in 10 us bins, plus one overflow bin.
inline constexpr int kPeriodBinUs = 10;
inline constexpr int kPeriodBins = 500;
// Jitter |period - nominal| histogram: 0 .. 5 ms in 1 us bins, plus one overflow bin.
inline constexpr int kJitterBins = 5000;

struct PeriodPercentiles {
    double p50 = 0.0, p99 = 0.0, max = 0.0;
};

struct ServoStats {
    uint64_t ticks = 0;
    double elapsed_s = 0.0;          // first tick's wake to last tick's wake
    double achieved_rate_hz = 0.0;   // (ticks - 1) / elapsed_s
    double nominal_rate_hz = 0.0;
    PeriodPercentiles period_us;        // tick-to-tick wake period
    PeriodPercentiles jitter_us;        // |period - nominal period|
    PeriodPercentiles step_us;          // renderer step wall time (over the kept samples)
    uint64_t deadline_misses = 0;    // ticks whose work ended after the next deadline
    uint64_t skipped_slots = 0;      // deadlines dropped to catch up after an overrun
    uint64_t read_failures = 0;      // device.read() returned false
    uint64_t record_drops = 0;       // recorder.add_tick() refused (ring full)
    uint64_t event_drops = 0;        // recorder.add_event() refused (ring full or too long)
    uint64_t commands = 0;           // queued commands applied
    uint64_t events_taken = 0;       // of them, post_event commands (UI and lesson events)
    uint64_t telemetry_drops = 0;    // telemetry samples dropped (queue full)
    std::array<uint64_t, kStepStatusCount> status_counts{};
    std::array<uint64_t, 6> safety_counts{};  // ticks per SafetyState (enum order)
    double max_force_sent_N = 0.0;
    double max_torque_sent_Nm = 0.0;
    bool non_finite_sent = false;    // a non-finite force or torque was sent (must never be)
    std::array<uint64_t, kPeriodBins + 1> period_histogram{};  // [i]: i*10 .. (i+1)*10 us
    bool realtime = false;           // SCHED_FIFO was granted
    std::string realtime_message;    // why not, when not
};

class ServoLoop {
public:
    ServoLoop();
    ~ServoLoop();  // stops the loop if it runs
    ServoLoop(const ServoLoop&) = delete;
    ServoLoop& operator=(const ServoLoop&) = delete;

    // Starts the device (device.start()) and the servo thread, and returns once the thread has
    // set its priority and warmed the step up (first-call scratch), before its first tick. With
    // ServoConfig::manual_clock the same preparation happens on the calling thread and no thread
    // is started: the caller ticks with step_manual().
    // `model`, `device` and `recorder` (may be null; the caller opens it, runs its writer thread
    // and closes it after stop()) must outlive the loop. The renderer state starts at the
    // device's first pose. The device pose is used as the haptic pose in the world frame.
    // Returns "" or one line saying why the loop did not start.
    std::string start(const ServoConfig& config, Device& device, const Model& model,
                      RecordingWriter* recorder = nullptr);
    // Asks the loop to end, waits for it, sends one zero wrench and stops the device. In manual
    // mode there is no thread to wait for; the rest is the same.
    void stop();
    // Waits for a loop with a duration to end by itself, then as stop(). In manual mode: as stop().
    void wait();
    bool running() const noexcept { return running_.load(std::memory_order_acquire); }

    // Manual clock only (ServoConfig::manual_clock): runs exactly one tick on the calling thread,
    // the threaded loop's own tick body (commands, device, step, safety, recording, trace,
    // telemetry, latest(), statistics), with time_s = tick / rate_hz, dt_s = 1 / rate_hz and
    // deadline_missed = false; never sleeps. False, and no tick, when the loop was not started in
    // manual mode, after stop(), or once tick / rate_hz reaches a positive duration_s (the loop
    // then counts as ended, as the threaded one does). Not concurrently with start() or stop().
    bool step_manual() noexcept;
    bool manual() const noexcept { return manual_active_; }

    // The latest tick's outcome; false before the first tick. Lock-free, any thread.
    bool latest(ServoSnapshot& out) const noexcept { return published_.load(out); }
    // Consumer side of the telemetry queue (ServoConfig::telemetry_queue; one thread only): the
    // oldest tick not yet taken, in tick order; false when empty or telemetry is off. What is left
    // after stop() can still be drained; a new start() discards it (no pop may run during start()).
    bool pop_telemetry(ServoSnapshot& out) noexcept { return telemetry_ && telemetry_->pop(out); }
    // Set once start() has returned; "" when SCHED_FIFO was granted (or not asked for).
    const std::string& realtime_message() const noexcept { return realtime_message_; }
    bool realtime() const noexcept { return realtime_; }
    // Producer side of the command queue (one thread: the UI's or the lesson's). Each returns ""
    // or one line saying why the command was refused (bad command, loop not running, queue full);
    // a refused command is not applied and not recorded. The event is recorded at the tick that
    // takes it; the map applies from that tick on.
    std::string post_event(std::string_view kind, std::string_view json);
    std::string set_workspace(const WorkspaceMap& map);
    // Latch the emergency stop / ask the safety layer to clear its latches, at the next tick;
    // never refused, lock-free, any thread. Both are recorded at the tick that takes them.
    void emergency_stop() noexcept { estop_request_.store(true, std::memory_order_release); }
    void reset_safety() noexcept { reset_request_.store(true, std::memory_order_release); }
    SafetyState safety_state() const noexcept { return safety_ ? safety_->state() : SafetyState::Idle; }
    // The safety settings in force (after start(): the device's limits applied).
    const SafetyConfig& safety_config() const noexcept { return config_.safety; }

    // Statistics of the last run; meaningful after stop() or wait().
    ServoStats stats() const;
    // The kept ticks (ServoConfig::trace_ticks), in order; valid after stop().
    const std::vector<TickSample>& trace() const noexcept { return trace_; }
    std::size_t trace_size() const noexcept { return trace_count_; }

private:
    void run() noexcept;
    // Before the first tick, on the thread that will tick: the renderer state at the device's
    // first pose (anchored when asked), the warm-up step, and the servo.begin event.
    void prepare() noexcept;
    // One tick's work, shared by the threaded loop and step_manual(): commands, device -> step ->
    // safety -> device, statistics, recording, trace, deadline check, telemetry and publication.
    // `overrun_at_ns` > 0: the work overran when it ended after that time (threaded loop; `end_ns`
    // gets the end time); 0: no deadline (manual clock). Returns whether the work overran.
    bool tick_body(uint64_t tick, double time_s, double dt_s, bool missed, int64_t overrun_at_ns,
                   int64_t& end_ns) noexcept;
    void finish();
    std::string push(const ServoCommand& command);
    void record_event(uint64_t tick, std::string_view kind, std::string_view json) noexcept;

    ServoConfig config_;
    Device* device_ = nullptr;
    const Model* model_ = nullptr;
    RecordingWriter* recorder_ = nullptr;
    std::unique_ptr<SafetyLayer> safety_;
    ServoTick work_;                // the tick's work (servo thread, or the manual caller)
    std::thread thread_;
    bool manual_active_ = false;    // started with manual_clock and not yet stopped
    uint64_t manual_tick_ = 0;      // the next manual tick's index
    std::atomic<bool> stop_request_{false};
    std::atomic<bool> running_{false};
    std::atomic<bool> ready_{false};
    std::atomic<bool> estop_request_{false};
    std::atomic<bool> reset_request_{false};
    std::unique_ptr<SpscQueue<ServoCommand>> commands_;
    std::unique_ptr<SpscQueue<ServoSnapshot>> telemetry_;  // null when telemetry is off
    std::string begin_text_;        // the servo.begin event, made at start()
    ServoCommand command_scratch_;  // servo thread: the command being applied (1 KiB, off the stack)
    Seqlock<ServoSnapshot> published_;
    bool realtime_ = false;
    std::string realtime_message_;

    // Servo-thread data, sized at start().
    std::vector<TickSample> trace_;
    std::size_t trace_count_ = 0;
    std::vector<float> step_us_ring_;
    uint64_t step_samples_ = 0;
    std::array<uint64_t, kPeriodBins + 1> period_hist_{};
    std::vector<uint32_t> jitter_hist_;  // kJitterBins + 1
    double period_max_us_ = 0.0;
    double jitter_max_us_ = 0.0;
    double step_max_us_ = 0.0;
    int64_t first_wake_ns_ = 0;
    int64_t last_wake_ns_ = 0;
    ServoStats counts_;  // the counters part, filled by the servo thread
};

}  // namespace sulcus
