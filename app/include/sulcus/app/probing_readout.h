// What the trainee sees and writes while probing a case: which site the probe is in and how deep
// (the depth its markings show), and the chart the trainee fills in, site by site, to compare with
// the case's reference chart. Headless: the desktop app draws these, the lesson runtime scores them.
#pragma once

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/engine/types.h"

#include <array>
#include <map>
#include <optional>
#include <vector>

namespace sulcus {

// Default capture radius of read_probe: the tip counts as at a site within this distance of the
// site's probe line (metres).
inline constexpr double kProbeCaptureRadius_m = 1.5e-3;
// How far above a site's margin the tip may be and still be read at that site (metres).
inline constexpr double kProbeAboveMargin_m = 1.0e-3;

struct ProbeReading {
    int site_index = -1;     // into the sites given to read_probe; -1: the tip is at no site
    // Below are meaningful when site_index >= 0.
    double depth_m = 0.0;    // tip end below the site's gingival margin along the tooth axis (the
                             // probing depth the markings show; negative above the margin)
    double lateral_m = 0.0;  // tip end's distance from the site's probe line
    double angle_rad = 0.0;  // between the probe's long axis (toward the handle) and the tooth's
                             // long axis (toward occlusal): 0 when held parallel, as charted
    bool in_sulcus = false;  // tip below the margin and within the capture radius of the line
};

// The site the probe is at, for a probe pose in the case frame (probe frame: tip end at the origin,
// +Y toward the handle). Among the sites whose probe line (through margin_point along axis) passes
// within `capture_radius_m` of the tip end, and with the tip end no more than 1 mm
// (kProbeAboveMargin_m) above their margin, the one whose line is nearest; -1 when there is none.
ProbeReading read_probe(const std::vector<SiteFrame>& sites, const Pose& probe_pose,
                        double capture_radius_m = kProbeCaptureRadius_m);

// The depth a clinician charts for a reading (metres): the nearest whole millimetre, a half
// rounding up (2.49 mm -> 2, 2.5 mm -> 3; within 1e-9 mm of a half counts as the half); 0 at or
// above the margin; at most kMaxProbingDepthMm. NaN for a depth that is not finite.
double chart_depth_mm(double depth_m);

// One site of ChartSession::compare.
struct SiteComparison {
    int fdi = 0;
    Site site = Site::MB;
    std::optional<double> trainee_pd_mm, reference_pd_mm;
    std::optional<double> difference_mm;  // trainee - reference, when both are charted
};

// The trainee's chart of a case: for every tooth of the reference chart, its six sites, each with
// an optional probing depth (mm, whole millimetres as recorded), a gingival margin (mm relative to
// the CEJ, negative = recession; 0 until set) and bleeding on probing.
class ChartSession {
public:
    // The teeth come from `reference` (the case's chart); nothing is charted yet.
    explicit ChartSession(const Chart& reference);

    // Whether the session has this tooth (and so its six sites).
    bool has_tooth(int fdi) const { return teeth_.count(fdi) > 0; }
    // Records a probing depth read off the probe (metres), rounded to the nearest whole millimetre
    // as clinicians chart, a half rounding up (2.49 mm -> 2, 2.5 mm -> 3; a value within 1e-9 mm
    // of a half counts as the half); a tip at or above the margin records 0, and nothing records
    // more than kMaxProbingDepthMm. Replaces an earlier reading. False (nothing recorded) for a tooth the session does not have or a depth that is
    // not finite.
    bool record_depth(int fdi, Site site, double depth_m);
    // The gingival margin (mm, kMinGingivalMarginMm..kMaxGingivalMarginMm) and bleeding of a site.
    // False (nothing changed) for an unknown tooth or a margin out of range.
    bool set_gm(int fdi, Site site, double gm_mm);
    bool set_bop(int fdi, Site site, bool bleeding);
    // Forgets a site's depth, margin and bleeding.
    void clear(int fdi, Site site);

    std::optional<double> pd_mm(int fdi, Site site) const;
    double gm_mm(int fdi, Site site) const;  // 0 when not set or unknown
    bool bop(int fdi, Site site) const;
    // Clinical attachment level, PD - GM (mm); empty until the depth is recorded.
    std::optional<double> cal_mm(int fdi, Site site) const;

    int sites_charted() const;  // sites with a recorded depth
    int sites_total() const;    // six per tooth

    // The trainee's chart (for chart_to_json): every tooth of the session, with the sites whose
    // depth is recorded (a margin or bleeding without a depth is not written: a chart site needs
    // its probing depth).
    Chart to_chart() const;
    // Every site of the session in chart order (FDI ascending, then kAllSites), with the difference
    // PD_trainee - PD_reference where both are charted.
    std::vector<SiteComparison> compare(const Chart& reference) const;

private:
    struct Entry {
        std::optional<double> pd_mm;
        double gm_mm = 0.0;
        bool bop = false;
    };
    Entry* find(int fdi, Site site);
    const Entry* find(int fdi, Site site) const;
    std::map<int, std::array<Entry, 6>> teeth_;  // keyed by FDI, indexed by Site
};

}  // namespace sulcus
