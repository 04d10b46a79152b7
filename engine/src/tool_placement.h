// The convex tool placed in the world at a pose: its vertices, its face planes and the view of
// it the separating-axis and distance tests take. Shared by the servo step and the CCD.
#pragma once

#include "geometry.h"
#include "sulcus/engine/renderer.h"

namespace sulcus {

inline void place_tool_vertices(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* vertices) {
    for (size_t i = 0; i < tool.mesh.vertices.size(); ++i) vertices[i] = q * tool.mesh.vertices[i] + p;
}

// Face planes in the world: n . x <= d inside.
inline void place_tool_planes(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* normals, double* offsets) {
    for (size_t f = 0; f < tool.face_normals.size(); ++f) {
        normals[f] = q * tool.face_normals[f];
        offsets[f] = tool.face_offsets[f] + glm::dot(normals[f], p);
    }
}

// `rotation` (the tool's world orientation, kept current by the caller as the planes move)
// enables the fast separating-axis test.
// The capsules' axis points (kToolCapsules + 1 of them) in the world.
inline void place_tool_capsule(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* points) {
    for (size_t k = 0; k < tool.capsule_points.size(); ++k) points[k] = q * tool.capsule_points[k] + p;
}

inline ConvexView tool_convex_view(const ModelTool& tool, const Vec3* vertices, const Vec3* normals,
                                   const double* offsets, const Quat* rotation, const Vec3* capsule = nullptr) {
    ConvexView v;
    v.vertices = vertices;
    v.vertex_count = static_cast<int>(tool.mesh.vertices.size());
    v.normals = normals;
    v.offsets = offsets;
    v.face_count = static_cast<int>(tool.face_normals.size());
    v.edges = reinterpret_cast<const uint32_t (*)[2]>(tool.edges.data());
    v.edge_count = static_cast<int>(tool.edges.size());
    v.depths = tool.face_depths.data();
    v.edge_normals = reinterpret_cast<const Vec3 (*)[2]>(tool.edge_normals.data());
    v.rotation = rotation;
    v.capsule = capsule;
    v.capsule_radii = tool.capsule_radii_m.data();
    v.capsule_count = tool.capsule_count;
    return v;
}

}  // namespace sulcus
