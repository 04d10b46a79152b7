// Triangle meshes: loading, validation, adjacency and the convex/concave classification of
// every edge and vertex (the classification of Table 1 of the seed paper, derived from the mesh
// instead of a hand-made lookup table).
#pragma once

#include "sulcus/engine/types.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace sulcus {

// A closed, consistently oriented triangle mesh; triangles wind counter-clockwise seen from
// outside, so the right-hand normal points out of the solid. Coordinates in metres.
struct TriMesh {
    std::vector<Vec3> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;
};

enum class Convexity : uint8_t {
    Flat,     // dihedral within the flatness tolerance of 180 degrees
    Convex,   // the solid is locally convex here (free space is locally non-convex)
    Concave,  // the solid is locally concave here (free space is locally convex)
    Mixed,    // vertices only: both convex and concave edges meet here (saddle)
};

// One undirected edge of a closed manifold mesh with its two triangles.
struct MeshEdge {
    std::array<uint32_t, 2> v;     // v[0] < v[1]
    std::array<uint32_t, 2> tri;   // tri[0]: the triangle in which the edge runs v[0] -> v[1]
    Convexity convexity = Convexity::Flat;
    double dihedral = 0.0;         // signed bend angle in radians: > 0 convex, < 0 concave, 0 flat
};

// A sphere round a triangle: centred on its centroid, through its furthest vertex (m), and the
// centre's distance from the origin (m; what the distance bounds' room for rounding scales with).
struct TriangleSphere {
    Vec3 centre;
    double radius;
    double centre_norm_m;
};
inline TriangleSphere triangle_sphere(const Vec3& a, const Vec3& b, const Vec3& e) {
    const Vec3 centre = (a + b + e) / 3.0;
    const double da = glm::dot(a - centre, a - centre), db = glm::dot(b - centre, b - centre),
                 de = glm::dot(e - centre, e - centre);
    return {centre, std::sqrt(std::max(std::max(da, db), de)), glm::length(centre)};
}

// Adjacency derived from a validated TriMesh.
struct MeshTopology {
    std::vector<MeshEdge> edges;
    std::vector<std::array<uint32_t, 3>> triangle_edges;   // edge index of (v0v1, v1v2, v2v0)
    std::vector<std::array<uint32_t, 3>> triangle_neighbours;  // triangle across each of those edges
    std::vector<Vec3> triangle_normals;                    // unit outward normals
    std::vector<TriangleSphere> triangle_spheres;          // triangle_sphere of each triangle
    // Triangles and edges around each vertex (CSR layout: offsets has vertices+1 entries).
    std::vector<uint32_t> vertex_triangle_offsets, vertex_triangles;
    std::vector<uint32_t> vertex_edge_offsets, vertex_edges;
    std::vector<Convexity> vertex_convexity;
    // Per triangle, which of its features can meet a tool's: bit k (k < 3) for a convex or mixed
    // vertex k, bit 3 + k for a convex edge k (triangle_edges order). One byte where the step
    // would otherwise read three vertices' and three edges' records.
    std::vector<uint8_t> triangle_corners;
};

// Bend angle below which an edge counts as flat, in radians.
inline constexpr double kFlatEdgeAngle = 1e-9;

struct MeshLoad {
    TriMesh mesh;
    std::string error;  // empty on success; else one line "path: place: what is wrong"
    bool ok() const { return error.empty(); }
};

// Reads OBJ and OFF (strict readers: faulty faces are kept for validation to report), STL and PLY
// (OpenMesh), glTF/GLB (tinygltf: the triangle primitives of the default scene with node transforms
// applied), merges coincident vertices of per-face formats (STL, glTF), and validates. On failure
// the error names the file and the first fault.
MeshLoad load_mesh(const std::string& path);

// Checks that a mesh is usable as a solid: finite coordinates, indices in range, no degenerate
// or duplicate triangles, every edge shared by exactly two triangles with opposite directions
// (closed, manifold, consistently oriented), manifold vertices, positive enclosed volume
// (outward orientation). Returns "" or a one-line description of the first fault
// (without the file name).
std::string validate_mesh(const TriMesh& mesh);

// Builds the adjacency of a mesh that passed validate_mesh.
MeshTopology build_topology(const TriMesh& mesh);

// The connected components of a mesh (triangles joined through shared vertices), each with its
// own vertex list in first-use order; components ordered by their first triangle. Unused
// vertices are dropped.
std::vector<TriMesh> connected_components(const TriMesh& mesh);

// Signed volume enclosed by the mesh in cubic metres (> 0 for outward orientation).
double mesh_volume(const TriMesh& mesh);

// Writes a mesh as Wavefront OBJ (used by content generators and tests).
bool write_obj(const TriMesh& mesh, const std::string& path, std::string* error);

}  // namespace sulcus
