// The per-tick safety state machine: engage, ramp in, pass through, fade on stall, and the
// immediate zeros (disconnect, fault, e-stop). Rules and defaults: docs/safety.md.
#include "sulcus/haptics/safety.h"

#include <algorithm>
#include <cmath>

namespace sulcus {
namespace {

// Timers accumulate dt; this absorbs the rounding of summing 0.001 s many times.
constexpr double kTimeEps_s = 1e-9;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A usable duration or threshold: NaN and non-positive values become 0.
double usable(double x) { return x > 0.0 ? x : 0.0; }

// Length that does not overflow for huge finite components.
double length(const Vec3& v) {
    const double m = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (m == 0.0) return 0.0;
    const Vec3 u = v / m;
    return m * std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
}

bool is_zero(const Vec3& v) { return v.x == 0.0 && v.y == 0.0 && v.z == 0.0; }

}  // namespace

const char* to_string(SafetyState s) noexcept {
    switch (s) {
        case SafetyState::Idle: return "idle";
        case SafetyState::RampIn: return "ramp-in";
        case SafetyState::Active: return "active";
        case SafetyState::Fading: return "fading";
        case SafetyState::Faulted: return "faulted";
        case SafetyState::EStopped: return "e-stopped";
    }
    return "unknown";
}

SafetyLayer::SafetyLayer(const SafetyConfig& config) noexcept : config_(config) {}

void SafetyLayer::emergency_stop() noexcept { estop_request_.store(true, std::memory_order_release); }

void SafetyLayer::reset() noexcept { reset_request_.store(true, std::memory_order_release); }

void SafetyLayer::enter_idle() noexcept {
    state_ = SafetyState::Idle;
    engage_count_ = 0;
    ramp_elapsed_s_ = 0.0;
    fade_elapsed_s_ = 0.0;
    clear_s_ = 0.0;
}

// Safety first: these zeros skip the rate limit. A step from full force to zero in one tick is
// what the device's own protection does on a fault; keeping force on a device that has faulted,
// been unplugged or been e-stopped for even 50 ms is the worse risk.
SafetyOutput SafetyLayer::zero_now(SafetyOutput out, SafetyState s) noexcept {
    out.immediate_zero = true;
    out.force_N = Vec3(0.0);
    out.torque_Nm = Vec3(0.0);
    out.scale = 0.0;
    last_force_N_ = Vec3(0.0);
    last_torque_Nm_ = Vec3(0.0);
    if (s == SafetyState::Idle)
        enter_idle();
    else
        state_ = s;
    out.state = state_;
    published_state_.store(state_, std::memory_order_relaxed);
    return out;
}

SafetyOutput SafetyLayer::tick(const SafetyInput& in) noexcept {
    SafetyOutput out;
    const double nominal_dt = config_.nominal_dt_s > 0.0 ? config_.nominal_dt_s : 0.001;
    const double max_dt = config_.max_dt_s > 0.0 ? config_.max_dt_s : nominal_dt;
    const double dt = (std::isfinite(in.dt_s) && in.dt_s > 0.0) ? std::min(in.dt_s, max_dt) : nominal_dt;

    // A reset acts on the latches as they were; a new e-stop or fault in this same tick wins.
    if (reset_request_.exchange(false, std::memory_order_acq_rel)) {
        if (estop_latched_) {
            if (in.estop_button)
                out.reset_refused = true;
            else
                estop_latched_ = false;
        }
        if (fault_latched_) {
            if (in.device_fault || !in.device_connected)
                out.reset_refused = true;
            else
                fault_latched_ = false;
        }
        const bool was_latched = state_ == SafetyState::Faulted || state_ == SafetyState::EStopped;
        if (was_latched && !estop_latched_ && !fault_latched_) enter_idle();
    }
    if (estop_request_.exchange(false, std::memory_order_acq_rel) || in.estop_button) estop_latched_ = true;
    if (in.device_fault) fault_latched_ = true;
    out.estop = estop_latched_;
    out.fault = fault_latched_;

    if (estop_latched_) return zero_now(out, SafetyState::EStopped);
    if (fault_latched_) return zero_now(out, SafetyState::Faulted);
    if (!in.device_connected) {
        out.disconnected = true;
        return zero_now(out, SafetyState::Idle);
    }

    // Is the request trustworthy this tick?
    const bool is_finite = finite(in.force_N) && finite(in.torque_Nm);
    const double f_len = is_finite ? length(in.force_N) : 0.0;
    const double t_len = is_finite ? length(in.torque_Nm) : 0.0;
    out.non_finite_input = !is_finite;
    out.huge_input = is_finite && (!(f_len <= usable(config_.huge_force_N)) ||
                                   !(t_len <= usable(config_.huge_torque_Nm)));
    out.step_failed = !in.step_ok;
    miss_count_ = in.deadline_missed ? std::min(miss_count_ + 1, 1 << 30) : 0;
    out.deadline_stall = miss_count_ >= std::max(1, config_.stall_deadline_misses);
    const bool stall = out.non_finite_input || out.huge_input || out.step_failed || out.deadline_stall;
    // Cleared means a fully good tick: a single late step does not count toward recovery.
    const bool clear = !stall && !in.deadline_missed;

    Vec3 target_f(0.0), target_t(0.0);
    double scale = 0.0;
    bool fade_done = false;
    if ((state_ == SafetyState::RampIn || state_ == SafetyState::Active) && stall) {
        // Fade what was actually sent: the request itself cannot be trusted now.
        state_ = SafetyState::Fading;
        fade_from_force_N_ = last_force_N_;
        fade_from_torque_Nm_ = last_torque_Nm_;
        fade_elapsed_s_ = 0.0;
        clear_s_ = 0.0;
    }
    switch (state_) {
        case SafetyState::Idle: {
            const bool small = clear && f_len < usable(config_.engage_force_N) &&
                               t_len < usable(config_.engage_torque_Nm);
            engage_count_ = small ? engage_count_ + 1 : 0;
            if (engage_count_ >= std::max(1, config_.engage_ticks)) {
                // The ramp starts with the next tick.
                state_ = SafetyState::RampIn;
                engage_count_ = 0;
                ramp_elapsed_s_ = 0.0;
            }
            break;
        }
        case SafetyState::RampIn: {
            ramp_elapsed_s_ += dt;
            const double ramp = usable(config_.ramp_in_time_s);
            scale = 1.0;
            if (ramp > 0.0 && ramp_elapsed_s_ < ramp - kTimeEps_s) scale = ramp_elapsed_s_ / ramp;
            if (scale >= 1.0) state_ = SafetyState::Active;
            target_f = in.force_N * scale;
            target_t = in.torque_Nm * scale;
            break;
        }
        case SafetyState::Active:
            scale = 1.0;
            target_f = in.force_N;
            target_t = in.torque_Nm;
            break;
        case SafetyState::Fading: {
            clear_s_ = clear ? clear_s_ + dt : 0.0;
            fade_elapsed_s_ += dt;
            const double fade = usable(config_.fade_time_s);
            scale = 0.0;
            if (fade > 0.0 && fade_elapsed_s_ < fade - kTimeEps_s) scale = 1.0 - fade_elapsed_s_ / fade;
            target_f = fade_from_force_N_ * scale;
            target_t = fade_from_torque_Nm_ * scale;
            fade_done = scale == 0.0;
            break;
        }
        case SafetyState::Faulted:
        case SafetyState::EStopped:
            // Unreachable with the latches clear (a reset moves to Idle); send nothing.
            enter_idle();
            break;
    }

    const WrenchOut w = limit_wrench(config_.limits, target_f, target_t, last_force_N_, last_torque_Nm_, dt);
    out.force_N = w.force_N;
    out.torque_Nm = w.torque_Nm;
    out.force_clamped = w.force_clamped;
    out.torque_clamped = w.torque_clamped;
    out.rate_limited = w.rate_limited;
    out.scale = scale;
    last_force_N_ = w.force_N;
    last_torque_Nm_ = w.torque_Nm;

    // Recovery: only from a finished fade, after the stall has been clear for the hold-off.
    if (state_ == SafetyState::Fading && fade_done && clear && is_zero(w.force_N) && is_zero(w.torque_Nm) &&
        clear_s_ >= usable(config_.recover_hold_off_s) - kTimeEps_s) {
        state_ = SafetyState::RampIn;
        ramp_elapsed_s_ = 0.0;
    }
    out.state = state_;
    published_state_.store(state_, std::memory_order_relaxed);
    return out;
}

}  // namespace sulcus
