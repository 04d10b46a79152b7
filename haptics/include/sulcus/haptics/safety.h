// The safety layer between the renderer step and the device, run once per servo tick (1 kHz).
// It decides how much of the requested wrench (eq. 4) reaches the device: nothing until the
// request has been small for a moment at start, then a linear ramp-in, then the request as is;
// a fade to zero when the simulation stalls or gives bad numbers; zero at once on disconnect,
// device fault or emergency stop. Every wrench it emits goes through limit_wrench (finite,
// clamped, rate-limited) except those immediate zeros. See docs/safety.md.
#pragma once

#include "sulcus/engine/types.h"
#include "sulcus/haptics/force_limits.h"

#include <atomic>
#include <cstdint>

namespace sulcus {

// Defaults are argued in docs/safety.md. Times in seconds. A time that is NaN or not positive
// switches its stage off (no ramp, no fade, no hold-off); the output stays rate-limited anyway.
struct SafetyConfig {
    ForceLimits limits;                  // device limits: magnitude and rate
    double ramp_in_time_s = 0.5;         // linear rise of the output scale from 0 to 1
    double engage_force_N = 0.5;         // engage only once the request is below this ...
    double engage_torque_Nm = 0.01;      // ... and its torque below this ...
    int engage_ticks = 3;                // ... for this many consecutive good ticks
    int stall_deadline_misses = 3;       // this many consecutive missed deadlines is a stall
    double fade_time_s = 0.05;           // a stall fades the last sent wrench to zero over this
    double recover_hold_off_s = 0.2;     // the stall must have cleared this long before ramping in
    double huge_force_N = 1000.0;        // a request above this is broken, not a hard contact
    double huge_torque_Nm = 100.0;       // likewise for torque
    double nominal_dt_s = 0.001;         // used in place of a NaN or non-positive dt_s
    double max_dt_s = 0.01;              // longer ticks count as this (bounds the rate step)
};

// One tick's input. The defaults describe a tick that must send nothing (disconnected, no good
// step), so a caller that forgets a field fails safe.
struct SafetyInput {
    Vec3 force_N{0.0};             // requested force (eq. 4), world frame
    Vec3 torque_Nm{0.0};           // requested torque (eq. 4)
    bool step_ok = false;          // the renderer step succeeded (not held, no bad input)
    bool deadline_missed = false;  // the step result came too late for this tick
    bool device_connected = false; // the device answers
    bool device_fault = false;     // the device reports an error (e.g. a latched HD error)
    bool estop_button = false;     // an e-stop chord or key seen by the servo thread this tick
    double dt_s = 0.001;           // time since the previous tick
};

enum class SafetyState : uint8_t {
    Idle,      // zero output; waiting for a small request to engage (start, after reconnect/reset)
    RampIn,    // output = scale * request, scale rising linearly to 1
    Active,    // output = request (clamped, rate-limited)
    Fading,    // stalled: the last sent wrench fades to zero, then zero until recovery
    Faulted,   // device fault latched: zero until reset() with the fault cleared
    EStopped,  // emergency stop latched: zero until reset()
};

const char* to_string(SafetyState s) noexcept;

struct SafetyOutput {
    Vec3 force_N{0.0};    // the force to send this tick
    Vec3 torque_Nm{0.0};  // the torque to send this tick
    SafetyState state = SafetyState::Idle;
    double scale = 0.0;   // share of the request let through (ramp / fade), 0..1
    // Why: any number of these may be set in one tick.
    bool force_clamped = false;      // magnitude cut to the device limit
    bool torque_clamped = false;
    bool rate_limited = false;       // the change was cut to the rate limit
    bool non_finite_input = false;   // NaN or infinity in the request
    bool huge_input = false;         // request above huge_force_N / huge_torque_Nm
    bool step_failed = false;        // step_ok was false
    bool deadline_stall = false;     // stall_deadline_misses consecutive misses reached
    bool disconnected = false;       // device_connected was false: zeroed this tick
    bool fault = false;              // device fault latched
    bool estop = false;              // emergency stop latched
    bool immediate_zero = false;     // zeroed without rate limit (disconnect, fault, e-stop)
    bool reset_refused = false;      // a reset was asked while the fault was still reported
};

// Not copyable (it holds atomics). tick() belongs to the servo thread; emergency_stop(), reset()
// and state() may be called from any thread. Nothing here allocates, locks or throws.
class SafetyLayer {
public:
    explicit SafetyLayer(const SafetyConfig& config = {}) noexcept;
    SafetyLayer(const SafetyLayer&) = delete;
    SafetyLayer& operator=(const SafetyLayer&) = delete;

    // One servo tick: what to send to the device now.
    SafetyOutput tick(const SafetyInput& in) noexcept;

    // Latches EStopped; the next tick sends zero. Lock-free, callable from any thread.
    void emergency_stop() noexcept;
    // Asks to clear the latches at the next tick: the e-stop latch clears (unless the e-stop
    // button is still held), the fault latch only if that tick reports no fault and a connected
    // device; otherwise the request is dropped (reset_refused) and must be repeated. A cleared
    // layer starts again from Idle (wait for a small request, then ramp in).
    void reset() noexcept;

    SafetyState state() const noexcept { return published_state_.load(std::memory_order_relaxed); }
    const SafetyConfig& config() const noexcept { return config_; }

private:
    SafetyOutput zero_now(SafetyOutput out, SafetyState s) noexcept;
    void enter_idle() noexcept;

    SafetyConfig config_;
    std::atomic<bool> estop_request_{false};
    std::atomic<bool> reset_request_{false};
    std::atomic<SafetyState> published_state_{SafetyState::Idle};

    // Servo-thread state, fixed size.
    SafetyState state_ = SafetyState::Idle;
    bool estop_latched_ = false;
    bool fault_latched_ = false;
    int engage_count_ = 0;       // consecutive small, good ticks while Idle
    int miss_count_ = 0;         // consecutive deadline misses
    double ramp_elapsed_s_ = 0;  // time in RampIn
    double fade_elapsed_s_ = 0;  // time in Fading
    double clear_s_ = 0;         // time the stall condition has been clear while Fading
    Vec3 fade_from_force_N_{0.0};
    Vec3 fade_from_torque_Nm_{0.0};
    Vec3 last_force_N_{0.0};     // what was sent last tick
    Vec3 last_torque_Nm_{0.0};
};

}  // namespace sulcus
