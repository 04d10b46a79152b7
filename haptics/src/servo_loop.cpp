#include "sulcus/haptics/servo_loop.h"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace sulcus {
namespace {

int64_t now_ns() noexcept {
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleep_until_ns(int64_t t_ns) noexcept {
    timespec ts;
    ts.tv_sec = static_cast<time_t>(t_ns / 1000000000);
    ts.tv_nsec = static_cast<long>(t_ns % 1000000000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
}

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Percentile of a histogram with `bin_us`-wide bins (the bin's upper edge), capped at `max`.
template <class H>
double hist_percentile(const H& hist, std::size_t bins, double bin_us, double q, double max_us) {
    uint64_t total = 0;
    for (std::size_t i = 0; i < bins; ++i) total += hist[i];
    if (total == 0) return 0.0;
    const uint64_t rank = static_cast<uint64_t>(std::ceil(q * static_cast<double>(total)));
    uint64_t seen = 0;
    for (std::size_t i = 0; i < bins; ++i) {
        seen += hist[i];
        if (seen >= std::max<uint64_t>(rank, 1)) return std::min((static_cast<double>(i) + 1.0) * bin_us, max_us);
    }
    return max_us;
}

}  // namespace

ServoLoop::ServoLoop() = default;

ServoLoop::~ServoLoop() { stop(); }

std::string ServoLoop::start(const ServoConfig& config, Device& device, const Model& model,
                             RecordingWriter* recorder) {
    if (thread_.joinable() || manual_active_) return "servo: the loop is already running";
    if (!(config.rate_hz > 0.0) || !std::isfinite(config.rate_hz) || config.rate_hz > 100000.0)
        return "servo: rate_hz must be in (0, 100000]";
    if (!valid_workspace(config.workspace)) return "servo: workspace offset must be finite and scale in [0.001, 1000]";
    if (config.command_queue < 1 || config.command_queue > (1u << 16) || config.commands_per_tick < 1)
        return "servo: command_queue must be 1..65536 and commands_per_tick at least 1";
    if (config.telemetry_queue > (1u << 20)) return "servo: telemetry_queue must be 0..1048576";
    config_ = config;
    config_.safety.nominal_dt_s = 1.0 / config_.rate_hz;
    config_.step_time_ring = std::max<std::size_t>(config_.step_time_ring, 1);
    device_ = &device;
    model_ = &model;
    recorder_ = recorder;

    const std::string err = device.start();
    if (!err.empty()) return err;
    // The device's own limits bound the safety layer's: never more force than its peak, and no
    // torque where it has no actuated gimbal.
    const DeviceCapabilities& caps = device.capabilities();
    if (caps.max_force_N > 0.0)
        config_.safety.limits.max_force_N = std::min(config_.safety.limits.max_force_N, caps.max_force_N);
    if (caps.output_dof > 0 && caps.output_dof < 6) config_.safety.limits.max_torque_Nm = 0.0;
    else if (caps.max_torque_Nm > 0.0)
        config_.safety.limits.max_torque_Nm = std::min(config_.safety.limits.max_torque_Nm, caps.max_torque_Nm);
    begin_text_ = format_servo_begin(config_.workspace, config_.safety);

    // Everything the ticks touch is allocated here.
    safety_ = std::make_unique<SafetyLayer>(config_.safety);
    commands_ = std::make_unique<SpscQueue<ServoCommand>>(config_.command_queue);
    telemetry_.reset();
    if (config_.telemetry_queue > 0) telemetry_ = std::make_unique<SpscQueue<ServoSnapshot>>(config_.telemetry_queue);
    estop_request_.store(false);
    reset_request_.store(false);
    trace_.assign(config_.trace_ticks, TickSample{});
    trace_count_ = 0;
    step_us_ring_.assign(config_.step_time_ring, 0.0f);
    step_samples_ = 0;
    period_hist_.fill(0);
    jitter_hist_.assign(kJitterBins + 1, 0);
    period_max_us_ = jitter_max_us_ = step_max_us_ = 0.0;
    first_wake_ns_ = last_wake_ns_ = 0;
    counts_ = ServoStats{};
    realtime_ = false;
    realtime_message_.clear();
    stop_request_.store(false);
    ready_.store(false);
    running_.store(true, std::memory_order_release);

    if (config_.manual_clock) {
        // No thread: the caller ticks. The same preparation as the servo thread's, here.
        realtime_message_ = "manual clock: no servo thread";
        prepare();
        manual_tick_ = 0;
        manual_active_ = true;
        ready_.store(true, std::memory_order_release);
        return "";
    }

    // The thread sets its own priority and warms up, then waits for the go from here, so the
    // priority message is readable once start() returns.
    thread_ = std::thread([this] { run(); });
    while (!ready_.load(std::memory_order_acquire)) std::this_thread::yield();
    return "";
}

void ServoTick::begin(Device& device, const Model& model, const WorkspaceMap& map, const Vec3* anchor) noexcept {
    device.read(sample_);
    map_ = anchor ? anchored_workspace(map.scale, sample_.pose.position, *anchor) : map;
    haptic_ = map_device_pose(map_, sample_.pose);
    state_ = make_state(haptic_);
    {
        State warm = state_;
        (void)step(model, warm, haptic_);
    }
    result_ = StepResult{};
    result_.graphic = state_.graphic;
    result_.status = StepStatus::Held;
}

ServoTick::Out ServoTick::run(Device& device, const Model& model, SafetyLayer& safety, bool deadline_missed,
                              double dt_s) noexcept {
    Out o;
    o.read_ok = device.read(sample_);
    if (o.read_ok) {
        haptic_ = map_device_pose(map_, sample_.pose);
        const int64_t s0 = now_ns();
        result_ = step(model, state_, haptic_);
        o.step_us = static_cast<double>(now_ns() - s0) * 1e-3;
    }
    o.step_ok = o.read_ok && result_.status != StepStatus::Held && result_.status != StepStatus::BadInput;
    SafetyInput in;
    in.force_N = result_.force_N;
    in.torque_Nm = result_.torque_Nm;
    in.step_ok = o.step_ok;
    in.deadline_missed = deadline_missed;
    in.device_connected = sample_.connected;
    in.device_fault = sample_.fault != kDeviceFaultNone;
    in.dt_s = dt_s;
    o.sent = safety.tick(in);
    device.write(o.sent.force_N, o.sent.torque_Nm);
    return o;
}

void ServoLoop::run() noexcept {
    if (config_.try_realtime) {
        sched_param sp{};
        const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
        sp.sched_priority = std::clamp(config_.realtime_priority, lo, hi);
        const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
        if (rc == 0) {
            realtime_ = true;
        } else {
            realtime_message_ = std::string("SCHED_FIFO refused (") + std::strerror(rc) +
                                "): the servo thread runs at normal priority";
        }
    } else {
        realtime_message_ = "SCHED_FIFO not requested";
    }

    prepare();
    ready_.store(true, std::memory_order_release);

    const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / config_.rate_hz));
    const double nominal_us = static_cast<double>(period_ns) * 1e-3;
    const int64_t duration_ns =
        config_.duration_s > 0.0 ? static_cast<int64_t>(std::llround(config_.duration_s * 1e9)) : 0;
    const int64_t start_ns = now_ns() + period_ns;
    int64_t deadline = start_ns;
    int64_t prev_wake = 0;
    bool prev_overran = false;
    uint64_t tick = 0;

    while (!stop_request_.load(std::memory_order_relaxed)) {
        sleep_until_ns(deadline);
        const int64_t wake = now_ns();
        if (duration_ns > 0 && wake - start_ns >= duration_ns) break;
        const bool late_wake = wake - deadline > period_ns;

        // Period statistics.
        if (tick == 0) {
            first_wake_ns_ = wake;
        } else {
            const double period_us = static_cast<double>(wake - prev_wake) * 1e-3;
            const auto pbin = static_cast<std::size_t>(std::min(period_us / kPeriodBinUs, double(kPeriodBins)));
            ++period_hist_[pbin];
            period_max_us_ = std::max(period_max_us_, period_us);
            const double jitter_us = std::fabs(period_us - nominal_us);
            const auto jbin = static_cast<std::size_t>(std::min(jitter_us, double(kJitterBins)));
            ++jitter_hist_[jbin];
            jitter_max_us_ = std::max(jitter_max_us_, jitter_us);
        }
        const double dt_s = tick == 0 ? 1.0 / config_.rate_hz : static_cast<double>(wake - prev_wake) * 1e-9;
        prev_wake = wake;
        last_wake_ns_ = wake;

        // The work must end before the next deadline.
        const double time_s = static_cast<double>(wake - first_wake_ns_) * 1e-9;
        int64_t end = 0;
        prev_overran = tick_body(tick, time_s, dt_s, late_wake || prev_overran, deadline + period_ns, end);
        ++tick;

        // After an overrun the missed slots are dropped rather than run back to back.
        deadline += period_ns;
        if (prev_overran) {
            const int64_t behind = end - deadline;
            const int64_t skip = behind / period_ns + 1;
            if (skip > 1) {
                deadline += (skip - 1) * period_ns;
                counts_.skipped_slots += static_cast<uint64_t>(skip - 1);
            }
        }
    }
    counts_.ticks = tick;
    running_.store(false, std::memory_order_release);
}

void ServoLoop::prepare() noexcept {
    work_.begin(*device_, *model_, config_.workspace, config_.anchor ? &config_.anchor_position_m : nullptr);
    if (config_.anchor) begin_text_ = format_servo_begin(work_.workspace(), config_.safety);  // the anchored map
    record_event(0, kEventServoBegin, begin_text_);
}

ServoSnapshot make_snapshot(const ServoTick& work, const ServoTick::Out& out, uint64_t tick, double time_s) noexcept {
    const StepResult& result = work.result();
    ServoSnapshot snap;
    snap.tick = tick;
    snap.time_s = time_s;
    snap.haptic = work.haptic();
    snap.graphic = result.graphic;
    snap.force_N = out.sent.force_N;
    snap.torque_Nm = out.sent.torque_Nm;
    snap.rendered_force_N = result.force_N;
    snap.rendered_torque_Nm = result.torque_Nm;
    snap.safety = out.sent.state;
    snap.status = result.status;
    snap.device_ok = out.read_ok;
    snap.step_us = static_cast<float>(out.step_us);
    snap.tick_check = tick;
    return snap;
}

bool ServoLoop::tick_body(uint64_t tick, double time_s, double dt_s, bool missed, int64_t overrun_at_ns,
                          int64_t& end_ns) noexcept {
    Device& dev = *device_;
    const Model& model = *model_;
    SafetyLayer& safety = *safety_;
    ServoTick& work = work_;
    char map_text[160];

    // Requests from other threads, applied (and recorded) before this tick's work.
    if (estop_request_.exchange(false, std::memory_order_acq_rel)) {
        safety.emergency_stop();
        record_event(tick, kEventServoEStop, "{}");
    }
    if (reset_request_.exchange(false, std::memory_order_acq_rel)) {
        safety.reset();
        record_event(tick, kEventServoReset, "{}");
    }
    for (int c = 0; c < config_.commands_per_tick; ++c) {
        ServoCommand& cmd = command_scratch_;
        if (!commands_->pop(cmd)) break;
        ++counts_.commands;
        if (cmd.type == ServoCommandKind::SetWorkspace) {
            work.set_workspace(cmd.workspace);
            record_event(tick, kEventServoWorkspace,
                         std::string_view(map_text, format_workspace(cmd.workspace, map_text, sizeof map_text)));
        } else {
            ++counts_.events_taken;
            record_event(tick, cmd.kind_view(), cmd.text_view());
        }
    }

    // Device -> step -> safety -> device.
    const ServoTick::Out o = work.run(dev, model, safety, missed, dt_s);
    const DeviceSample& sample = work.sample();
    const StepResult& result = work.result();
    const SafetyOutput& out = o.sent;
    if (!o.read_ok) ++counts_.read_failures;
    if (o.step_us >= 0.0) {
        step_us_ring_[step_samples_ % step_us_ring_.size()] = static_cast<float>(o.step_us);
        ++step_samples_;
        step_max_us_ = std::max(step_max_us_, o.step_us);
    }
    ++counts_.status_counts[static_cast<std::size_t>(result.status)];
    ++counts_.safety_counts[static_cast<std::size_t>(out.state)];
    if (!finite(out.force_N) || !finite(out.torque_Nm)) counts_.non_finite_sent = true;
    counts_.max_force_sent_N = std::max(counts_.max_force_sent_N, glm::length(out.force_N));
    counts_.max_torque_sent_Nm = std::max(counts_.max_torque_sent_Nm, glm::length(out.torque_Nm));

    // Record.
    TickSample ts;
    ts.tick = tick;
    ts.time_s = time_s;
    ts.device_pose = sample.pose;
    ts.buttons = sample.buttons;
    ts.force_N = out.force_N;
    ts.torque_Nm = out.torque_Nm;
    ts.status = result.status;
    ts.dt_s = dt_s;
    ts.device_fault = sample.fault;
    ts.device_read = o.read_ok;
    ts.connected = sample.connected;
    ts.deadline_missed = missed;
    ts.safety_state = static_cast<uint8_t>(out.state);
    ts.step_us = static_cast<float>(o.step_us);
    if (recorder_ && !recorder_->add_tick(ts)) ++counts_.record_drops;
    if (trace_count_ < trace_.size()) trace_[trace_count_++] = ts;

    // Deadline check: the work must end before the next deadline. Judged before publishing
    // (the only step after it), so the snapshot's miss count includes this tick.
    bool overran = false;
    if (overrun_at_ns > 0) {
        end_ns = now_ns();
        overran = end_ns > overrun_at_ns;
        if (overran) ++counts_.deadline_misses;
    }

    // Publish.
    ServoSnapshot snap = make_snapshot(work, o, tick, time_s);
    snap.deadline_misses = counts_.deadline_misses;
    snap.telemetry_drops = counts_.telemetry_drops;
    snap.events_taken = counts_.events_taken;
    // A queued sample carries the drops before it; the published one also counts its own.
    if (telemetry_ && !telemetry_->push(snap)) snap.telemetry_drops = ++counts_.telemetry_drops;
    published_.store(snap);
    return overran;
}

bool ServoLoop::step_manual() noexcept {
    if (!manual_active_ || !running_.load(std::memory_order_relaxed)) return false;
    const uint64_t tick = manual_tick_;
    const double time_s = static_cast<double>(tick) / config_.rate_hz;
    if (config_.duration_s > 0.0 && time_s >= config_.duration_s) {
        running_.store(false, std::memory_order_release);  // ended by its duration, as the thread would
        return false;
    }
    int64_t end = 0;
    (void)tick_body(tick, time_s, 1.0 / config_.rate_hz, false, 0, end);
    manual_tick_ = tick + 1;
    counts_.ticks = manual_tick_;
    return true;
}

void ServoLoop::record_event(uint64_t tick, std::string_view kind, std::string_view json) noexcept {
    if (recorder_ && !recorder_->add_event(tick, kind, json)) ++counts_.event_drops;
}

std::string ServoLoop::push(const ServoCommand& command) {
    if (!commands_ || !running()) return "servo: the loop is not running";
    if (!commands_->push(command))
        return "servo: command queue full (" + std::to_string(commands_->capacity()) + " waiting)";
    return "";
}

std::string ServoLoop::post_event(std::string_view kind, std::string_view json) {
    ServoCommand c;
    if (std::string err = make_event_command(kind, json, c); !err.empty()) return err;
    return push(c);
}

std::string ServoLoop::set_workspace(const WorkspaceMap& map) {
    ServoCommand c;
    if (std::string err = make_workspace_command(map, c); !err.empty()) return err;
    return push(c);
}

void ServoLoop::finish() {
    if (manual_active_) {
        manual_active_ = false;
        running_.store(false, std::memory_order_release);
    } else if (thread_.joinable()) {
        thread_.join();
    } else {
        return;
    }
    if (device_) {
        device_->write(Vec3(0.0), Vec3(0.0));
        device_->stop();
    }
}

void ServoLoop::stop() {
    stop_request_.store(true, std::memory_order_relaxed);
    finish();
}

void ServoLoop::wait() {
    if (config_.duration_s <= 0.0) stop_request_.store(true, std::memory_order_relaxed);
    finish();
}

ServoStats ServoLoop::stats() const {
    ServoStats s = counts_;
    s.nominal_rate_hz = config_.rate_hz;
    s.elapsed_s = static_cast<double>(last_wake_ns_ - first_wake_ns_) * 1e-9;
    s.achieved_rate_hz = s.ticks > 1 && s.elapsed_s > 0.0 ? static_cast<double>(s.ticks - 1) / s.elapsed_s : 0.0;
    s.period_histogram = period_hist_;
    s.period_us.p50 = hist_percentile(period_hist_, period_hist_.size(), kPeriodBinUs, 0.5, period_max_us_);
    s.period_us.p99 = hist_percentile(period_hist_, period_hist_.size(), kPeriodBinUs, 0.99, period_max_us_);
    s.period_us.max = period_max_us_;
    s.jitter_us.p50 = hist_percentile(jitter_hist_, jitter_hist_.size(), 1.0, 0.5, jitter_max_us_);
    s.jitter_us.p99 = hist_percentile(jitter_hist_, jitter_hist_.size(), 1.0, 0.99, jitter_max_us_);
    s.jitter_us.max = jitter_max_us_;
    const std::size_t n = static_cast<std::size_t>(std::min<uint64_t>(step_samples_, step_us_ring_.size()));
    if (n > 0) {
        std::vector<float> v(step_us_ring_.begin(), step_us_ring_.begin() + static_cast<std::ptrdiff_t>(n));
        std::sort(v.begin(), v.end());
        auto at = [&](double q) {
            const std::size_t i = std::min(n - 1, static_cast<std::size_t>(std::ceil(q * double(n))) - (q > 0 ? 1 : 0));
            return static_cast<double>(v[i]);
        };
        s.step_us.p50 = at(0.5);
        s.step_us.p99 = at(0.99);
        s.step_us.max = step_max_us_;
    }
    s.realtime = realtime_;
    s.realtime_message = realtime_message_;
    return s;
}

}  // namespace sulcus
