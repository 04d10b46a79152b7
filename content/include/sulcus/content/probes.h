// Periodontal probes as tools: the marking tables of the common probes (reference file §1.1-1.2,
// docs/probes.md), the collision shape for the haptic step (a convex working tip and convex pieces
// for the rest of the probe) and a drawable body.
//
// Probe frame: origin at the end point of the tip (the most distal point of the rounded or ball
// tip), +Y along the working end toward the handle, the shank bends (and the Nabers curve) in the
// XY plane. Distances along the probe ("u") are measured from the tip end along the centreline of
// the working end, which is what the markings read; for straight probes u is simply y.
#pragma once

#include "sulcus/content/asset.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <string>
#include <vector>

namespace sulcus {

enum class ProbeKind { Williams, Unc15, Cpi, Marquis, Nabers };
inline constexpr ProbeKind kAllProbeKinds[] = {ProbeKind::Williams, ProbeKind::Unc15, ProbeKind::Cpi,
                                               ProbeKind::Marquis, ProbeKind::Nabers};

// "williams", "unc15", "cpi", "marquis", "nabers" (exact, lower case).
bool parse_probe_kind(const std::string& name, ProbeKind* out);
const char* probe_kind_name(ProbeKind kind);

// Materials a probe is drawn with; ProbeMark::material indexes this list.
enum ProbeMaterial : int { kProbeSteel = 0, kProbeHandle = 1, kProbeMarkBlack = 2 };
const std::vector<Material>& probe_materials();

// A coloured ring or band on the working end, from_m < to_m along the centreline from the tip end.
struct ProbeMark {
    double from_m, to_m;
    int material;  // ProbeMaterial
};

struct ProbeSpec {
    ProbeKind kind;
    std::string display_name;
    double tip_diameter_m;       // diameter of the rounded (or ball) tip
    bool ball_tip;               // a ball wider than the shaft just behind it (WHO / CPI)
    double working_length_m;     // tip end to the start of the shank, along the centreline
    std::vector<double> graduations_m;  // the readable positions: centres of thin rings, edges of bands
    std::vector<ProbeMark> marks;       // what is drawn (steel sections between bands are the body)
    double shank_diameter_m;     // working-end diameter where it meets the shank
    double neck_diameter_m;      // ball tips: narrowest diameter behind the ball; else = tip diameter
    double curve_radius_m;       // 0: straight working end; else the arc radius (bends toward +X)
    double collision_length_m;   // length of working end (from the tip end) the collision tip covers
    std::vector<std::string> sources;  // as named in the reference file
};

const ProbeSpec& probe_spec(ProbeKind kind);

// Centreline of the probe body at distance u_m from the tip end (u beyond the working length
// follows the shank); optional unit tangent. The body is a sweep of circles around this line.
Vec3 probe_centreline(const ProbeSpec& spec, double u_m, Vec3* tangent = nullptr);
// Radius of the working end's circular cross-section at u_m (0 <= u_m <= working length): the
// rounded tip (measured along the axis), then a straight taper to the shank diameter.
double probe_body_radius(const ProbeSpec& spec, double u_m);

// Collision description: the convex working tip in the probe frame, closed and outward (see
// docs/probes.md). Straight probes: a sphere cap of the tip radius whose pole is the origin,
// continued by the tangent frustum of the taper to the collision length. Nabers: the convex hull of
// the distal piece of the curved working end.
TriMesh make_probe_tip_collision(ProbeKind kind);

// The whole probe as a tool: closed, outward, convex pieces in the probe frame, each following the
// drawn body within 0.05 mm: the working tip (make_probe_tip_collision) first, then the rest of
// the working end (Nabers), the shank (a frustum per straight run, bends and curves as short
// hulls) and the handle (the ferrule's two frustums, the grip). Pieces may overlap.
std::vector<TriMesh> make_probe_collision_pieces(ProbeKind kind);
// The pieces as one mesh whose connected components are the pieces, in that order (the scene's
// tool, sulcus.scene/1).
TriMesh make_probe_collision(ProbeKind kind);

// Visual: one node "probe <kind>" with closed parts for the steel body (tip, working end, shank),
// the handle (ferrule and grip) and the marks (one part per mark colour: rings a few micrometres
// proud of the body); materials are added to `asset` (reused when an equal one of the same name is
// there). Extras: "probe", "display_name", "tip_diameter_m", "ball_tip", "marks_mm" (graduations),
// "bands_mm" ([from, to] of every drawn mark), "frame", "collision" (make_probe_collision's mesh,
// its piece count, the tip's shape and length).
AssetNode make_probe_node(ProbeKind kind, Asset& asset);

// Marks stand this far proud of the body surface (metres).
inline constexpr double kProbeMarkProud_m = 5e-6;

}  // namespace sulcus
