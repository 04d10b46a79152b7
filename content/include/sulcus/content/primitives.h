// Procedural solids for test and demonstration scenes: boxes, a box with a cavity, extruded
// polygons and a wedge ridge. Every mesh is closed, consistently oriented (counter-clockwise seen
// from outside, so normals point out of the solid) and in metres; output depends only on the
// arguments (no randomness), so generated assets are reproducible bit for bit.
//
// Invalid arguments (non-positive sizes, a cavity that does not fit, a polygon that is not simple
// or not counter-clockwise) throw std::invalid_argument: these are authoring errors, caught when
// the content is generated, never at run time.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <array>
#include <cstdint>
#include <vector>

namespace sulcus {

using Vec2 = glm::dvec2;

// Axis-aligned box: 8 vertices, 12 triangles.
TriMesh make_box(const Vec3& half_extents, const Vec3& centre = Vec3(0.0));

// Box centred at the origin with a box-shaped hollow inside: two shells, the outer facing out,
// the inner facing into the cavity (so the solid is the material between them). The cavity must
// lie strictly inside the outer box.
TriMesh make_box_with_cavity(const Vec3& outer_half_extents, const Vec3& cavity_half_extents,
                             const Vec3& cavity_centre = Vec3(0.0));

// Prism over a simple polygon in the XY plane (counter-clockwise, no repeated vertices; may be
// concave), from z0 to z1 (> z0). The caps are triangulated by ear clipping.
TriMesh make_extruded_polygon(const std::vector<Vec2>& polygon, double z0, double z1);

// A sharp ridge along Z: a triangular prism whose cross-section is an isosceles triangle with the
// apex at `apex` (pointing +Y), apex angle `apex_angle_rad`, base `height` below the apex,
// extending `half_length` either side of apex.z.
TriMesh make_wedge(double apex_angle_rad, double height, double half_length, const Vec3& apex = Vec3(0.0));

// Ear-clipping triangulation of a simple counter-clockwise polygon: triangles of indices into
// `polygon`, each counter-clockwise with positive area. Throws std::invalid_argument otherwise.
std::vector<std::array<uint32_t, 3>> triangulate_polygon(const std::vector<Vec2>& polygon);

// Signed area of a polygon (> 0 for counter-clockwise), in square metres.
double polygon_signed_area(const std::vector<Vec2>& polygon);

}  // namespace sulcus
