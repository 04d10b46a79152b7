// A probe leaning in the compliant tissue of a full-resolution case: the bench's two-region
// session at 46 B (tip pressed into the pocket floor, side against the root, the gingiva's wall
// giving way along the shank). Every tick finds its answer in the pass it starts with, or one
// more: a contact where the tissue gives way counts as real where the tool really is that deep
// in it, not only on the face whose plane holds it, so the step does not run pass after pass
// (and then hold) on contacts that are there.
#include "cli/bench_scenes.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <string>

using namespace sulcus;

namespace {

TEST(CompliantSession, LeaningInTheTissueNeedsNoPassAfterPass) {
    cli::BenchScenes s = cli::load_bench_scenes({"quadrant_two_regions"}, std::string(SULCUS_SOURCE_DIR) + "/content/assets",
                                                std::string(SULCUS_BINARY_DIR) + "/cases");
    ASSERT_EQ(s.error, "");
    ASSERT_EQ(s.scenes.size(), 1u);
    const cli::BenchScene& b = s.scenes.front();
    RendererSettings settings;
    settings.haptic = b.scene.haptic;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    ASSERT_TRUE(mb.model) << mb.error;
    State state = make_state(b.ticks.front());
    int contact = 0, soft = 0, two_regions = 0, extra = 0, held = 0, most_passes = 0;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        const StepResult r = step(*mb.model, state, b.ticks[i]);
        held += r.status == StepStatus::Held;
        if (r.status != StepStatus::Contact) continue;
        ++contact;
        soft += r.stats.soft_zones > 0;
        two_regions += r.stats.regions >= 2;
        extra += r.stats.passes > 0;
        most_passes = std::max(most_passes, r.stats.passes);
    }
    // The session is what it says: in contact most of the time, in the tissue, in two regions.
    EXPECT_GT(contact, 4000);
    EXPECT_GT(soft, 4000);
    EXPECT_GT(two_regions, 2500);
    // No tick holds its last pose, none runs out of passes, and extra passes are rare.
    EXPECT_EQ(held, 0);
    EXPECT_LE(most_passes, 2);
    EXPECT_LE(extra, contact / 100);
}

}  // namespace
