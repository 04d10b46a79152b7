// Charts built in code for the case tests: sites, whole teeth alike, and quick case settings
// (coarse cells, no bone) that keep a case build to seconds.
#pragma once

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/content/probes.h"

#include <vector>

namespace sulcus::test {

inline SiteRecord site_record(double pd_mm, double gm_mm, bool bop) {
    SiteRecord r;
    r.pd_mm = pd_mm;
    r.gm_mm = gm_mm;
    r.bop = bop;
    return r;
}

inline Chart uniform_chart(const std::vector<int>& teeth, double pd, double gm) {
    Chart c;
    for (int fdi : teeth) {
        ToothRecord t;
        t.fdi = fdi;
        for (Site s : kAllSites) t.sites[size_t(s)] = site_record(pd, gm, false);
        c.teeth[fdi] = t;
    }
    return c;
}

inline CaseSettings quick_settings() {
    CaseSettings s;
    s.gum_cell_m = 1.5e-4;
    s.tooth_cell_m = 2e-4;
    s.bone = false;
    s.probe_profile_m = probe_radius_profile(make_probe_tip_collision(ProbeKind::Williams), s.probe_profile_step_m);
    return s;
}

}  // namespace sulcus::test
