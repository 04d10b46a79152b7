// Implicit solids to triangle meshes: the content library models teeth, gingiva and bone as
// implicit fields (negative inside, roughly a signed distance in metres) and turns them into
// closed, manifold, outward-oriented meshes here, then coarsens them where they are flat.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <cstddef>
#include <functional>

namespace sulcus {

// f(p) < 0 inside the solid, > 0 outside; continuous. Need not be an exact distance, but the
// closer it is to one, the better the vertex placement.
using ImplicitField = std::function<double(const Vec3&)>;

struct PolygonizeSettings {
    double cell_m = 1e-4;    // grid spacing
    int refine_steps = 24;   // bisection steps that move each vertex onto the zero set along its grid edge
};

// Marching tetrahedra over a regular grid covering `box` (each cube split into six tetrahedra
// sharing the cube's main diagonal, so neighbouring cubes agree on their shared faces): the zero
// set of the piecewise-linear field is a closed 2-manifold whenever the solid lies strictly inside
// the box. Grid values that are exactly zero are nudged outside. Vertices on the same grid edge are
// shared, then moved onto the field's zero set by bisection along their edge. Triangles wind
// counter-clockwise seen from outside. Throws std::invalid_argument if the field is negative on
// the box boundary (the solid is cut off) or the settings are not positive.
TriMesh polygonize(const ImplicitField& field, const Aabb& box, const PolygonizeSettings& settings);

struct DecimateSettings {
    double max_error_m = 1e-5;        // largest allowed distance of the coarse surface from the fine one
    size_t target_triangles = 0;      // stop at this many triangles (0 = only the error bound stops it)
    double max_normal_change_rad = 0.5;  // a collapse may not turn any triangle's normal by more
    double max_aspect = 20.0;         // no collapse may create a triangle longer than this times its height
};

// Edge-collapse decimation (OpenMesh's decimater with an unweighted plane-distance quadric as
// priority and bound, no normal turned by more than max_normal_change_rad, no new slivers). Keeps
// the mesh closed, manifold and oriented; every vertex stays within max_error_m of the planes of
// all the original triangles merged into it, which holds the surface to about that distance.
TriMesh decimate(const TriMesh& mesh, const DecimateSettings& settings);

// Smooth minimum / maximum of two distance-like fields with blend radius k (metres): union and
// intersection with a rounded seam. k <= 0 gives the plain min / max.
double smooth_min(double a, double b, double k);
double smooth_max(double a, double b, double k);

}  // namespace sulcus
