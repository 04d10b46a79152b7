// A probe tip pressed into a flat compliant layer: the force-depth curve the step renders.
#include "sulcus/app/tissue_probe.h"

#include "sulcus/content/primitives.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/renderer.h"

#include <cmath>

namespace sulcus {

TissueProbeRun probe_tissue(const YieldCurve& curve, ProbeKind probe, double max_force_N) {
    TissueProbeRun run;
    if (std::string why = validate_yield_curve(curve); !why.empty()) {
        run.error = "tissue curve: " + why;
        return run;
    }
    ContactMaterial layer;
    layer.name = "layer";
    layer.compliant = true;
    for (size_t i = 1; i < curve.points_N_mm.size(); ++i)
        layer.yield_curve.push_back({curve.points_N_mm[i][0], curve.points_N_mm[i][1] * 1e-3});
    // A 20 mm slab, its top at y = 0; the probe upright (its frame's +Y up), tip end lowest.
    SceneObject slab;
    slab.name = "layer";
    slab.mesh = make_box(Vec3(10e-3, 2e-3, 10e-3), Vec3(0.0, -2e-3, 0.0));
    slab.material = 0;
    const TriMesh tip = make_probe_tip_collision(probe);
    ModelBuild b = build_model(tip, {slab}, RendererSettings{}, {layer});
    if (!b.model) {
        run.error = b.error;
        return run;
    }
    const Model& model = *b.model;
    const double K = model.settings.haptic.stiffness_N_per_m;
    const double start = 0.1e-3, speed = 1e-3, rate = 1000.0;
    // Far enough down for the force to pass max_force_N: its depth plus the spring's stretch.
    const double travel = start + curve.depth_m_at(max_force_N) + max_force_N / K + 0.05e-3;
    const long ticks = long(std::ceil(travel / speed * rate));
    const std::vector<PlacedMesh> placed = {PlacedMesh{&model.objects[0].mesh, Pose{}}};
    State state = make_state(Pose{Vec3(0.0, start, 0.0), Quat(1, 0, 0, 0)});
    for (long i = 0; i <= ticks; ++i) {
        const Pose h{Vec3(0.0, start - speed * double(i) / rate, 0.0), Quat(1, 0, 0, 0)};
        const StepResult r = step(model, state, h);
        if (r.status == StepStatus::Held || !std::isfinite(r.force_N.y)) {
            run.error = "step " + std::to_string(i) + ": no safe answer (" + to_string(r.status) + ")";
            return run;
        }
        if (r.contacts == 0) continue;
        TissueProbeSample s;
        s.force_N = glm::length(r.force_N);
        s.depth_m = r.stats.soft_depth_m;
        s.exact_depth_m = exact_check(tip, r.graphic, placed, 0.0).penetration_m;
        run.samples.push_back(s);
        if (s.force_N > max_force_N) break;
    }
    return run;
}

}  // namespace sulcus
