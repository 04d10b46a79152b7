#include "sulcus/haptics/sim_device.h"

#include <cmath>
#include <utility>

namespace sulcus {
namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

SimulatedHand::SimulatedHand(std::vector<TrajectorySample> script, HandParameters hand, DeviceCapabilities caps)
    : script_(std::move(script)), hand_(hand), caps_(std::move(caps)) {}

std::string SimulatedHand::start() {
    if (script_.empty()) return "simulated hand: empty script";
    for (size_t i = 0; i < script_.size(); ++i) {
        const TrajectorySample& s = script_[i];
        if (!std::isfinite(s.t) || !finite(s.pose.position))
            return "simulated hand: script row " + std::to_string(i) + ": not finite";
        if (i > 0 && !(s.t > script_[i - 1].t))
            return "simulated hand: script row " + std::to_string(i) + ": time does not increase";
    }
    if (!(hand_.mass_kg > 0.0) || !(hand_.grip_stiffness_N_per_m >= 0.0) || !(hand_.grip_damping_N_s_per_m >= 0.0))
        return "simulated hand: mass must be positive, grip stiffness and damping not negative";
    dt_ = hand_.dt_s > 0.0 ? hand_.dt_s : (caps_.nominal_rate_Hz > 0.0 ? 1.0 / caps_.nominal_rate_Hz : 0.0);
    if (!(dt_ > 0.0) || !std::isfinite(dt_)) return "simulated hand: no servo tick (dt_s and nominal rate unset)";
    if (hand_.latency_ticks < 0 || hand_.latency_ticks > kMaxHandLatencyTicks)
        return "simulated hand: latency_ticks must be 0.." + std::to_string(kMaxHandLatencyTicks);
    if (!(hand_.position_resolution_m >= 0.0) || !std::isfinite(hand_.position_resolution_m))
        return "simulated hand: position_resolution_m must be finite and not negative";
    for (Vec3& f : pending_) f = Vec3(0.0);
    pending_head_ = 0;

    cursor_ = 0;
    t_ = script_.front().t;
    Pose p;
    Vec3 v;
    target_at(t_, p, v);
    x_ = p.position;  // at rest on the first target: no transient from the start
    v_ = Vec3(0.0);
    orientation_ = p.orientation;
    fault_ = kDeviceFaultNone;
    running_ = true;
    return "";
}

void SimulatedHand::stop() {
    running_ = false;
    fault_ = kDeviceFaultNotStarted;
}

bool SimulatedHand::read(DeviceSample& sample) noexcept {
    sample.connected = running_;
    sample.fault = fault_;
    if (!running_) return false;
    sample.pose = Pose{x_, orientation_};
    const double res = hand_.position_resolution_m;
    if (res > 0.0) sample.pose.position = glm::round(x_ / res) * res;
    sample.linear_velocity_m_per_s = v_;
    sample.buttons = buttons_;
    return true;
}

void SimulatedHand::write(const Vec3& force_N, const Vec3& /*torque_Nm*/) noexcept {
    if (!running_) return;
    Vec3 f = force_N;
    if (!finite(f)) {
        f = Vec3(0.0);  // a broken command renders nothing and is reported
        fault_ = kDeviceFaultBadCommand;
    }
    if (hand_.saturate_force && caps_.max_force_N > 0.0) {
        const double n = glm::length(f);
        if (n > caps_.max_force_N) f *= caps_.max_force_N / n;
    }
    if (hand_.latency_ticks > 0) {
        // Delay line: this tick's force acts latency_ticks writes from now.
        const int size = hand_.latency_ticks + 1;
        pending_[pending_head_] = f;
        pending_head_ = (pending_head_ + 1) % size;
        f = pending_[pending_head_];
    }
    // The grip pulls the stylus toward the target pose and damps its velocity relative to the
    // target's; the device force acts on the same mass. Semi-implicit Euler: velocity first,
    // then position with the new velocity (stable for an undamped spring while w dt < 2).
    Pose target;
    Vec3 target_v;
    target_at(t_, target, target_v);
    const Vec3 grip = hand_.grip_stiffness_N_per_m * (target.position - x_) +
                      hand_.grip_damping_N_s_per_m * (target_v - v_);
    v_ += (dt_ / hand_.mass_kg) * (grip + f);
    x_ += dt_ * v_;
    t_ += dt_;
    Vec3 unused;
    target_at(t_, target, unused);
    orientation_ = target.orientation;  // the orientation follows the script
}

Pose SimulatedHand::target() const {
    Pose p;
    Vec3 v;
    target_at(t_, p, v);
    return p;
}

double SimulatedHand::energy_J() const {
    const Vec3 stretch = target().position - x_;
    return 0.5 * hand_.mass_kg * glm::dot(v_, v_) + 0.5 * hand_.grip_stiffness_N_per_m * glm::dot(stretch, stretch);
}

void SimulatedHand::target_at(double t, Pose& pose, Vec3& velocity) const noexcept {
    pose = sample_trajectory(script_, t, cursor_);
    velocity = Vec3(0.0);
    // Velocity of the linear segment t lies on; zero past either end.
    if (t > script_.front().t && t < script_.back().t && cursor_ + 1 < script_.size()) {
        const TrajectorySample& a = script_[cursor_];
        const TrajectorySample& b = script_[cursor_ + 1];
        velocity = (b.pose.position - a.pose.position) / (b.t - a.t);
    }
}

}  // namespace sulcus
