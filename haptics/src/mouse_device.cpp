// MouseDevice: the lock-free target hand-over and the rate-limited approach in read().
#include "sulcus/haptics/mouse_device.h"

#include "sulcus/haptics/servo_loop.h"  // Seqlock

#include <cmath>

namespace sulcus {

namespace {

bool finite(const Vec3& v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

bool finite(const Quat& q) noexcept {
    return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

bool positive(double v) noexcept { return std::isfinite(v) && v > 0.0; }

struct Wrench {
    Vec3 force_N{0.0};
    Vec3 torque_Nm{0.0};
};

DeviceCapabilities mouse_capabilities(const MouseDeviceConfig& config) {
    DeviceCapabilities c;
    c.name = "Mouse and keyboard";
    c.input_dof = 6;
    c.output_dof = 0;
    c.max_force_N = 0.0;
    c.nominal_rate_Hz = config.rate_hz;
    if (config.workspace_min_m == Vec3(0.0) && config.workspace_max_m == Vec3(0.0)) {
        c.workspace_min_m = config.start_pose.position - Vec3(0.1);
        c.workspace_max_m = config.start_pose.position + Vec3(0.1);
    } else {
        c.workspace_min_m = glm::min(config.workspace_min_m, config.workspace_max_m);
        c.workspace_max_m = glm::max(config.workspace_min_m, config.workspace_max_m);
    }
    return c;
}

// `from` turned toward `to` by at most `max_angle_rad` (about the axis of the shortest turn
// between them, in the parent frame); `to` itself when it is that close.
Quat turn_toward(const Quat& from, const Quat& to, double max_angle_rad) noexcept {
    Quat d = to * glm::conjugate(from);
    if (d.w < 0.0) d = -d;  // the short way round
    const Vec3 v(d.x, d.y, d.z);
    const double s = glm::length(v);
    const double angle = 2.0 * std::atan2(s, d.w);
    if (angle <= max_angle_rad || s == 0.0) return to;
    return glm::normalize(glm::angleAxis(max_angle_rad, v / s) * from);
}

}  // namespace

struct MouseDevice::Shared {
    Seqlock<Pose> target;   // writer: the UI thread (set_target)
    Seqlock<Wrench> wrench; // writer: the servo thread (write)
};

MouseDevice::MouseDevice(MouseDeviceConfig config)
    : config_(config), caps_(mouse_capabilities(config_)), shared_(std::make_unique<Shared>()) {
    pose_ = config_.start_pose;
}

MouseDevice::~MouseDevice() = default;

std::string MouseDevice::start() {
    stop();
    if (!positive(config_.rate_hz)) return "mouse: rate_hz must be a positive number";
    if (!positive(config_.max_speed_m_per_s)) return "mouse: max_speed_m_per_s must be a positive number";
    if (!positive(config_.max_angular_speed_rad_per_s))
        return "mouse: max_angular_speed_rad_per_s must be a positive number";
    if (!finite(config_.start_pose.position) || !finite(config_.start_pose.orientation) ||
        glm::length(config_.start_pose.orientation) == 0.0)
        return "mouse: the start pose is not finite";
    caps_ = mouse_capabilities(config_);
    if (!finite(caps_.workspace_min_m) || !finite(caps_.workspace_max_m))
        return "mouse: the workspace box is not finite";

    pose_.position = glm::clamp(config_.start_pose.position, caps_.workspace_min_m, caps_.workspace_max_m);
    pose_.orientation = glm::normalize(config_.start_pose.orientation);
    dt_s_ = 1.0 / config_.rate_hz;
    fault_ = kDeviceFaultNone;
    bad_commands_.store(0, std::memory_order_relaxed);
    shared_->wrench.store(Wrench{});
    running_ = true;
    return "";
}

void MouseDevice::stop() {
    running_ = false;
    fault_ = kDeviceFaultNotStarted;
}

bool MouseDevice::set_target(const Pose& pose) noexcept {
    const double n = glm::length(pose.orientation);
    if (!finite(pose.position) || !finite(pose.orientation) || !std::isfinite(n) || n == 0.0) {
        rejected_.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    shared_->target.store(Pose{pose.position, pose.orientation / n});
    return true;
}

bool MouseDevice::read(DeviceSample& sample) noexcept {
    sample.pose = pose_;
    sample.linear_velocity_m_per_s = Vec3(0.0);
    sample.buttons = 0;
    if (!running_) {
        sample.connected = false;
        sample.fault = kDeviceFaultNotStarted;
        return false;
    }
    Pose target;
    if (shared_->target.load(target)) {
        const Vec3 before = pose_.position;
        // Aim at the nearest point of the box, so the approach is a straight line at full speed
        // and the position never leaves the box.
        const Vec3 aim = glm::clamp(target.position, caps_.workspace_min_m, caps_.workspace_max_m);
        const Vec3 d = aim - pose_.position;
        const double len = glm::length(d);
        const double max_step = config_.max_speed_m_per_s * dt_s_;
        pose_.position = len <= max_step ? aim : pose_.position + d * (max_step / len);
        pose_.position = glm::clamp(pose_.position, caps_.workspace_min_m, caps_.workspace_max_m);
        pose_.orientation =
            turn_toward(pose_.orientation, target.orientation, config_.max_angular_speed_rad_per_s * dt_s_);
        sample.linear_velocity_m_per_s = (pose_.position - before) / dt_s_;
    }
    sample.pose = pose_;
    sample.connected = true;
    sample.fault = fault_;
    return true;
}

void MouseDevice::write(const Vec3& force_N, const Vec3& torque_Nm) noexcept {
    if (!running_) return;
    if (!finite(force_N) || !finite(torque_Nm)) {
        // As on a real device: a broken command applies zero and is a fault upstream.
        bad_commands_.fetch_add(1, std::memory_order_relaxed);
        fault_ = kDeviceFaultBadCommand;
        shared_->wrench.store(Wrench{});
        return;
    }
    shared_->wrench.store(Wrench{force_N, torque_Nm});
}

Vec3 MouseDevice::last_force() const noexcept {
    Wrench w;
    shared_->wrench.load(w);
    return w.force_N;
}

Vec3 MouseDevice::last_torque() const noexcept {
    Wrench w;
    shared_->wrench.load(w);
    return w.torque_Nm;
}

}  // namespace sulcus
