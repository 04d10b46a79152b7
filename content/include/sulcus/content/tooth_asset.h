// Teeth as drawable assets: the surface split at the cemento-enamel junction into enamel and root
// parts, with the tooth's metadata.
#pragma once

#include "sulcus/content/asset.h"
#include "sulcus/content/case.h"
#include "sulcus/content/tooth.h"

#include <array>

namespace sulcus {

// Splits a tooth-frame surface at the CEJ (a triangle belongs to the enamel when its centre lies
// above the CEJ curve). With a placement, the parts come out in the case frame (mirrored teeth
// keep their outward winding). Materials are those of case_materials().
std::array<MeshPart, 2> tooth_parts(const TriMesh& mesh, const ToothShape& shape, const ToothPlacement* placement);

// A node "tooth FDI" in the tooth frame with extras: fdi, universal number, class, the table row.
AssetNode make_tooth_node(const TriMesh& mesh, const ToothShape& shape);

}  // namespace sulcus
