// A patient case from a periodontal chart: the charted teeth placed on a standard arch, the
// gingiva and alveolar bone shaped from the chart (margin, pocket floor and furcations at every
// site), the probing sites as frames, and the files that make it a runnable scene
// (docs/cases.md).
//
// Case frame: metres, +X toward the patient's left, +Y up, +Z anterior (out of the mouth);
// right-handed, +Y up as glTF. Lower teeth have their facial CEJ at y = 0 and point up; upper
// teeth have theirs at y = kUpperCejHeight and point down. The tooth frame of DESIGN.md (+X
// mesial, +Y occlusal, +Z buccal) is right-handed, so teeth of quadrants 1 and 3 reach the case
// frame through a mirror (x -> -x in the tooth frame) followed by a rotation.
#pragma once

#include "sulcus/content/asset.h"
#include "sulcus/content/chart.h"
#include "sulcus/content/probes.h"
#include "sulcus/content/tissue.h"
#include "sulcus/content/tooth.h"

#include <array>
#include <string>
#include <vector>

namespace sulcus {

inline constexpr double kUpperCejHeight = 0.022;  // metres

// Where a tooth sits: case = position + rotation * (mirror ? diag(-1, 1, 1) : I) * tooth.
struct ToothPlacement {
    int fdi = 0;
    Vec3 position;
    Quat rotation{1, 0, 0, 0};
    bool mirror = false;
    Vec3 to_case(const Vec3& tooth_point) const;
    Vec3 to_case_direction(const Vec3& tooth_direction) const;
    Vec3 to_tooth(const Vec3& case_point) const;
};
// The standard-arch placement of any supported tooth (contacts along a parabolic arch).
ToothPlacement arch_placement(int fdi);

// A probing site of the case: the straight probe, held parallel to the tooth's long axis, runs
// down the line through `margin_point` and `floor_point` (case frame, metres).
struct SiteFrame {
    int fdi = 0;
    Site site = Site::B;
    double theta_rad = 0.0;   // polar angle of the site in the tooth frame
    Vec3 margin_point;        // probe axis at the gingival margin
    Vec3 floor_point;         // probe axis at the charted pocket floor (pd below the margin): where
                              // the tip end rests at 0.25 N
    Vec3 axis;                // unit, the tooth's long axis toward occlusal (insertion is -axis)
    Vec3 outward;             // unit, horizontal, away from the tooth
    double pd_m = 0.0, gm_m = 0.0;
    // The floor's tissue (chart, or by bleeding: site_tissue) and where its yielding layer starts:
    // the gingiva's floor surface, depth_at(0.25 N) above the charted floor on the probe axis
    // (docs/cases.md; never less than 0.2 mm below the margin, so a pocket shallower than that
    // plus depth_at(0.25 N) rests deeper than charted: see rest_depth_m).
    Tissue tissue;
    Vec3 onset_point;
    double rest_depth_m = 0.0;          // margin to the tip end at 0.25 N along the axis (= pd_m)
    // The yielding layer is a block of its own under the site (a scene object in the tissue's
    // material, docs/cases.md): its flat top at the onset, this far either way along the pocket.
    double floor_half_width_m = 0.0;
};

struct CaseSettings {
    double probe_radius_m = 0.25e-3;     // radius of the probe tip the pocket is opened for
    // Radius of the probe's collision tip at heights 0, step, 2 step, ... above its end (a tapered
    // working end); empty = probe_radius_m all along. The pocket wall clears its widest part
    // within the pocket.
    std::vector<double> probe_profile_m;
    double probe_profile_step_m = 1e-4;
    double tooth_clearance_m = 0.05e-3;  // probe line to tooth (and neighbouring teeth)
    double wall_clearance_m = 0.08e-3;   // probe to the inner wall of the gingiva
    double gum_cell_m = 1.3e-4;          // polygonizer grid for gingiva (bone: twice as coarse)
    double gum_max_error_m = 1.0e-5;     // decimation bound for gingiva and bone
    double tooth_cell_m = 2.0e-4;        // polygonizer grid for the teeth (vertices on the surface)
    double tooth_max_error_m = 1.0e-5;   // decimation bound for the teeth
    bool bone = true;                    // build the alveolar bone (visual only)
};

struct PatientCase {
    Chart chart;
    std::vector<ToothPlacement> teeth;  // charted teeth, in chart order
    std::vector<SiteFrame> sites;       // six per tooth, in the order of kAllSites
    // Nodes: "tooth 36" (mesh in its tooth frame, placement in extras), "gingiva lower",
    // "bone lower", and the same for the upper jaw where charted. Every mesh in the case frame
    // except the teeth.
    Asset asset;
    // Closed meshes in the case frame for collision: one per tooth, one gingiva per jaw.
    std::vector<std::pair<std::string, TriMesh>> solids;
};

// The radius profile of a probe's collision tip (probe frame: tip end at the origin, +Y along the
// working end), sampled every `step` from the end, never decreasing: for CaseSettings.
std::vector<double> probe_radius_profile(const TriMesh& tip, double step_m = 1e-4);

// Materials of a case asset, in this order.
enum CaseMaterial : int { kMaterialEnamel = 0, kMaterialRoot = 1, kMaterialGingiva = 2, kMaterialBone = 3 };
const std::vector<Material>& case_materials();

// Builds the case; `chart` must pass check_chart_for_case. Throws std::invalid_argument with a
// one-line reason if the chart describes geometry that cannot be built.
PatientCase build_case(const Chart& chart, const CaseSettings& settings = {});

// The probing trajectory of a case: for every tooth and site, the probe (tip end at the probe
// frame origin, +Y toward the handle) comes down the site's line from above the crowns at
// `insert_speed_m_per_s`, goes on until the force would reach `force_N` (the haptic tip
// force_N / stiffness past where the graphic tip then rests, onset + depth_at(force_N), plus
// kProbeOvershootMargin_m), holds, and leaves upward (docs/cases.md).
struct ProbingPass {
    int fdi;
    Site site;
    double t_start, t_floor, t_end;  // seconds: descent start, haptic tip at the charted floor, back up
    double past_floor_m;             // how far the haptic tip goes past the charted floor
};
struct Trajectory {
    std::vector<std::pair<double, Pose>> samples;  // (t, haptic pose)
    std::vector<ProbingPass> passes;
};
inline constexpr double kProbeOvershootMargin_m = 0.1e-3;
Trajectory probing_trajectory(const PatientCase& c, double insert_speed_m_per_s = 6e-3,
                              double stiffness_N_per_m = 1000.0, double force_N = kFirmProbeForce_N);

// Materials of the case's scene (docs/tissue.md): the teeth and the gingiva's wall.
inline constexpr double kGingivaStiffness_N_per_m = 400.0;
inline constexpr double kToothFrictionStatic = 0.15, kToothFrictionKinetic = 0.10;
inline constexpr double kTissueFrictionStatic = 0.5, kTissueFrictionKinetic = 0.4;
// The floor regions of the scene accept gingiva faces within this angle of the tooth axis.
// The gingiva's own pocket floor lies this far below each site's yielding layer, so the tip meets
// the layer's flat top alone (docs/cases.md).
inline constexpr double kFloorLayerDepth = 2.0e-3;

// Writes a runnable case into `dir` (created if missing): scene.json (sulcus.scene/1: one object per
// tooth and gingiva with their materials and one floor region per site, the probe's collision
// (make_probe_collision) as the tool), one .glb per object, the tool as OBJ,
// probing.csv (the trajectory), case.glb (every node with its metadata, and the probe), chart.json,
// and case.json (sulcus.case/1: the sites and the probing passes). Returns "" or a one-line error.
std::string write_case(const PatientCase& c, ProbeKind probe, const std::string& dir);

}  // namespace sulcus
