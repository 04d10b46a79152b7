// Turns mouse and keyboard input into the probe's target pose, for MouseDevice::set_target when
// no haptic device is attached. Headless: the camera reaches it as plain vectors (ViewBasis).
//
// The pose maps the probe frame to the world (metres): the tip end at the origin, +Y along the
// shaft toward the handle. Every motion keeps the tip where the user is looking: drags move it
// in the view plane, the wheel in depth, right-drags and the rotate keys turn the probe about the
// tip end (the tip stays put). See docs/mouse-device.md for the table of inputs.
#pragma once

#include "sulcus/engine/types.h"

#include <cstdint>

namespace sulcus {

// The camera's axes in the world frame (need not be unit: they are normalised here) and the
// world size of one screen pixel at the probe's depth.
struct ViewBasis {
    Vec3 right{1.0, 0.0, 0.0};
    Vec3 up{0.0, 1.0, 0.0};
    Vec3 forward{0.0, 0.0, -1.0};  // from the eye into the scene
    double metres_per_pixel = 1e-4;
};

struct MouseProbeSettings {
    double wheel_step_m = 0.5e-3;        // tip travel in depth per wheel step
    double tilt_rad_per_px = 0.005;      // probe turn per pixel of right-drag
    double key_step_m = 0.1e-3;          // travel along the shaft per insert key step
    double key_rotate_rad = 0.087266462599716478;  // turn about the shaft per rotate key step (5 deg)
    double fine_scale = 0.1;             // every motion times this with the fine modifier
};

class MouseProbeDriver {
public:
    explicit MouseProbeDriver(const Pose& home = Pose{}, MouseProbeSettings settings = {});

    // Each returns false and changes nothing when an input (or the view) is not finite, or an
    // axis of the view is zero; such inputs are counted (rejected_inputs()).

    // Left-drag: the tip follows the cursor in the view plane, metres_per_pixel per pixel
    // (screen right = +right, screen down (dy > 0) = -up).
    bool drag(double dx_px, double dy_px, const ViewBasis& view, bool fine = false);
    // Wheel: the tip moves along the view direction, wheel_step_m per step; positive steps go
    // away from the viewer (into the scene).
    bool wheel(double steps, const ViewBasis& view, bool fine = false);
    // Right-drag: the probe turns about its tip end, as a trackball: horizontal drag about the
    // view's up axis, vertical drag about its right axis, tilt_rad_per_px per pixel; the part of
    // the probe facing the viewer follows the cursor.
    bool tilt(double dx_px, double dy_px, const ViewBasis& view, bool fine = false);
    // Insert keys: along the probe's own shaft, key_step_m per step; positive steps go toward the
    // tip (-Y of the probe), deeper into a pocket.
    bool key_insert(double steps, bool fine = false);
    // Rotate keys: about the probe's own shaft (+Y, right-handed: counter-clockwise seen from the
    // handle), key_rotate_rad per step; the tip stays put.
    bool key_rotate(double steps, bool fine = false);

    // Takes `pose` as it is (orientation normalised); false and no change when not finite.
    bool set_pose(const Pose& pose);
    const Pose& pose() const noexcept { return pose_; }
    // Back to `home` (the new home).
    bool reset(const Pose& home);
    const Pose& home() const noexcept { return home_; }

    // Optional box (world, m) the tip is kept in, e.g. the device workspace mapped to the world,
    // so the target cannot run off where the device will not follow. Unbounded by default.
    bool set_bounds(const Vec3& min_m, const Vec3& max_m);
    void clear_bounds() noexcept { bounded_ = false; }

    const MouseProbeSettings& settings() const noexcept { return settings_; }
    uint64_t rejected_inputs() const noexcept { return rejected_; }

private:
    bool reject();
    void translate(const Vec3& delta_m);
    void rotate(const Quat& world_turn);

    MouseProbeSettings settings_;
    Pose pose_;
    Pose home_;
    bool bounded_ = false;
    Vec3 bounds_min_m_{0.0};
    Vec3 bounds_max_m_{0.0};
    uint64_t rejected_ = 0;
};

}  // namespace sulcus
