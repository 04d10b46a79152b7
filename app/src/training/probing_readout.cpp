// The probe's reading at a site and the trainee's chart.
#include "sulcus/app/probing_readout.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

ProbeReading read_probe(const std::vector<SiteFrame>& sites, const Pose& probe_pose, double capture_radius_m) {
    ProbeReading best;
    const Vec3 tip = probe_pose.position;
    const Vec3 probe_axis = glm::normalize(probe_pose.rotate(Vec3(0.0, 1.0, 0.0)));
    double best_lateral = INFINITY;
    for (std::size_t i = 0; i < sites.size(); ++i) {
        const SiteFrame& f = sites[i];
        const Vec3 axis = glm::normalize(f.axis);
        const Vec3 d = tip - f.margin_point;
        const double height = glm::dot(d, axis);  // above the margin, toward occlusal
        const double lateral = glm::length(d - height * axis);
        if (lateral > capture_radius_m || height > kProbeAboveMargin_m || !(lateral < best_lateral)) continue;
        best_lateral = lateral;
        best.site_index = static_cast<int>(i);
        best.depth_m = -height;
        best.lateral_m = lateral;
        best.angle_rad = std::acos(std::clamp(glm::dot(probe_axis, axis), -1.0, 1.0));
        best.in_sulcus = height < 0.0;
    }
    return best;
}

ChartSession::ChartSession(const Chart& reference) {
    for (const auto& [fdi, tooth] : reference.teeth) teeth_[fdi] = {};
}

ChartSession::Entry* ChartSession::find(int fdi, Site site) {
    const auto it = teeth_.find(fdi);
    return it == teeth_.end() ? nullptr : &it->second[static_cast<std::size_t>(site)];
}

const ChartSession::Entry* ChartSession::find(int fdi, Site site) const {
    const auto it = teeth_.find(fdi);
    return it == teeth_.end() ? nullptr : &it->second[static_cast<std::size_t>(site)];
}

double chart_depth_mm(double depth_m) {
    if (!std::isfinite(depth_m)) return NAN;
    // Nearest whole millimetre, halves up; the small allowance keeps 2.5 mm given as 0.0025 m a half.
    const double mm = std::max(0.0, depth_m * 1e3);
    return std::min(std::floor(mm + 0.5 + 1e-9), kMaxProbingDepthMm);
}

bool ChartSession::record_depth(int fdi, Site site, double depth_m) {
    Entry* e = find(fdi, site);
    if (!e || !std::isfinite(depth_m)) return false;
    e->pd_mm = chart_depth_mm(depth_m);
    return true;
}

bool ChartSession::set_gm(int fdi, Site site, double gm_mm) {
    Entry* e = find(fdi, site);
    if (!e || !(gm_mm >= kMinGingivalMarginMm && gm_mm <= kMaxGingivalMarginMm)) return false;
    e->gm_mm = gm_mm;
    return true;
}

bool ChartSession::set_bop(int fdi, Site site, bool bleeding) {
    Entry* e = find(fdi, site);
    if (!e) return false;
    e->bop = bleeding;
    return true;
}

void ChartSession::clear(int fdi, Site site) {
    if (Entry* e = find(fdi, site)) *e = Entry{};
}

std::optional<double> ChartSession::pd_mm(int fdi, Site site) const {
    const Entry* e = find(fdi, site);
    return e ? e->pd_mm : std::nullopt;
}

double ChartSession::gm_mm(int fdi, Site site) const {
    const Entry* e = find(fdi, site);
    return e ? e->gm_mm : 0.0;
}

bool ChartSession::bop(int fdi, Site site) const {
    const Entry* e = find(fdi, site);
    return e && e->bop;
}

std::optional<double> ChartSession::cal_mm(int fdi, Site site) const {
    const Entry* e = find(fdi, site);
    if (!e || !e->pd_mm) return std::nullopt;
    return *e->pd_mm - e->gm_mm;
}

int ChartSession::sites_charted() const {
    int n = 0;
    for (const auto& [fdi, entries] : teeth_)
        for (const Entry& e : entries) n += e.pd_mm.has_value();
    return n;
}

int ChartSession::sites_total() const { return static_cast<int>(teeth_.size() * kAllSites.size()); }

Chart ChartSession::to_chart() const {
    Chart c;
    for (const auto& [fdi, entries] : teeth_) {
        ToothRecord& t = c.teeth[fdi];
        t.fdi = fdi;
        for (Site s : kAllSites) {
            const Entry& e = entries[static_cast<std::size_t>(s)];
            if (!e.pd_mm) continue;
            SiteRecord r;
            r.pd_mm = *e.pd_mm;
            r.gm_mm = e.gm_mm;
            r.bop = e.bop;
            t.sites[static_cast<std::size_t>(s)] = r;
        }
    }
    return c;
}

std::vector<SiteComparison> ChartSession::compare(const Chart& reference) const {
    std::vector<SiteComparison> out;
    for (const auto& [fdi, entries] : teeth_) {
        const auto ref = reference.teeth.find(fdi);
        for (Site s : kAllSites) {
            SiteComparison c;
            c.fdi = fdi;
            c.site = s;
            c.trainee_pd_mm = entries[static_cast<std::size_t>(s)].pd_mm;
            if (ref != reference.teeth.end())
                if (const auto& r = ref->second.sites[static_cast<std::size_t>(s)]) c.reference_pd_mm = r->pd_mm;
            if (c.trainee_pd_mm && c.reference_pd_mm) c.difference_mm = *c.trainee_pd_mm - *c.reference_pd_mm;
            out.push_back(c);
        }
    }
    return out;
}

}  // namespace sulcus
