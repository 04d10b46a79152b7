// One triangle primitive of a glTF model as mesh data: shared by the engine's mesh loader and the
// content library's glTF reader, so both check accessors and indices the same way.
#pragma once

#include "sulcus/engine/mesh.h"

#include <glm/mat4x4.hpp>

#include <string>

namespace tinygltf {
class Model;
struct Primitive;
}  // namespace tinygltf

namespace sulcus {

// Appends the primitive's vertices (each mapped by `transform`) and triangles to `out`. A mirroring
// transform reverses the winding, as glTF does, which this undoes so normals keep pointing out.
// Accessors are bounds-checked against their buffer views and buffers; indices against the vertex
// count. On failure returns false with a one-line reason (no file or place in it): a mode other than
// triangles, a missing or malformed POSITION, bad indices. `out` may then hold part of the data.
bool append_gltf_triangles(const tinygltf::Model& model, const tinygltf::Primitive& prim, const glm::dmat4& transform,
                           TriMesh& out, std::string& error);

}  // namespace sulcus
