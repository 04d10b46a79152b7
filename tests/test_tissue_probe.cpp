// The pocket-floor tissue settings as the step renders them: a probe tip pressed into a layer of
// each preset follows the documented depth-against-force curve, by the step's own account and by
// the exact geometric check.
#include "sulcus/app/tissue_probe.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sulcus {
namespace {

TEST(TissueProbe, EveryPresetRendersItsDocumentedCurve) {
    for (TissuePreset p : kAllTissuePresets) {
        SCOPED_TRACE(tissue_preset_name(p));
        const YieldCurve& curve = tissue_preset_curve(p);
        const TissueProbeRun run = probe_tissue(curve, ProbeKind::Williams, 1.0);
        ASSERT_EQ(run.error, "");
        ASSERT_GT(run.samples.size(), 500u);
        EXPECT_GT(run.samples.back().force_N, 1.0);
        double worst = 0.0, worst_exact = 0.0;
        for (const TissueProbeSample& s : run.samples) {
            worst = std::max(worst, std::abs(s.depth_m - curve.depth_m_at(s.force_N)));
            worst_exact = std::max(worst_exact, std::abs(s.exact_depth_m - curve.depth_m_at(s.force_N)));
        }
        EXPECT_LE(worst, 1e-9);
        EXPECT_LE(worst_exact, 1e-6);
    }
}

// The clinical statements the presets are tuned to (docs/tissue.md): a healthy floor barely
// yields between 0.20 and 0.25 N; an inflamed one lets the tip 0.5 mm further at 0.5 N than at
// 0.25 N.
TEST(TissueProbe, PresetsMeetTheirClinicalTargets) {
    const YieldCurve& healthy = tissue_preset_curve(TissuePreset::Healthy);
    const YieldCurve& inflamed = tissue_preset_curve(TissuePreset::Inflamed);
    EXPECT_LE(healthy.depth_mm_at(0.25) - healthy.depth_mm_at(0.20), 0.2);
    EXPECT_NEAR(inflamed.depth_mm_at(0.5) - inflamed.depth_mm_at(0.25), 0.5, 1e-12);
    EXPECT_LT(healthy.depth_mm_at(0.5) - healthy.depth_mm_at(0.25), 0.1);
}

}  // namespace
}  // namespace sulcus
