// MouseProbeDriver: the input -> probe pose mappings of docs/mouse-device.md.
#include "sulcus/app/mouse_probe.h"

#include <cmath>

namespace sulcus {

namespace {

bool finite(double v) { return std::isfinite(v); }
bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const Quat& q) {
    return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

// A usable axis: finite and not zero (so it can be normalised).
bool axis_ok(const Vec3& v) { return finite(v) && glm::length(v) > 0.0 && std::isfinite(glm::length(v)); }

bool pose_ok(const Pose& p) {
    const double n = glm::length(p.orientation);
    return finite(p.position) && finite(p.orientation) && std::isfinite(n) && n > 0.0;
}

}  // namespace

MouseProbeDriver::MouseProbeDriver(const Pose& home, MouseProbeSettings settings) : settings_(settings) {
    if (pose_ok(home)) {
        home_ = Pose{home.position, glm::normalize(home.orientation)};
        pose_ = home_;
    }
}

bool MouseProbeDriver::reject() {
    ++rejected_;
    return false;
}

void MouseProbeDriver::translate(const Vec3& delta_m) {
    pose_.position += delta_m;
    if (bounded_) pose_.position = glm::clamp(pose_.position, bounds_min_m_, bounds_max_m_);
}

// A turn in the world frame about the tip end: the tip (the probe frame's origin, at
// pose_.position) is on every axis it turns about, so only the orientation changes.
void MouseProbeDriver::rotate(const Quat& world_turn) {
    pose_.orientation = glm::normalize(world_turn * pose_.orientation);
}

bool MouseProbeDriver::drag(double dx_px, double dy_px, const ViewBasis& view, bool fine) {
    if (!finite(dx_px) || !finite(dy_px) || !finite(view.metres_per_pixel) || !axis_ok(view.right) ||
        !axis_ok(view.up))
        return reject();
    const double k = view.metres_per_pixel * (fine ? settings_.fine_scale : 1.0);
    translate(glm::normalize(view.right) * (dx_px * k) - glm::normalize(view.up) * (dy_px * k));
    return true;
}

bool MouseProbeDriver::wheel(double steps, const ViewBasis& view, bool fine) {
    if (!finite(steps) || !axis_ok(view.forward)) return reject();
    const double step_m = settings_.wheel_step_m * (fine ? settings_.fine_scale : 1.0);
    translate(glm::normalize(view.forward) * (steps * step_m));
    return true;
}

bool MouseProbeDriver::tilt(double dx_px, double dy_px, const ViewBasis& view, bool fine) {
    if (!finite(dx_px) || !finite(dy_px) || !axis_ok(view.right) || !axis_ok(view.up)) return reject();
    const double k = settings_.tilt_rad_per_px * (fine ? settings_.fine_scale : 1.0);
    // Trackball: about +up, a positive angle takes the side facing the viewer (-forward = right x
    // up) toward +right; about +right, it takes that side toward -up, i.e. screen down.
    const Quat about_up = glm::angleAxis(dx_px * k, glm::normalize(view.up));
    const Quat about_right = glm::angleAxis(dy_px * k, glm::normalize(view.right));
    rotate(about_up * about_right);
    return true;
}

bool MouseProbeDriver::key_insert(double steps, bool fine) {
    if (!finite(steps)) return reject();
    const double step_m = settings_.key_step_m * (fine ? settings_.fine_scale : 1.0);
    translate(pose_.rotate(Vec3(0.0, -1.0, 0.0)) * (steps * step_m));
    return true;
}

bool MouseProbeDriver::key_rotate(double steps, bool fine) {
    if (!finite(steps)) return reject();
    const double angle = steps * settings_.key_rotate_rad * (fine ? settings_.fine_scale : 1.0);
    // About the probe's own +Y: the same turn as about the shaft's world direction.
    pose_.orientation = glm::normalize(pose_.orientation * glm::angleAxis(angle, Vec3(0.0, 1.0, 0.0)));
    return true;
}

bool MouseProbeDriver::set_pose(const Pose& pose) {
    if (!pose_ok(pose)) return reject();
    pose_ = Pose{pose.position, glm::normalize(pose.orientation)};
    if (bounded_) pose_.position = glm::clamp(pose_.position, bounds_min_m_, bounds_max_m_);
    return true;
}

bool MouseProbeDriver::reset(const Pose& home) {
    if (!set_pose(home)) return false;
    home_ = Pose{home.position, glm::normalize(home.orientation)};
    return true;
}

bool MouseProbeDriver::set_bounds(const Vec3& min_m, const Vec3& max_m) {
    if (!finite(min_m) || !finite(max_m)) return reject();
    bounds_min_m_ = glm::min(min_m, max_m);
    bounds_max_m_ = glm::max(min_m, max_m);
    bounded_ = true;
    pose_.position = glm::clamp(pose_.position, bounds_min_m_, bounds_max_m_);
    return true;
}

}  // namespace sulcus
