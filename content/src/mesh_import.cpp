#include "sulcus/content/mesh_import.h"

#include <cstdio>

namespace sulcus {

bool parse_length_unit(const std::string& s, LengthUnit* out) {
    LengthUnit u;
    if (s == "m") u = LengthUnit::Metre;
    else if (s == "cm") u = LengthUnit::Centimetre;
    else if (s == "mm") u = LengthUnit::Millimetre;
    else if (s == "um" || s == "\xC2\xB5m") u = LengthUnit::Micrometre;  // "µm" in UTF-8
    else if (s == "in") u = LengthUnit::Inch;
    else return false;
    if (out) *out = u;
    return true;
}

const char* length_unit_name(LengthUnit u) {
    switch (u) {
    case LengthUnit::Metre: return "m";
    case LengthUnit::Centimetre: return "cm";
    case LengthUnit::Millimetre: return "mm";
    case LengthUnit::Micrometre: return "um";
    case LengthUnit::Inch: return "in";
    }
    return "?";
}

double metres_per(LengthUnit u) {
    switch (u) {
    case LengthUnit::Metre: return 1.0;
    case LengthUnit::Centimetre: return 1e-2;
    case LengthUnit::Millimetre: return 1e-3;
    case LengthUnit::Micrometre: return 1e-6;
    case LengthUnit::Inch: return 0.0254;
    }
    return 1.0;
}

namespace {

// "35 m", "12 mm", "40 um": three significant digits in the unit that reads best.
std::string format_length(double metres) {
    char buf[64];
    if (metres >= 1.0) std::snprintf(buf, sizeof buf, "%.3g m", metres);
    else if (metres >= 1e-3) std::snprintf(buf, sizeof buf, "%.3g mm", metres * 1e3);
    else std::snprintf(buf, sizeof buf, "%.3g um", metres * 1e6);
    return buf;
}

}  // namespace

ImportResult import_mesh(const std::string& path, LengthUnit unit) {
    ImportResult result;
    MeshLoad load = load_mesh(path);
    if (!load.ok()) {
        result.error = std::move(load.error);
        return result;
    }
    result.mesh = std::move(load.mesh);
    const double scale = metres_per(unit);
    Aabb box;
    for (Vec3& v : result.mesh.vertices) {
        if (unit != LengthUnit::Metre) v *= scale;
        box.grow(v);
    }
    const Vec3 extent = box.hi - box.lo;
    const double size = std::max(extent.x, std::max(extent.y, extent.z));
    // A scan in mm read as metres is a thousand times too large; flag it, but leave the choice to the caller.
    if (size > kImportMaxSize || size < kImportMinSize)
        result.warning = path + ": size " + format_length(size) + " after scaling from " + length_unit_name(unit) +
                         ": wrong unit?";
    return result;
}

}  // namespace sulcus
