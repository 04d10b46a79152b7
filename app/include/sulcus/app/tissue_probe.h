// Force against depth of a tissue setting, measured through the servo step: a probe's collision
// tip pressed slowly, straight down, into a flat compliant layer with the tissue's yield curve.
// For the force-depth plots in docs/ (sulcus-cli tissue) and the test that the step renders the
// documented curve.
#pragma once

#include "sulcus/content/probes.h"
#include "sulcus/content/tissue.h"

#include <string>
#include <vector>

namespace sulcus {

struct TissueProbeSample {
    double force_N = 0.0;       // normal force rendered (eq. 4)
    double depth_m = 0.0;       // how far the layer gives way at the solution (the step's slack)
    double exact_depth_m = 0.0; // how far the tip is inside the layer, by the exact check
};

struct TissueProbeRun {
    std::vector<TissueProbeSample> samples;  // one per servo tick in contact, force ascending
    std::string error;                       // one line when the run could not be made
};

// Presses the tip of `probe` into a layer of `curve` at 1 mm/s until the force exceeds
// `max_force_N`, with the scene defaults' haptic stiffness (1000 N/m) at 1 kHz.
TissueProbeRun probe_tissue(const YieldCurve& curve, ProbeKind probe, double max_force_N);

}  // namespace sulcus
