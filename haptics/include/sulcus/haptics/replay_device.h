// Replay of a recorded session (sulcus.recording/2): a Device that plays back the recorded
// device poses and buttons, and a headless, deterministic replay of the servo tick over a whole
// recording, so a session's forces can be recomputed and compared bit for bit with what was sent.
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/haptics/device.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/safety.h"
#include "sulcus/haptics/servo_loop.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace sulcus {

// Plays a recording back as a device. The tick cursor advances on write(): read() gives the
// pose and buttons of the tick not yet answered, so a read with no write in between (the servo
// loop's read before its first tick) sees the same tick again, as with a real device whose
// stylus has not moved. After the last tick has been written, read() keeps giving the last pose
// and finished() is true; further writes are counted, not stored. The recording carries no
// connection state or fault, so every sample is connected and fault-free. No allocation in
// read() or write(): the force and torque stores are sized to the recording at construction.
class ReplayDevice final : public Device {
public:
    explicit ReplayDevice(const RecordingRead& recording);
    // Reads the file; error() says why when it cannot (start() then fails with it).
    explicit ReplayDevice(const std::string& path);

    const DeviceCapabilities& capabilities() const override { return caps_; }
    // Rewinds to the first tick and clears the stored forces; fails on an unread or empty recording.
    std::string start() override;
    bool read(DeviceSample& sample) noexcept override;
    void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept override;
    void stop() override;

    const std::string& error() const noexcept { return error_; }
    std::size_t tick_count() const noexcept { return ticks_.size(); }
    // Index of the tick the next read() gives (== tick_count() once finished).
    std::size_t cursor() const noexcept { return cursor_; }
    bool finished() const noexcept { return !ticks_.empty() && cursor_ >= ticks_.size(); }
    const std::vector<TickSample>& recorded() const noexcept { return ticks_; }
    // What was written at each tick, by tick index; only the first writes_stored() are meaningful.
    const std::vector<Vec3>& forces_written() const noexcept { return forces_; }
    const std::vector<Vec3>& torques_written() const noexcept { return torques_; }
    std::size_t writes_stored() const noexcept { return cursor_; }
    uint64_t writes_past_end() const noexcept { return writes_past_end_; }

private:
    void init(const RecordingRead& recording);

    DeviceCapabilities caps_;
    std::string error_;
    std::vector<TickSample> ticks_;
    std::vector<Vec3> forces_;
    std::vector<Vec3> torques_;
    std::size_t cursor_ = 0;
    uint64_t writes_past_end_ = 0;
    double dt_s_ = 1e-3;
    bool running_ = false;
};

// The outcome of replaying every tick of a recording.
struct ReplayResult {
    std::string error;                // empty when the replay ran
    std::vector<Vec3> force_N;        // sent at each recorded tick (after the safety layer)
    std::vector<Vec3> torque_Nm;
    std::vector<StepStatus> status;   // the step's status at each tick
    std::vector<SafetyState> safety;  // the safety layer's state at each tick
    // First tick whose replayed force, torque or status differs from the recording (force and
    // torque compared bit for bit); -1 when none does.
    int64_t first_mismatch = -1;
    bool ok() const { return error.empty(); }
};

// Runs the servo loop's tick (device read -> workspace map -> step -> safety layer -> device
// write) once per recorded tick, in order, on the calling thread with no clock: the renderer
// state starts at the first tick's pose under the recorded starting map (servo.begin), each tick
// gets its recorded length, deadline flag and device state, and the recorded servo commands
// (workspace changes, emergency stop, safety reset) are applied before the tick they were taken
// at. The safety settings are the recorded ones (servo.begin); `safety` stands in for a recording
// without them, with its nominal_dt_s replaced by 1 / rate, as the loop does. Deterministic: the same
// recording and model give the same result, bit for bit.
ReplayResult replay_recording(const RecordingRead& recording, const Model& model, const SafetyConfig& safety);

// What a replay shows a consumer (a lesson runtime recomputing scores) tick by tick: the same
// stream the live loop gives through its telemetry and post_event. Either callback may be empty.
struct ReplayObserver {
    // A UI or lesson event (kind not starting with "servo."), in file order, after the servo
    // commands of the tick it belongs to and before that tick's work. An event whose tick is past
    // the last recorded tick comes after the last on_tick.
    std::function<void(const RecordingEvent&)> on_event;
    // After each tick's work: the snapshot the live loop published for it (make_snapshot), with
    // tick, time_s and step_us as recorded, events_taken = UI and lesson events delivered so far,
    // deadline_misses = recorded ticks flagged deadline_missed so far, telemetry_drops = 0.
    std::function<void(const ServoSnapshot&)> on_tick;
};

// As above, and tells `observer` of every event and tick as it goes.
ReplayResult replay_recording(const RecordingRead& recording, const Model& model, const SafetyConfig& safety,
                              const ReplayObserver& observer);

}  // namespace sulcus
