// Continuous collision detection for the tool's free motion by conservative advancement: the tool
// moves from `base` along x (translation x[0..2], world rotation vector x[3..5], both linear in
// the motion parameter tau in [0,1]); no point of the tool moves faster than
// |x_p| + |x_theta| * radius per unit tau, so advancing tau by (distance - clearance) / speed can
// never step over a contact, however thin the wall or fast the motion.
#pragma once

#include "geometry.h"
#include "sulcus/engine/renderer.h"

#include <limits>

namespace sulcus {

// An object triangle within reach of one piece of the tool (a triangle near two pieces is listed
// once for each).
struct NearTriangle {
    uint16_t object;
    uint32_t tri;
    uint8_t piece = 0;
    // A lower bound on the distance between the piece and the triangle at the pose the list was
    // made for (from the piece's bounding capsules; -infinity when it has none).
    double lower_m = -1e300;
    // A lower bound on the separation of the piece and the triangle at that pose (their distance
    // when apart, from GJK, or the separating-axis overlap when they touch), once the step has
    // needed it (NaN before): no point moving by d changes the separation by more than d, so it
    // bounds the separation at any nearby pose.
    double separation_m = std::numeric_limits<double>::quiet_NaN();
    // An upper bound on their distance there (from GJK; 1e300 when not measured).
    double upper_m = 1e300;
    // Roughly the direction from the triangle towards the piece (world; zero when unknown): where
    // a distance search between them starts.
    Vec3 direction{0.0};
    GjkSimplex simplex{};  // where a GJK search between them ended (count 0 when unknown)
    // Where the step keeps what it knows of the pair between ticks (0: nowhere); the renderer's
    // own index.
    uint16_t memo = 0;
};

struct CcdResult {
    bool hit = false;   // the tool comes within `clearance` of a triangle
    double toi = 1.0;   // motion parameter of the first such pose (1 when none)
    int iterations = 0;  // most advances any one triangle needed
    int tests = 0;       // triangle tests made
    bool exhausted = false;  // iteration cap reached before a verdict (treated as a hit)
};

// `max_iterations` advances per triangle. With `first_only`, stops at the first contact found
// (its time is then a contact's, not necessarily the first).
CcdResult conservative_advancement(const Model& model, const Pose& base, const double x[6], double clearance,
                                   const NearTriangle* near, int near_count, int max_iterations,
                                   bool first_only = false);

}  // namespace sulcus
