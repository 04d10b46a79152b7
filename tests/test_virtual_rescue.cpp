// Virtual contacts taken round within the pass (RendererSettings::rescue_virtual). A probe stroked
// along a dense rippled surface often ends a tick with a vertex slid past the edge of the face
// whose plane holds it; swapping that atom for what the vertex faces at the answer and solving
// again in the same box gives, tick for tick from the same state, the answers another pass of
// detect, gather and solve gives, without most of those passes.
#include "bench_scene_helpers.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/renderer.h"
#include "so3.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

using namespace sulcus;

namespace {

cli::BenchScene load(const std::string& name) { return test::load_bench_scene(name); }

std::unique_ptr<Model> model_for(const cli::BenchScene& b, bool rescue) {
    RendererSettings settings;
    settings.rescue_virtual = rescue;
    return test::bench_model(b, settings);
}

// Eq. 3's energy of an answer: how far the graphic tool is from the haptic tool.
double energy(const HapticSettings& h, const Pose& graphic, const Pose& haptic) {
    const Vec3 d = graphic.position - haptic.position;
    const Vec3 r = quat_log(graphic.orientation * glm::conjugate(haptic.orientation));
    return h.weight_translational * glm::dot(d, d) + h.weight_rotational * glm::dot(r, r);
}

bool same_bits(const StepResult& a, const StepResult& b) {
    return std::memcmp(&a.graphic.position, &b.graphic.position, sizeof(Vec3)) == 0 &&
           std::memcmp(&a.graphic.orientation, &b.graphic.orientation, sizeof(Quat)) == 0 &&
           std::memcmp(&a.force_N, &b.force_N, sizeof(Vec3)) == 0 && a.status == b.status;
}

}  // namespace

// Along the dense wedge's probing, each tick is stepped from the same state with and without the
// rescue. Where the tick needed no further pass, nothing changes, to the bit. Where it did, the
// rescue takes most of those ticks round within the pass, to answers of the same status, as close
// to the haptic tool (eq. 3's energy, to the tolerance's give) and within micrometres of the other
// pass's; where they are further apart than the tolerance, the rescue's has less energy (it went
// further round). No penetration.
TEST(VirtualRescue, DenseWedgeNeedsFarFewerPassesForTheSameAnswers) {
    const cli::BenchScene b = load("dense_wedge_250k");
    ASSERT_GT(b.ticks.size(), 3000u);
    const auto with = model_for(b, true), without = model_for(b, false);
    std::vector<PlacedMesh> objects;
    for (const SceneObject& o : b.scene.objects) objects.push_back(PlacedMesh{&o.mesh, o.pose});
    const std::vector<TriMesh> pieces = connected_components(b.scene.tool.mesh);
    const HapticSettings& h = b.scene.haptic;

    State state = make_state(b.ticks.front());
    const double s_tol = with->settings.constraint_tol_m;
    int passes_without = 0, passes_with = 0, rescued = 0, compared = 0, unchanged = 0, apart_higher = 0;
    double worst_energy = 0.0, max_dp = 0.0, max_df = 0.0, max_pen = 0.0;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        State copy = state;
        const StepResult off = step(*without, state, b.ticks[i]);
        const bool passed = off.stats.passes > 0;
        // Every tick that took another pass, and every 25th of the others in contact.
        if (!passed && !(off.status == StepStatus::Contact && i % 25 == 0)) continue;
        const StepResult on = step(*with, copy, b.ticks[i]);
        if (!passed) {
            EXPECT_TRUE(same_bits(on, off)) << "tick " << i;
            unchanged += same_bits(on, off);
            continue;
        }
        ++compared;
        passes_without += off.stats.passes;
        passes_with += on.stats.passes;
        rescued += on.stats.rescues > 0;
        EXPECT_EQ(on.status, off.status) << "tick " << i;
        const double e_on = energy(h, on.graphic, b.ticks[i]), e_off = energy(h, off.graphic, b.ticks[i]);
        worst_energy = std::max(worst_energy, (e_on - e_off) / e_off);
        const double dp = glm::length(on.graphic.position - off.graphic.position);
        // Apart by more than the tolerance: the rescue went further round, to less energy.
        if (dp > s_tol && e_on > e_off) ++apart_higher;
        max_dp = std::max(max_dp, dp);
        max_df = std::max(max_df, glm::length(on.force_N - off.force_N));
        max_pen = std::max(max_pen, exact_check(pieces, on.graphic, objects, 0.0).penetration_m);
    }
    std::printf("ticks with another pass: %d (%d passes); with the rescue %d passes, %d ticks rescued; "
                "energy at most %.3g higher, %.3g m and %.3g N apart, penetration %.3g m; %d unchanged\n",
                compared, passes_without, passes_with, rescued, worst_energy, max_dp, max_df, max_pen, unchanged);
    EXPECT_GE(compared, 50);
    EXPECT_GE(unchanged, 50);
    EXPECT_LE(passes_with * 5, passes_without);
    EXPECT_GE(rescued * 5, compared * 4);
    EXPECT_LE(worst_energy, 5e-4);
    EXPECT_EQ(apart_higher, 0);
    EXPECT_LE(max_dp, 2e-6);
    EXPECT_LE(max_df, 2e-3);
    EXPECT_LE(max_pen, 1e-7);
}
