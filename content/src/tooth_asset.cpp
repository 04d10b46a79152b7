#include "sulcus/content/tooth_asset.h"

#include <cmath>

namespace sulcus {

std::array<MeshPart, 2> tooth_parts(const TriMesh& mesh, const ToothShape& shape, const ToothPlacement* placement) {
    std::array<MeshPart, 2> parts;
    parts[0].material = kMaterialEnamel;
    parts[1].material = kMaterialRoot;
    std::array<std::vector<int64_t>, 2> map;
    map[0].assign(mesh.vertices.size(), -1);
    map[1].assign(mesh.vertices.size(), -1);
    for (const auto& tri : mesh.triangles) {
        const Vec3 c = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0;
        const size_t which = c.y > shape.cej_height(std::atan2(c.z, c.x)) ? 0 : 1;
        MeshPart& part = parts[which];
        std::array<uint32_t, 3> t{};
        for (size_t k = 0; k < 3; ++k) {
            const uint32_t v = tri[k];
            if (map[which][v] < 0) {
                map[which][v] = int64_t(part.mesh.vertices.size());
                part.mesh.vertices.push_back(placement ? placement->to_case(mesh.vertices[v]) : mesh.vertices[v]);
            }
            t[k] = uint32_t(map[which][v]);
        }
        if (placement && placement->mirror) std::swap(t[1], t[2]);
        part.mesh.triangles.push_back(t);
    }
    return parts;
}

AssetNode make_tooth_node(const TriMesh& mesh, const ToothShape& shape) {
    const ToothDimensions& d = shape.dims();
    AssetNode node;
    node.name = "tooth " + std::to_string(d.fdi);
    const auto parts = tooth_parts(mesh, shape, nullptr);
    node.parts.assign(parts.begin(), parts.end());
    static const char* classes[] = {"central incisor", "lateral incisor", "canine", "first premolar",
                                    "second premolar", "first molar", "second molar"};
    node.extras = {{"fdi", d.fdi},
                   {"universal", universal_number(d.fdi)},
                   {"class", classes[int(d.cls)]},
                   {"arch", d.upper ? "upper" : "lower"},
                   {"frame", "tooth: origin at the facial CEJ on the long axis, +Y occlusal, +X mesial, +Z buccal"},
                   {"dimensions_mm",
                    {{"crown_length", d.crown_length_mm},
                     {"root_length", d.root_length_mm},
                     {"crown_md", d.crown_md_mm},
                     {"cervix_md", d.cervix_md_mm},
                     {"crown_bl", d.crown_bl_mm},
                     {"cervix_bl", d.cervix_bl_mm},
                     {"cej_curve_mesial", d.cej_curve_mesial_mm},
                     {"cej_curve_distal", d.cej_curve_distal_mm},
                     {"roots", d.roots}}}};
    return node;
}

}  // namespace sulcus
