#include "desktop/camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sulcus::desktop {

namespace {
constexpr double kPitchLimit = 1.5;  // rad, short of straight up or down (the up vector is +Y)
}

Vec3 OrbitCamera::eye() const {
    const Vec3 back(std::sin(yaw_rad) * std::cos(pitch_rad), std::sin(pitch_rad),
                    std::cos(yaw_rad) * std::cos(pitch_rad));
    return target + distance_m * back;
}
Vec3 OrbitCamera::forward() const { return glm::normalize(target - eye()); }
Vec3 OrbitCamera::right() const { return glm::normalize(glm::cross(forward(), Vec3(0, 1, 0))); }
Vec3 OrbitCamera::up() const { return glm::cross(right(), forward()); }

glm::dmat4 OrbitCamera::view() const { return glm::lookAt(eye(), target, Vec3(0, 1, 0)); }

glm::dmat4 OrbitCamera::projection(double aspect) const {
    // Near and far follow the distance so the depth buffer keeps its resolution at any zoom.
    return glm::perspective(fov_y_rad, aspect, distance_m * 0.02, distance_m * 20.0);
}

double OrbitCamera::metres_per_pixel(const Vec3& point, double height_px) const {
    const double depth = std::max(glm::dot(point - eye(), forward()), distance_m * 0.02);
    return 2.0 * depth * std::tan(0.5 * fov_y_rad) / std::max(height_px, 1.0);
}

void OrbitCamera::orbit(double dx_px, double dy_px) {
    yaw_rad -= 0.01 * dx_px;
    pitch_rad = std::clamp(pitch_rad + 0.01 * dy_px, -kPitchLimit, kPitchLimit);
}

void OrbitCamera::pan(double dx_px, double dy_px, double height_px) {
    const double m = metres_per_pixel(target, height_px);
    target += (-dx_px * m) * right() + (dy_px * m) * up();
}

void OrbitCamera::zoom(double steps) { distance_m = std::clamp(distance_m * std::pow(0.9, steps), 0.002, 1.0); }

int sextant_of(int fdi) {
    const int q = fdi / 10, n = fdi % 10;
    if (q < 1 || q > 4 || n < 1 || n > 8) return 0;
    const bool anterior = n <= 3;
    switch (q) {
        case 1: return anterior ? 2 : 1;
        case 2: return anterior ? 2 : 3;
        case 3: return anterior ? 5 : 4;
        default: return anterior ? 5 : 6;
    }
}

const char* sextant_label(int sextant) {
    static const char* const kLabels[] = {"?",          "S1 (18-14)", "S2 (13-23)", "S3 (24-28)",
                                          "S4 (38-34)", "S5 (33-43)", "S6 (44-48)"};
    return kLabels[(sextant >= 1 && sextant <= 6) ? sextant : 0];
}

namespace {

// Frames `teeth` from direction `from` (unit, horizontal), raised by `pitch`.
OrbitCamera frame(const std::vector<const ToothSpot*>& teeth, Vec3 from, double pitch_rad) {
    OrbitCamera cam;
    Vec3 lo(1e9), hi(-1e9);
    for (const ToothSpot* t : teeth) {
        lo = glm::min(lo, t->centre);
        hi = glm::max(hi, t->centre);
    }
    cam.target = 0.5 * (lo + hi);
    // The centres are at the gingival margins: aim a little toward the crowns, which fill the view.
    cam.target.y += pitch_rad < 0 ? -0.003 : 0.003;
    // A tooth is about 10 mm wide and 20 mm tall: frame the span of the centres plus one tooth.
    const double span = std::max(glm::length(hi - lo) + 0.012, 0.035);
    cam.distance_m = 0.6 * span / std::tan(0.5 * cam.fov_y_rad);
    from.y = 0.0;
    if (glm::length(from) < 1e-9) from = Vec3(0, 0, 1);
    from = glm::normalize(from);
    cam.yaw_rad = std::atan2(from.x, from.z);
    cam.pitch_rad = pitch_rad;
    return cam;
}

}  // namespace

bool sextant_view(const std::vector<ToothSpot>& teeth, int sextant, bool lingual, OrbitCamera& out) {
    std::vector<const ToothSpot*> in;
    Vec3 buccal(0.0);
    bool upper = false;
    for (const ToothSpot& t : teeth) {
        if (sextant_of(t.fdi) != sextant) continue;
        in.push_back(&t);
        buccal += t.buccal;
        upper = t.fdi / 10 == 1 || t.fdi / 10 == 2;
    }
    if (in.empty()) return false;
    // Look a little from occlusal: down onto a lower jaw, up into an upper one.
    out = frame(in, lingual ? -buccal : buccal, upper ? -0.2 : 0.35);
    return true;
}

OrbitCamera overview(const std::vector<ToothSpot>& teeth) {
    std::vector<const ToothSpot*> all;
    Vec3 buccal(0.0);
    int upper = 0;
    for (const ToothSpot& t : teeth) {
        all.push_back(&t);
        buccal += t.buccal;
        upper += (t.fdi / 10 == 1 || t.fdi / 10 == 2) ? 1 : -1;
    }
    if (all.empty()) return OrbitCamera{};
    // From occlusal of the jaw with more of the teeth: down onto a lower one, up into an upper one.
    return frame(all, buccal, upper > 0 ? -0.2 : 0.35);
}

}  // namespace sulcus::desktop
