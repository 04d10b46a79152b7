// Meshes a school already has (intra-oral scans, models exported from CAD or sculpting tools):
// OBJ, STL, PLY, OFF, glTF/GLB read by the engine's load_mesh and scaled from the file's length
// unit to metres.
//
// load_mesh accepts closed, consistently oriented solids only and returns no mesh when a file
// fails validation, so an open scan surface cannot be imported through it (the engine needs
// closed solids for collision anyway). An open glTF/GLB surface for display can be read with
// read_glb (gltf_io.h), which does not require closure. See docs/gltf.md.
#pragma once

#include "sulcus/engine/mesh.h"

#include <string>

namespace sulcus {

enum class LengthUnit { Metre, Centimetre, Millimetre, Micrometre, Inch };

// "m", "cm", "mm", "um" (or "µm"), "in". Returns false and leaves *out alone otherwise.
bool parse_length_unit(const std::string& s, LengthUnit* out);
// The short name parse_length_unit accepts ("mm").
const char* length_unit_name(LengthUnit u);
// Length of one unit in metres (Inch = 0.0254 exactly).
double metres_per(LengthUnit u);

// Plausible size of a dental model after scaling: the largest bounding-box extent, in metres.
inline constexpr double kImportMinSize = 1e-3;
inline constexpr double kImportMaxSize = 0.5;

struct ImportResult {
    TriMesh mesh;         // metres
    std::string error;    // load_mesh's one-line error, "" on success
    std::string warning;  // "" or one line, e.g. "scan.stl: size 35 m after scaling from mm: wrong unit?"
    bool ok() const { return error.empty(); }
};

// Loads `path` with load_mesh (which validates it as a closed solid) and multiplies every
// coordinate by metres_per(unit). A mesh whose largest extent falls outside
// [kImportMinSize, kImportMaxSize] after scaling is still returned, with a warning.
ImportResult import_mesh(const std::string& path, LengthUnit unit);

}  // namespace sulcus
