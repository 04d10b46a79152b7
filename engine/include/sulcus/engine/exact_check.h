// Exact geometric checks of a tool pose against the scene objects, written independently of the
// solver (its own primitives, brute force over the triangles near the tool): used for the
// penetration and gap figures of a run and by the tests.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <vector>

namespace sulcus {

struct PlacedMesh {
    const TriMesh* mesh = nullptr;
    Pose pose;  // local -> world
};

struct ExactCheck {
    // Largest penetration depth in metres (0 when the tool and the objects do not overlap):
    // the maximum of (a) depth of tool vertices inside an object (distance to its surface),
    // (b) depth of object vertices inside the tool (distance to the tool's surface),
    // (c) depth of object edges passing through the tool (deepest point along the edge),
    // (d) depth of tool edges passing through an object (deepest sampled point along the edge).
    double penetration_m = 0.0;
    // Smallest distance in metres between the tool surface and any object surface
    // (0 when they touch or overlap). Only computed up to `gap_limit`; beyond it, = gap_limit.
    double distance_m = 0.0;
};

// `tool` must be convex. `gap_limit` bounds the distance search in metres.
ExactCheck exact_check(const TriMesh& tool, const Pose& tool_pose, const std::vector<PlacedMesh>& objects,
                       double gap_limit);

// A tool made of convex pieces (a rigid union, e.g. connected_components of its mesh): the
// largest penetration of any piece and the least distance of any piece.
ExactCheck exact_check(const std::vector<TriMesh>& tool_pieces, const Pose& tool_pose,
                       const std::vector<PlacedMesh>& objects, double gap_limit);

}  // namespace sulcus
