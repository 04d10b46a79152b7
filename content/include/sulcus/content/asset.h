// A content asset: named nodes, each a set of triangle-mesh parts with a material, a placement and
// free-form metadata. Teeth, gingiva, bone and probes are built as assets; glTF files read and write
// them (gltf_io.h); the tools draw them.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace sulcus {

// Metallic-roughness material, as glTF 2.0 has it. Colour components are linear, in [0, 1].
struct Material {
    std::string name;
    std::array<double, 4> base_color{0.8, 0.8, 0.8, 1.0};  // RGBA
    double metallic = 0.0;
    double roughness = 0.5;
    bool operator==(const Material&) const = default;
};

// Part of a node drawn with one material. For a solid node the parts together bound the solid
// (e.g. a tooth's enamel and root surfaces), so each part alone may be open.
struct MeshPart {
    TriMesh mesh;      // node-local coordinates, metres
    int material = -1; // index into Asset::materials, -1 = default material
};

struct AssetNode {
    std::string name;
    std::vector<MeshPart> parts;
    Pose pose;                      // node-local -> asset frame (parent frame)
    nlohmann::json extras = nlohmann::json::object();  // metadata (FDI number, site frames, ...)
};

struct Asset {
    std::vector<Material> materials;
    std::vector<AssetNode> nodes;
    nlohmann::json extras = nlohmann::json::object();  // asset-wide metadata (the chart, ...)
};

// All parts of a node as one mesh (vertices of different parts are not merged).
TriMesh merged_parts(const AssetNode& node);

}  // namespace sulcus
