// The first fault of a mesh with the triangle or vertex it concerns, so that a loader can add
// the place in its source file (line, face) to the message validate_mesh returns.
#pragma once

#include "sulcus/engine/mesh.h"

#include <cstdint>
#include <string>

namespace sulcus {

struct MeshFault {
    std::string what;       // one line, "" when the mesh is valid
    int64_t triangle = -1;  // triangle the fault is found at, or -1
    int64_t vertex = -1;    // vertex the fault is found at, or -1
};

MeshFault find_mesh_fault(const TriMesh& mesh);

}  // namespace sulcus
