#include "sulcus/haptics/replay_device.h"

#include "sulcus/haptics/servo_loop.h"

#include <cmath>
#include <cstring>

namespace sulcus {

ReplayDevice::ReplayDevice(const RecordingRead& recording) { init(recording); }

ReplayDevice::ReplayDevice(const std::string& path) { init(read_recording(path)); }

void ReplayDevice::init(const RecordingRead& recording) {
    caps_.name = "replay";
    caps_.input_dof = 6;   // the recorded pose is a full pose
    caps_.output_dof = 6;  // force and torque are both stored
    const double rate = recording.metadata.rate_hz;
    caps_.nominal_rate_Hz = rate > 0.0 && std::isfinite(rate) ? rate : 1000.0;
    dt_s_ = 1.0 / caps_.nominal_rate_Hz;
    if (!recording.ok()) {
        error_ = "replay: " + recording.error;
        return;
    }
    ticks_ = recording.ticks;
    forces_.assign(ticks_.size(), Vec3(0.0));
    torques_.assign(ticks_.size(), Vec3(0.0));
}

std::string ReplayDevice::start() {
    if (!error_.empty()) return error_;
    if (ticks_.empty()) return "replay: the recording holds no ticks";
    cursor_ = 0;
    writes_past_end_ = 0;
    for (std::size_t i = 0; i < ticks_.size(); ++i) forces_[i] = torques_[i] = Vec3(0.0);
    running_ = true;
    return "";
}

bool ReplayDevice::read(DeviceSample& sample) noexcept {
    if (!running_) {
        sample.connected = false;
        sample.fault = kDeviceFaultNotStarted;
        return false;
    }
    // Past the end the stylus rests where it was last seen.
    const std::size_t i = cursor_ < ticks_.size() ? cursor_ : ticks_.size() - 1;
    const TickSample& t = ticks_[i];
    sample.pose = t.device_pose;
    sample.buttons = t.buttons;
    // Not recorded: a backward difference of the recorded positions stands in for it.
    sample.linear_velocity_m_per_s =
        i > 0 && cursor_ < ticks_.size() ? (t.device_pose.position - ticks_[i - 1].device_pose.position) / dt_s_
                                         : Vec3(0.0);
    sample.connected = t.connected;
    sample.fault = t.device_fault;
    return t.device_read;
}

void ReplayDevice::write(const Vec3& force_N, const Vec3& torque_Nm) noexcept {
    if (!running_) return;
    if (cursor_ >= ticks_.size()) {
        ++writes_past_end_;
        return;
    }
    forces_[cursor_] = force_N;
    torques_[cursor_] = torque_Nm;
    ++cursor_;
}

void ReplayDevice::stop() { running_ = false; }

ReplayResult replay_recording(const RecordingRead& recording, const Model& model, const SafetyConfig& safety_config) {
    return replay_recording(recording, model, safety_config, ReplayObserver{});
}

ReplayResult replay_recording(const RecordingRead& recording, const Model& model, const SafetyConfig& safety_config,
                              const ReplayObserver& observer) {
    ReplayResult r;
    const double rate_hz = recording.metadata.rate_hz;
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz) || rate_hz > 100000.0) {
        r.error = "replay: rate_hz must be in (0, 100000]";
        return r;
    }
    ReplayDevice dev(recording);
    if (std::string err = dev.start(); !err.empty()) {
        r.error = err;
        return r;
    }
    const std::size_t n = dev.tick_count();
    r.status.assign(n, StepStatus::Held);
    r.safety.assign(n, SafetyState::Idle);

    SafetyConfig cfg = safety_config;
    const double dt_s = 1.0 / rate_hz;
    cfg.nominal_dt_s = dt_s;  // as ServoLoop::start

    // The servo commands as recorded: the starting map and safety settings, then each command
    // before its tick's work.
    std::vector<const RecordingEvent*> commands;
    std::vector<const RecordingEvent*> ui_events;  // for the observer
    WorkspaceMap start_map;
    bool begun = false;
    for (const RecordingEvent& e : recording.events) {
        if (!is_servo_event(e.kind)) {
            ui_events.push_back(&e);
            continue;
        }
        if (e.kind == kEventServoBegin && !begun) {
            bool has_safety = false;
            SafetyConfig recorded;
            if (std::string err = parse_servo_begin(e.json, start_map, recorded, has_safety); !err.empty()) {
                r.error = "replay: event servo.begin: " + err;
                return r;
            }
            if (has_safety) cfg = recorded;
            begun = true;
            continue;
        }
        commands.push_back(&e);
    }
    SafetyLayer safety(cfg);

    // The servo loop's own tick with the recorded clock and device state (a version-1 recording
    // has no clock: every tick lasts 1 / rate and no deadline is missed).
    ServoTick work;
    work.begin(dev, model, start_map);
    std::size_t next = 0;
    std::size_t next_ui = 0;
    uint64_t misses = 0;
    const std::vector<TickSample>& rec = dev.recorded();
    for (std::size_t tick = 0; tick < n; ++tick) {
        for (; next < commands.size() && commands[next]->tick <= rec[tick].tick; ++next) {
            const RecordingEvent& e = *commands[next];
            if (e.kind == kEventServoEStop) {
                safety.emergency_stop();
            } else if (e.kind == kEventServoReset) {
                safety.reset();
            } else if (e.kind == kEventServoWorkspace) {
                WorkspaceMap m;
                if (std::string err = parse_workspace(e.json, m); !err.empty()) {
                    r.error = "replay: event servo.workspace at tick " + std::to_string(e.tick) + ": " + err;
                    return r;
                }
                work.set_workspace(m);
            }
        }
        // The UI and lesson events the loop took at this tick, before its work, as live.
        for (; next_ui < ui_events.size() && ui_events[next_ui]->tick <= rec[tick].tick; ++next_ui)
            if (observer.on_event) observer.on_event(*ui_events[next_ui]);
        const double tick_dt_s = rec[tick].dt_s > 0.0 ? rec[tick].dt_s : dt_s;
        const ServoTick::Out out = work.run(dev, model, safety, rec[tick].deadline_missed, tick_dt_s);
        r.status[tick] = work.result().status;
        r.safety[tick] = out.sent.state;
        if (rec[tick].deadline_missed) ++misses;
        if (observer.on_tick) {
            ServoSnapshot snap = make_snapshot(work, out, rec[tick].tick, rec[tick].time_s);
            snap.step_us = rec[tick].step_us;  // the live step's wall time, not this one's
            snap.deadline_misses = misses;
            snap.events_taken = next_ui;
            observer.on_tick(snap);
        }
    }
    for (; next_ui < ui_events.size(); ++next_ui)  // past the last tick
        if (observer.on_event) observer.on_event(*ui_events[next_ui]);
    dev.stop();

    r.force_N = dev.forces_written();
    r.torque_Nm = dev.torques_written();
    for (std::size_t i = 0; i < n && r.first_mismatch < 0; ++i) {
        const TickSample& t = dev.recorded()[i];
        if (std::memcmp(&t.force_N, &r.force_N[i], sizeof(Vec3)) != 0 ||
            std::memcmp(&t.torque_Nm, &r.torque_Nm[i], sizeof(Vec3)) != 0 || t.status != r.status[i])
            r.first_mismatch = static_cast<int64_t>(i);
    }
    return r;
}

}  // namespace sulcus
