// Virtual contacts taken round within the pass (RendererSettings::rescue_virtual). A probe stroked
// along a dense rippled surface often ends a tick with a vertex slid past the edge of the face
// whose plane holds it; swapping that atom for what the vertex faces at the answer and solving
// again in the same box gives, tick for tick from the same state, the answers another pass of
// detect, gather and solve gives, without most of those passes. A probe's edge laid across a
// tooth's ridge of short edges likewise, by the edges at the end its contact slid past.
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

// Along a bench scene's probing, each tick is stepped from the same state with and without the
// rescue. Where the tick needed no further pass, nothing changes, to the bit. Where it did, the
// rescue takes most of those ticks round within the pass, to answers of the same status, as close
// to the haptic tool (eq. 3's energy, to the tolerance's give) and within micrometres of the other
// pass's; where they are further apart than the tolerance, the rescue's has less energy (it went
// further round). No penetration of a rigid object.
struct RescueCounts {
    int compared = 0, unchanged = 0, passes_without = 0, passes_with = 0, rescued = 0, apart_higher = 0;
    double worst_energy = 0.0, max_dp = 0.0, max_df = 0.0, max_pen = 0.0;
};

RescueCounts compare_rescue(const std::string& name) {
    RescueCounts n;
    const cli::BenchScene b = load(name);
    EXPECT_GT(b.ticks.size(), 3000u) << name;
    const auto with = model_for(b, true), without = model_for(b, false);
    std::vector<PlacedMesh> objects;
    for (size_t k = 0; k < b.scene.objects.size(); ++k)
        if (!with->objects[k].compliant) objects.push_back(PlacedMesh{&b.scene.objects[k].mesh, b.scene.objects[k].pose});
    const std::vector<TriMesh> pieces = connected_components(b.scene.tool.mesh);
    const HapticSettings& h = b.scene.haptic;

    State state = make_state(b.ticks.front());
    const double s_tol = with->settings.constraint_tol_m;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        State copy = state;
        const StepResult off = step(*without, state, b.ticks[i]);
        const bool passed = off.stats.passes > 0;
        // Every tick that took another pass, and every 25th of the others in contact.
        if (!passed && !(off.status == StepStatus::Contact && i % 25 == 0)) continue;
        const StepResult on = step(*with, copy, b.ticks[i]);
        if (!passed) {
            EXPECT_TRUE(same_bits(on, off)) << name << " tick " << i;
            n.unchanged += same_bits(on, off);
            continue;
        }
        ++n.compared;
        n.passes_without += off.stats.passes;
        n.passes_with += on.stats.passes;
        n.rescued += on.stats.rescues > 0;
        EXPECT_EQ(on.status, off.status) << name << " tick " << i;
        const double e_on = energy(h, on.graphic, b.ticks[i]), e_off = energy(h, off.graphic, b.ticks[i]);
        n.worst_energy = std::max(n.worst_energy, (e_on - e_off) / e_off);
        const double dp = glm::length(on.graphic.position - off.graphic.position);
        // Apart by more than the tolerance: the rescue went further round, to less energy.
        if (dp > s_tol && e_on > e_off) ++n.apart_higher;
        n.max_dp = std::max(n.max_dp, dp);
        n.max_df = std::max(n.max_df, glm::length(on.force_N - off.force_N));
        n.max_pen = std::max(n.max_pen, exact_check(pieces, on.graphic, objects, 0.0).penetration_m);
    }
    std::printf("%s: ticks with another pass: %d (%d passes); with the rescue %d passes, %d ticks rescued; "
                "energy at most %.3g higher, %.3g m and %.3g N apart, penetration %.3g m; %d unchanged\n",
                name.c_str(), n.compared, n.passes_without, n.passes_with, n.rescued, n.worst_energy, n.max_dp,
                n.max_df, n.max_pen, n.unchanged);
    return n;
}

}  // namespace

TEST(VirtualRescue, DenseWedgeNeedsFarFewerPassesForTheSameAnswers) {
    const RescueCounts n = compare_rescue("dense_wedge_250k");
    EXPECT_GE(n.compared, 50);
    EXPECT_GE(n.unchanged, 50);
    EXPECT_LE(n.passes_with * 5, n.passes_without);
    EXPECT_GE(n.rescued * 5, n.compared * 4);
    EXPECT_LE(n.worst_energy, 5e-4);
    EXPECT_EQ(n.apart_higher, 0);
    EXPECT_LE(n.max_dp, 2e-6);
    EXPECT_LE(n.max_df, 2e-3);
    EXPECT_LE(n.max_pen, 1e-7);
}

// In the two-region session the probe's edge lies across a ridge of the tooth's short edges: each
// E-E atom whose lines meet beyond the object edge's end is swapped for that end's F-V atom and
// the tool edge against the end's other convex edges, as gather pairs them, and every such tick
// is taken round within its pass.
TEST(VirtualRescue, TwoRegionSessionTakesTheProbeAcrossTheToothsEdgesWithinThePass) {
    const RescueCounts n = compare_rescue("quadrant_two_regions");
    EXPECT_GE(n.compared, 5);
    EXPECT_GE(n.unchanged, 50);
    EXPECT_EQ(n.passes_with, 0);
    EXPECT_EQ(n.rescued, n.compared);
    EXPECT_LE(n.worst_energy, 5e-4);
    EXPECT_EQ(n.apart_higher, 0);
    EXPECT_LE(n.max_dp, 2e-6);
    EXPECT_LE(n.max_df, 2e-3);
    EXPECT_LE(n.max_pen, 1e-7);
}
