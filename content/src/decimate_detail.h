// Internal to the decimater (content/src/decimate.cpp), declared for its tests.
#pragma once

#include "sulcus/engine/mesh.h"

#include <cstddef>

namespace sulcus::decimate_detail {

// Loads `mesh` (open or closed) into the decimater's mesh and, `collapses` + 1 times, asks both
// the decimater's topology check and OpenMesh's own TriConnectivity::is_collapse_ok about every
// halfedge, then collapses one halfedge both allow (taken in a fixed stride through the
// halfedges). The halfedge lookup the decimater also answers itself is compared the same way.
struct CollapseCheckCount {
    size_t compared = 0;        // collapse checks
    size_t allowed = 0;         // of which allowed the collapse
    size_t found_compared = 0;  // halfedge lookups (the edge's far vertices, the edge's own ends)
    size_t found = 0;           // of which found a halfedge
    size_t disagreed = 0;       // answers that differed from OpenMesh's, of both kinds
};
CollapseCheckCount compare_collapse_checks(const TriMesh& mesh, size_t collapses);

}  // namespace sulcus::decimate_detail
