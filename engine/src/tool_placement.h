// The tool's convex pieces placed in the world at a pose: vertices, face planes, bounding
// capsules, and the view of one piece the separating-axis and distance tests take. Shared by the
// servo step and the CCD.
#pragma once

#include "geometry.h"
#include "lanes.h"
#include "sulcus/engine/renderer.h"

namespace sulcus {

// Out of line: inlined into the step (as GCC 12 did after an unrelated change there), its loop
// took nearly three times the instructions.
// With AVX2, four vertices at a time (LanesRotation: glm's operations in its order, so the same
// answers to the bit).
// Vertices [first, end) only where given (end clamped to the tool's).
[[gnu::noinline]] inline void place_tool_vertices(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* vertices,
                                                 size_t first = 0, size_t end = SIZE_MAX) {
    const size_t n = std::min(end, tool.mesh.vertices.size());
    size_t i = first;
#if defined(__AVX2__)
    const LanesRotation rotation(q);
    const __m256d px = lanes_of(p.x), py = lanes_of(p.y), pz = lanes_of(p.z);
    for (; i + 4 <= n; i += 4) {
        __m256d x, y, z;
        lanes_of_vectors(tool.mesh.vertices.data() + i, x, y, z);
        rotation.apply(x, y, z);
        store_lanes_as_vectors(_mm256_add_pd(x, px), _mm256_add_pd(y, py), _mm256_add_pd(z, pz), vertices + i);
    }
#endif
    for (; i < n; ++i) vertices[i] = q * tool.mesh.vertices[i] + p;
}

// Face planes of every piece in the world: n . x <= d inside the piece. With AVX2, four faces
// at a time, to the bit as one at a time.
// Faces [first, end) only where given (end clamped to the tool's).
inline void place_tool_planes(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* normals, double* offsets,
                              size_t first = 0, size_t end = SIZE_MAX) {
    const size_t n = std::min(end, tool.face_normals.size());
    size_t f = first;
#if defined(__AVX2__)
    const LanesRotation rotation(q);
    const __m256d px = lanes_of(p.x), py = lanes_of(p.y), pz = lanes_of(p.z);
    for (; f + 4 <= n; f += 4) {
        __m256d x, y, z;
        lanes_of_vectors(tool.face_normals.data() + f, x, y, z);
        rotation.apply(x, y, z);
        store_lanes_as_vectors(x, y, z, normals + f);
        const __m256d d = _mm256_add_pd(_mm256_loadu_pd(tool.face_offsets.data() + f), lanes_dot(x, y, z, px, py, pz));
        _mm256_storeu_pd(offsets + f, d);
    }
#endif
    for (; f < n; ++f) {
        normals[f] = q * tool.face_normals[f];
        offsets[f] = tool.face_offsets[f] + glm::dot(normals[f], p);
    }
}

// Piece k's capsule axis points in the world, at points[k * (kToolCapsules + 1)] on.
inline void place_piece_capsule(const ModelTool& tool, size_t k, const Quat& q, const Vec3& p, Vec3* points) {
    for (size_t j = 0; j <= size_t(kToolCapsules); ++j)
        points[k * (kToolCapsules + 1) + j] = q * tool.pieces[k].capsule_points[j] + p;
}

// The capsules' axis points of every piece in the world: kToolCapsules + 1 per piece, piece k's
// starting at points[k * (kToolCapsules + 1)].
inline void place_tool_capsule(const ModelTool& tool, const Quat& q, const Vec3& p, Vec3* points) {
    for (size_t k = 0; k < tool.pieces.size(); ++k) place_piece_capsule(tool, k, q, p, points);
}

// Piece k alone placed as the three above place the whole tool (the same values to the bit, in the
// whole tool's arrays): where only some pieces are needed at a pose.
inline void place_tool_piece(const ModelTool& tool, size_t k, const Quat& q, const Vec3& p, Vec3* vertices,
                             Vec3* normals, double* offsets, Vec3* capsule) {
    const ToolPiece& piece = tool.pieces[k];
    place_tool_vertices(tool, q, p, vertices, piece.vertex_begin, size_t(piece.vertex_begin) + piece.vertex_count);
    place_tool_planes(tool, q, p, normals, offsets, piece.face_begin, size_t(piece.face_begin) + piece.face_count);
    place_piece_capsule(tool, k, q, p, capsule);
}

// The view of piece `k`. `vertices`, `normals`, `offsets` and `capsule` are the whole tool's
// placed arrays (as filled above); `rotation` (the tool's world orientation, kept current by the
// caller as the planes move) enables the fast separating-axis test.
inline ConvexView tool_convex_view(const ModelTool& tool, size_t k, const Vec3* vertices, const Vec3* normals,
                                   const double* offsets, const Quat* rotation, const Vec3* capsule = nullptr) {
    const ToolPiece& piece = tool.pieces[k];
    ConvexView v;
    v.vertices = vertices + piece.vertex_begin;
    v.vertex_count = static_cast<int>(piece.vertex_count);
    v.normals = normals + piece.face_begin;
    v.offsets = offsets + piece.face_begin;
    v.face_count = static_cast<int>(piece.face_count);
    v.edges = reinterpret_cast<const uint32_t (*)[2]>(tool.piece_edges.data() + piece.edge_begin);
    v.edge_count = static_cast<int>(piece.edge_count);
    v.depths = tool.face_depths.data() + piece.face_begin;
    v.edge_normals = reinterpret_cast<const Vec3 (*)[2]>(tool.edge_normals.data() + piece.edge_begin);
    v.triangle_normals = tool.piece_triangle_normals.data() + piece.triangle_begin;
    v.triangle_count = static_cast<int>(piece.triangle_count);
    v.edge_triangles = reinterpret_cast<const uint32_t (*)[2]>(tool.edge_triangles.data() + piece.edge_begin);
    v.rotation = rotation;
    if (piece.descend) {
        v.neighbour_offsets = tool.neighbour_offsets.data() + piece.vertex_begin;
        v.neighbours = tool.neighbours.data();
        v.start_of = tool.descent_start.data() + piece.vertex_begin;
    }
    if (capsule) {
        v.capsule = capsule + k * (kToolCapsules + 1);
        v.capsule_radii = piece.capsule_radii_m.data();
        v.capsule_count = piece.capsule_count;
    }
    return v;
}

// Piece k's triangles, indexing its view's vertices.
inline const uint32_t (*piece_triangles(const ModelTool& tool, size_t k))[3] {
    return reinterpret_cast<const uint32_t (*)[3]>(tool.piece_triangles.data() + tool.pieces[k].triangle_begin);
}

}  // namespace sulcus
