#include "sulcus/content/asset.h"

namespace sulcus {

TriMesh merged_parts(const AssetNode& node) {
    TriMesh out;
    size_t vertices = 0, triangles = 0;
    for (const MeshPart& part : node.parts) {
        vertices += part.mesh.vertices.size();
        triangles += part.mesh.triangles.size();
    }
    out.vertices.reserve(vertices);
    out.triangles.reserve(triangles);
    for (const MeshPart& part : node.parts) {
        const auto offset = uint32_t(out.vertices.size());
        out.vertices.insert(out.vertices.end(), part.mesh.vertices.begin(), part.mesh.vertices.end());
        for (const auto& t : part.mesh.triangles) out.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    return out;
}

}  // namespace sulcus
