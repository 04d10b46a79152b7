// The 3D view's camera: orbits a target point (yaw about +Y from +Z toward +X, pitch up from the
// horizontal), pans it in the view plane and zooms by distance. Case frame, metres. Also the
// preset views: one per sextant of the case, from buccal or lingual.
#pragma once

#include "sulcus/engine/types.h"

#include <glm/mat4x4.hpp>

#include <string>
#include <vector>

namespace sulcus::desktop {

struct OrbitCamera {
    Vec3 target{0.0};
    double yaw_rad = 0.0;
    double pitch_rad = 0.3;
    double distance_m = 0.06;
    double fov_y_rad = 0.5;  // about 29 degrees

    Vec3 eye() const;
    Vec3 forward() const;  // unit, eye toward target
    Vec3 right() const;    // unit, screen right
    Vec3 up() const;       // unit, screen up
    glm::dmat4 view() const;
    glm::dmat4 projection(double aspect) const;
    // World length of one pixel at `point`'s depth, for a viewport `height_px` high.
    double metres_per_pixel(const Vec3& point, double height_px) const;

    void orbit(double dx_px, double dy_px);                     // 0.01 rad per pixel
    void pan(double dx_px, double dy_px, double height_px);     // the target follows the cursor
    void zoom(double steps);                                    // 10 % closer per step
};

// The teeth as the view presets see them: where each stands and which way is buccal.
struct ToothSpot {
    int fdi = 0;
    Vec3 centre;  // middle of its six gingival-margin points, metres
    Vec3 buccal;  // unit, horizontal, out of the mouth at the tooth
};

// Sextants 1-6 (1: 18-14, 2: 13-23, 3: 24-28, 4: 38-34, 5: 33-43, 6: 44-48).
int sextant_of(int fdi);
const char* sextant_label(int sextant);  // "S1 (18-14)", ...

// A camera looking at the teeth of `sextant` from buccal (or lingual), slightly from occlusal,
// framing them; false when the case has no tooth there.
bool sextant_view(const std::vector<ToothSpot>& teeth, int sextant, bool lingual, OrbitCamera& out);
// A camera framing every tooth from buccal of their middle.
OrbitCamera overview(const std::vector<ToothSpot>& teeth);

}  // namespace sulcus::desktop
