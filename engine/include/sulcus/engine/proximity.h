// Proximity and collision queries of the model's tool at a pose against all of the model's
// objects: least surface distance and overlap. Exact (per-triangle tests, no sampling), pruned by
// the objects' BVHs; allocation-free after the first call on a thread.
//
// Both queries treat the tool as its closed convex pieces and each object as its triangles: a
// tool lying wholly inside an object without meeting any of its triangles is reported at its
// distance from the object's surface, and as not colliding.
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/engine/types.h"

namespace sulcus {

// Work done by one query.
struct ProximityStats {
    int nodes_visited = 0;     // BVH nodes whose box was tested
    int triangles_tested = 0;  // object triangles that reached an exact triangle test
};

// Least distance (m) between the tool's surface and any object's surface: 0 when they touch or
// overlap; max_distance_m when nothing is nearer than that. Exact (no sampling). The pose's
// orientation must be a unit quaternion.
double tool_distance(const Model& model, const Pose& tool_pose, double max_distance_m,
                     ProximityStats* stats = nullptr);

// Whether the tool overlaps any object (exact separating-axis test per triangle against each
// convex piece); touching (zero separation) counts as overlapping.
bool tool_collides(const Model& model, const Pose& tool_pose, ProximityStats* stats = nullptr);

}  // namespace sulcus
