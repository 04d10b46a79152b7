// Content assets as glTF 2.0: binary .glb output that other tools (Blender, viewers) open, and a
// reader for .glb/.gltf files written by us or by those tools. The mapping is in docs/gltf.md.
#pragma once

#include "sulcus/content/asset.h"

#include <string>

namespace sulcus {

// Writes `asset` as one binary glTF 2.0 file: metres, +Y up; one glTF node per AssetNode
// (name, translation and rotation from its pose, rounded to float32; extras = node.extras), one
// mesh per node with one triangle primitive per MeshPart (POSITION float32 with min/max, unit
// area-weighted NORMAL float32, uint32 indices, one glTF vertex per mesh vertex), materials as
// pbrMetallicRoughness factors with their names, asset.extras as the scene's extras and
// asset.generator "sulcus". Written to a temporary name, then renamed: the file is whole or
// absent. Returns "" or one line "path: what".
std::string write_glb(const Asset& asset, const std::string& path);

struct AssetLoad {
    Asset asset;
    std::string error;  // "" on success; else one line "path: place: what"
    bool ok() const { return error.empty(); }
};

// Reads a .glb or .gltf file: every node of the default scene's tree that has a mesh becomes an
// AssetNode, in depth-first order, posed by its world transform (the hierarchy is flattened). A
// rigid world transform becomes the pose; scale or shear is baked into the vertices, the rigid
// rest stays the pose, and a mirroring transform has its winding reversed so that normals keep
// pointing out. Triangle primitives only; vertices are kept as stored (not welded), so a file
// written by write_glb gives back its meshes vertex for vertex. Extras (scene or root, and node)
// come back as JSON, exactly as written in the file.
AssetLoad read_glb(const std::string& path);

}  // namespace sulcus
