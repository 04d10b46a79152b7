// The step at constraint tolerances tighter than the default (1e-9 and 1e-10 m) on the bench's
// dense wedge. A feature pair of a rigid object further behind, at the step's start, than the
// recovery round's box can take the tool back out by (kRecoverTolerances tolerances) is not made
// an atom: the step's start is a checked pose, so such a pair says the tool is behind where it
// does not penetrate (edge pairs 0.36 um behind where the exact check finds 3e-17 m), and held
// as a constraint it left no feasible step: once wedged, the probe was held where it was for 205
// ticks at 1e-9 m.
#include "bench_scene_helpers.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

using namespace sulcus;

namespace {

// The probe wedged between two crowns is never held without a safe answer, and penetrates a
// crown by no more than the tolerance (checked exactly on every 10th tick in contact).
TEST(TightTolerance, WedgedProbeIsNeverHeldAndStaysWithinTheTolerance) {
    const cli::BenchScene b = test::load_bench_scene("dense_wedge_250k");
    ASSERT_GT(b.ticks.size(), 3000u);
    std::vector<PlacedMesh> objects;
    for (const auto& o : b.scene.objects) objects.push_back(PlacedMesh{&o.mesh, o.pose});
    const std::vector<TriMesh> pieces = connected_components(b.scene.tool.mesh);
    for (const double tol : {1e-9, 1e-10}) {
        RendererSettings settings;
        settings.constraint_tol_m = tol;
        const auto model = test::bench_model(b, settings);
        ASSERT_TRUE(model);
        State state = make_state(b.ticks.front());
        int held = 0, contact = 0, first_held = -1;
        double max_pen = 0.0;
        for (size_t i = 0; i < b.ticks.size(); ++i) {
            const StepResult r = step(*model, state, b.ticks[i]);
            if (r.status == StepStatus::Held && held++ == 0) first_held = int(i);
            if (r.status != StepStatus::Contact || ++contact % 10 != 0) continue;
            max_pen = std::max(max_pen, exact_check(pieces, r.graphic, objects, 0.0).penetration_m);
        }
        EXPECT_EQ(held, 0) << "tolerance " << tol << ": first held at tick " << first_held;
        EXPECT_GT(contact, 2000) << "tolerance " << tol;
        EXPECT_LE(max_pen, tol) << "tolerance " << tol;
        std::printf("dense wedge at %g m: %d ticks in contact, %d held, penetration at most %.3g m\n", tol, contact,
                    held, max_pen);
    }
}

}  // namespace
