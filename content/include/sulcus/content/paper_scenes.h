// The scenes of the seed paper's experiments (section V: cube in a narrow cavity, line-shaped tool
// over convex and concave features) and of its Fig. 5 (thin plate, sharp ridge), plus a free-motion
// scene, generated as `sulcus.scene/1` files with their meshes and haptic trajectories.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <string>
#include <vector>

namespace sulcus {

// Writes every paper scene (JSON), its meshes (OBJ), trajectories (CSV) and a README.md into
// `dir` (created if missing). Each file is written to a temporary name and renamed, so it is
// whole or absent. Before writing, every mesh is checked to be closed and outward-oriented,
// every tool convex, and every scene's first trajectory pose free of penetration; the first
// fault is reported in `error` (if not null) and false returned.
bool write_paper_scenes(const std::string& dir, std::string* error);

// Names of the scenes write_paper_scenes produces (file names without ".json").
std::vector<std::string> paper_scene_names();

// Exact overlap test of a convex tool against a closed object, both placed by their poses:
// true when a tool vertex lies inside the object, an object vertex inside the tool, or an edge
// of one passes through a face of the other, each by more than `tolerance_m` (so touching, as
// in a zero-clearance cavity, is not overlap).
bool tool_overlaps_object(const TriMesh& object, const Pose& object_pose, const TriMesh& convex_tool,
                          const Pose& tool_pose, double tolerance_m);

// "" when the mesh is closed and consistently oriented (every directed edge used once and its
// reverse once), has no zero-area triangle, and encloses a positive volume; else the first fault.
std::string check_closed_outward(const TriMesh& mesh);

}  // namespace sulcus
