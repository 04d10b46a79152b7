// Per-tooth tables the gingiva and bone fields of a case are built from (case_build.cpp).
#pragma once

#include "sulcus/content/case.h"

#include <array>
#include <vector>

namespace sulcus::case_detail {

inline constexpr int kAngles = 720;  // samples of the polar angle around each tooth

// A periodic function of the polar angle, sampled at kAngles points, linearly interpolated.
struct AngleTable {
    std::array<double, kAngles> v{};
    double at(double theta) const;
};

// A furcation opened by the chart (grade >= 2): a box between the roots, in the tooth frame.
struct Tunnel {
    Vec3 entrance;       // on the outline, at the roof
    Vec3 inward, across; // unit, horizontal
    double depth = 0.0;  // how far in from the entrance (through for grade >= 3)
    double outer = 0.0;  // how far out of the entrance (to the pocket)
    double half_width = 0.0;
    double y_low = 0.0, y_high = 0.0;
    double field(const Vec3& p) const;  // < 0 inside the box
};

struct ToothTables {
    ToothPlacement placement;
    const ToothShape* shape = nullptr;
    AngleTable margin;   // y of the gingival margin
    AngleTable floor;    // y of the pocket floor: the onset of the yielding layer
    AngleTable charted_floor;  // y of the charted floor (the tip at 0.25 N); the bone's reference
    AngleTable slot;     // radius of the inner wall of the gingiva along the pocket
    AngleTable outer;    // radius of the outer gingival surface at the margin
    // Convex hull of the tooth's cross-section: radius by (height, angle).
    double hull_y0 = 0.0, hull_dy = 1e-4;
    int hull_rows = 0;
    std::vector<float> hull;  // hull_rows x kAngles
    double hull_at(double theta, double y) const;
    std::vector<Tunnel> tunnels;
    // Half-spaces toward the neighbouring teeth of the same jaw: the collar stays on this side.
    std::vector<std::pair<Vec3, Vec3>> cuts;  // (point, outward unit normal) in the case frame
    double reach = 0.0;  // radius beyond which this tooth's collar and slot do not matter
    double bottom = 0.0; // y of the bottom of the gingiva block, tooth frame
};

// Smoothstep interpolation of site values around the tooth, flat at every site.
double site_interpolate(const std::array<double, 6>& site_theta, const std::array<double, 6>& values, double theta);

// Fields in the case frame (negative inside).
double gum_field(const std::vector<ToothTables>& jaw, const Vec3& p);
double bone_field(const std::vector<ToothTables>& jaw, const Vec3& p);

}  // namespace sulcus::case_detail
