// Tissue settings of the pocket floor: how far the tip sinks into the junctional epithelium (and,
// when inflamed, through it) under a given probing force (docs/tissue.md). The numbers are the
// scene format's `yield_curve_N_mm`: [force N, depth mm] points from [0, 0], both strictly
// increasing, slopes (N/mm) non-decreasing (a stiffening curve), extrapolated with the last slope.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace sulcus {

// Depth of the tip below the onset of the yielding layer against the probing force.
struct YieldCurve {
    std::vector<std::array<double, 2>> points_N_mm;  // {force N, depth mm}
    // Depth in mm at force_N: linear between points, the last slope beyond the last point, 0 for
    // force <= 0. Only meaningful for a curve that passes validate_yield_curve.
    double depth_mm_at(double force_N) const;
    double depth_m_at(double force_N) const { return depth_mm_at(force_N) * 1e-3; }
    bool operator==(const YieldCurve&) const = default;
};

// "" when the curve is usable; else a one-line reason. `bad_point` (optional) receives the index
// of the offending point, or -1 when the fault is the curve as a whole.
std::string validate_yield_curve(const YieldCurve& curve, int* bad_point = nullptr);

// Named tissues of the pocket floor.
enum class TissuePreset { Healthy, Inflamed };
inline constexpr TissuePreset kAllTissuePresets[] = {TissuePreset::Healthy, TissuePreset::Inflamed};

// "healthy", "inflamed".
const char* tissue_preset_name(TissuePreset preset);
// Exact, lower case; false (out untouched) for any other name.
bool parse_tissue_preset(const std::string& name, TissuePreset* out);
// healthy: [[0,0],[0.25,0.05],[0.5,0.08],[1.0,0.12]]; inflamed: [[0,0],[0.25,0.5],[0.5,1.0],[1.0,1.25]].
const YieldCurve& tissue_preset_curve(TissuePreset preset);

// The tissue of one site: a preset or an authored curve.
struct Tissue {
    bool is_preset = true;
    TissuePreset preset = TissuePreset::Healthy;
    YieldCurve custom;  // when !is_preset
    static Tissue of(TissuePreset p) { return Tissue{true, p, {}}; }
    static Tissue of(const YieldCurve& c) { return Tissue{false, TissuePreset::Healthy, c}; }
    const YieldCurve& curve() const { return is_preset ? tissue_preset_curve(preset) : custom; }
    // "healthy", "inflamed" or "custom".
    std::string label() const { return is_preset ? tissue_preset_name(preset) : "custom"; }
    bool operator==(const Tissue&) const = default;
};

// Probing forces the tissue settings are stated at (reference §1.3): the tip rests at the charted
// floor at the first, and the trajectory pushes to the second.
inline constexpr double kRestingProbeForce_N = 0.25;
inline constexpr double kFirmProbeForce_N = 0.5;

}  // namespace sulcus
