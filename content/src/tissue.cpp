// Depth-against-force curves of the pocket floor and their presets (docs/tissue.md).
#include "sulcus/content/tissue.h"

#include "sulcus/engine/json_text.h"

#include <cmath>

namespace sulcus {

double YieldCurve::depth_mm_at(double force_N) const {
    const auto& p = points_N_mm;
    if (p.size() < 2 || !(force_N > 0.0)) return 0.0;
    size_t i = 1;
    while (i + 1 < p.size() && force_N > p[i][0]) ++i;
    // Segment [i-1, i]; beyond the last point the last segment's slope continues.
    const double f0 = p[i - 1][0], d0 = p[i - 1][1], f1 = p[i][0], d1 = p[i][1];
    return d0 + (force_N - f0) * (d1 - d0) / (f1 - f0);
}

std::string validate_yield_curve(const YieldCurve& curve, int* bad_point) {
    using textio::num;
    auto fail = [&](int i, const std::string& why) {
        if (bad_point) *bad_point = i;
        return why;
    };
    const auto& p = curve.points_N_mm;
    if (p.size() < 2) return fail(-1, "a yield curve needs at least two [force N, depth mm] points, from [0, 0]");
    for (size_t i = 0; i < p.size(); ++i)
        if (!std::isfinite(p[i][0]) || !std::isfinite(p[i][1])) return fail(int(i), "not a finite number");
    if (p[0][0] != 0.0 || p[0][1] != 0.0) return fail(0, "the first point must be [0, 0]");
    double last_slope = 0.0;
    for (size_t i = 1; i < p.size(); ++i) {
        if (!(p[i][0] > p[i - 1][0])) return fail(int(i), "force must increase strictly (" + num(p[i][0]) + " N after " + num(p[i - 1][0]) + " N)");
        if (!(p[i][1] > p[i - 1][1])) return fail(int(i), "depth must increase strictly (" + num(p[i][1]) + " mm after " + num(p[i - 1][1]) + " mm)");
        const double slope = (p[i][0] - p[i - 1][0]) / (p[i][1] - p[i - 1][1]);  // N/mm
        // The tissue stiffens as it is pressed (springs in series bottoming out): slopes never fall.
        // A relative tolerance lets equal slopes written in decimals through.
        if (i > 1 && slope < last_slope * (1.0 - 1e-9))
            return fail(int(i), "slope " + num(slope) + " N/mm is below the previous segment's " + num(last_slope) +
                                    " N/mm (the curve must stiffen)");
        last_slope = slope;
    }
    if (bad_point) *bad_point = -1;
    return "";
}

const char* tissue_preset_name(TissuePreset preset) {
    switch (preset) {
        case TissuePreset::Healthy: return "healthy";
        case TissuePreset::Inflamed: return "inflamed";
    }
    return "?";
}

bool parse_tissue_preset(const std::string& name, TissuePreset* out) {
    for (TissuePreset p : kAllTissuePresets)
        if (name == tissue_preset_name(p)) {
            if (out) *out = p;
            return true;
        }
    return false;
}

const YieldCurve& tissue_preset_curve(TissuePreset preset) {
    // Tuned to the force thresholds of reference §1.3 (docs/tissue.md): no published JE stiffness.
    static const YieldCurve healthy{{{0.0, 0.0}, {0.25, 0.05}, {0.5, 0.08}, {1.0, 0.12}}};
    static const YieldCurve inflamed{{{0.0, 0.0}, {0.25, 0.5}, {0.5, 1.0}, {1.0, 1.25}}};
    return preset == TissuePreset::Inflamed ? inflamed : healthy;
}

}  // namespace sulcus
