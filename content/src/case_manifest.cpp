// Reading `sulcus.case/1`: every field write_case writes for the sites and passes, checked one by
// one so a damaged file says exactly where it is wrong, and the chart it names.
#include "sulcus/content/case_manifest.h"

#include "sulcus/engine/json_text.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <utility>

namespace sulcus {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using textio::num;
using textio::one_line;
using textio::shown;

// Collects "file: path: what" lines; paths are written `sites[3].axis`.
struct Errors {
    std::string file;
    std::vector<std::string>* out;
    void add(const std::string& place, const std::string& what) const {
        out->push_back(one_line(file + ": " + place + ": " + what));
    }
};

std::string at(const std::string& place, const char* key) { return place + "." + key; }

// A required member; reports "missing" when absent.
const json* member(const Errors& e, const json& obj, const char* key, const std::string& place) {
    const auto it = obj.find(key);
    if (it == obj.end()) {
        e.add(at(place, key), "missing");
        return nullptr;
    }
    return &*it;
}

bool read_number(const Errors& e, const json& obj, const char* key, const std::string& place, double lo, double hi,
                 double* out) {
    const json* v = member(e, obj, key, place);
    if (!v) return false;
    if (!v->is_number() || !std::isfinite(v->get<double>()) || v->get<double>() < lo || v->get<double>() > hi) {
        std::string range = "expected a number";
        if (std::isfinite(lo) && std::isfinite(hi)) range += " in [" + num(lo) + ", " + num(hi) + "]";
        else if (std::isfinite(lo)) range += " >= " + num(lo);
        e.add(at(place, key), range + ", found " + shown(v->dump()));
        return false;
    }
    *out = v->get<double>();
    return true;
}

bool read_vec3(const Errors& e, const json& obj, const char* key, const std::string& place, bool unit, Vec3* out) {
    const json* v = member(e, obj, key, place);
    if (!v) return false;
    bool good = v->is_array() && v->size() == 3;
    for (std::size_t i = 0; good && i < 3; ++i)
        good = (*v)[i].is_number() && std::isfinite((*v)[i].get<double>());
    if (!good) {
        e.add(at(place, key), "expected 3 numbers, found " + shown(v->dump()));
        return false;
    }
    const Vec3 p((*v)[0].get<double>(), (*v)[1].get<double>(), (*v)[2].get<double>());
    if (unit && std::fabs(glm::length(p) - 1.0) > 1e-6) {
        e.add(at(place, key), "expected a unit vector, its length is " + num(glm::length(p)));
        return false;
    }
    *out = p;
    return true;
}

bool read_fdi(const Errors& e, const json& obj, const std::string& place, int* out) {
    const json* v = member(e, obj, "fdi", place);
    if (!v) return false;
    if (!v->is_number_integer() || !is_supported_tooth(int(v->get<int64_t>()))) {
        e.add(at(place, "fdi"), "expected a tooth number 11-17, 21-27, 31-37 or 41-47, found " + shown(v->dump()));
        return false;
    }
    *out = int(v->get<int64_t>());
    return true;
}

bool read_site_name(const Errors& e, const json& obj, const std::string& place, Site* out) {
    const json* v = member(e, obj, "site", place);
    if (!v) return false;
    if (!v->is_string() || !parse_site(v->get<std::string>(), out)) {
        e.add(at(place, "site"), "unknown site " + shown(v->is_string() ? v->get<std::string>() : v->dump()) +
                                     " (expected MB, B, DB, ML, L or DL)");
        return false;
    }
    return true;
}

// "healthy" | "inflamed" | {"yield_curve_N_mm": [[force N, depth mm], ...]}, as in the chart.
bool read_tissue(const Errors& e, const json& obj, const std::string& place, Tissue* out) {
    const json* v = member(e, obj, "tissue", place);
    if (!v) return false;
    const std::string here = at(place, "tissue");
    if (v->is_string()) {
        TissuePreset p;
        if (!parse_tissue_preset(v->get<std::string>(), &p)) {
            e.add(here, "unknown tissue " + shown(v->get<std::string>()) + " (expected \"healthy\" or \"inflamed\")");
            return false;
        }
        *out = Tissue::of(p);
        return true;
    }
    const auto c = v->is_object() ? v->find("yield_curve_N_mm") : v->end();
    if (!v->is_object() || c == v->end() || !c->is_array()) {
        e.add(here, "expected \"healthy\", \"inflamed\" or {\"yield_curve_N_mm\": [[force N, depth mm], ...]}, found " +
                        shown(v->dump()));
        return false;
    }
    YieldCurve curve;
    for (std::size_t i = 0; i < c->size(); ++i) {
        const json& pt = (*c)[i];
        if (!pt.is_array() || pt.size() != 2 || !pt[0].is_number() || !pt[1].is_number()) {
            e.add(here + ".yield_curve_N_mm[" + std::to_string(i) + "]",
                  "expected [force N, depth mm], found " + shown(pt.dump()));
            return false;
        }
        curve.points_N_mm.push_back({pt[0].get<double>(), pt[1].get<double>()});
    }
    int bad = -1;
    if (const std::string why = validate_yield_curve(curve, &bad); !why.empty()) {
        e.add(here + ".yield_curve_N_mm" + (bad >= 0 ? "[" + std::to_string(bad) + "]" : std::string()), why);
        return false;
    }
    *out = Tissue::of(curve);
    return true;
}

bool read_site(const Errors& e, const json& v, const std::string& place, SiteFrame* f) {
    if (!v.is_object()) {
        e.add(place, "expected an object (a site frame), found " + shown(v.dump()));
        return false;
    }
    bool ok = read_fdi(e, v, place, &f->fdi);
    ok &= read_site_name(e, v, place, &f->site);
    ok &= read_number(e, v, "theta_rad", place, -7.0, 7.0, &f->theta_rad);
    ok &= read_vec3(e, v, "margin_point", place, false, &f->margin_point);
    ok &= read_vec3(e, v, "floor_point", place, false, &f->floor_point);
    ok &= read_vec3(e, v, "onset_point", place, false, &f->onset_point);
    ok &= read_vec3(e, v, "axis", place, true, &f->axis);
    ok &= read_vec3(e, v, "outward", place, true, &f->outward);
    double pd_mm = 0.0, gm_mm = 0.0;
    ok &= read_number(e, v, "pd_mm", place, 0.0, kMaxProbingDepthMm, &pd_mm);
    ok &= read_number(e, v, "gm_mm", place, kMinGingivalMarginMm, kMaxGingivalMarginMm, &gm_mm);
    f->pd_m = pd_mm * 1e-3;
    f->gm_m = gm_mm * 1e-3;
    ok &= read_tissue(e, v, place, &f->tissue);
    ok &= read_number(e, v, "floor_half_width_m", place, 0.0, INFINITY, &f->floor_half_width_m);
    // Written since the floor layers; older files rest at the charted depth.
    f->rest_depth_m = f->pd_m;
    if (v.contains("depth_at_0_25_N_mm")) {
        double rest_mm = 0.0;
        ok &= read_number(e, v, "depth_at_0_25_N_mm", place, 0.0, INFINITY, &rest_mm);
        f->rest_depth_m = rest_mm * 1e-3;
    }
    return ok;
}

bool read_pass(const Errors& e, const json& v, const std::string& place, ProbingPass* p) {
    if (!v.is_object()) {
        e.add(place, "expected an object (a probing pass), found " + shown(v.dump()));
        return false;
    }
    *p = ProbingPass{};
    bool ok = read_fdi(e, v, place, &p->fdi);
    ok &= read_site_name(e, v, place, &p->site);
    ok &= read_number(e, v, "t_start", place, 0.0, INFINITY, &p->t_start);
    ok &= read_number(e, v, "t_floor", place, 0.0, INFINITY, &p->t_floor);
    ok &= read_number(e, v, "t_end", place, 0.0, INFINITY, &p->t_end);
    double past_mm = 0.0;
    ok &= read_number(e, v, "past_floor_mm", place, 0.0, INFINITY, &past_mm);
    p->past_floor_m = past_mm * 1e-3;
    if (ok && !(p->t_start <= p->t_floor && p->t_floor <= p->t_end)) {
        e.add(place, "expected t_start <= t_floor <= t_end, found " + num(p->t_start) + ", " + num(p->t_floor) +
                         ", " + num(p->t_end));
        ok = false;
    }
    return ok;
}

const json* array_member(const Errors& e, const json& doc, const char* key) {
    const auto it = doc.find(key);
    if (it == doc.end()) {
        e.add(key, "missing");
        return nullptr;
    }
    if (!it->is_array()) {
        e.add(key, "expected an array, found " + shown(it->dump()));
        return nullptr;
    }
    return &*it;
}

std::string site_label(int fdi, Site s) { return std::to_string(fdi) + " " + site_name(s); }

}  // namespace

CaseManifestLoad parse_case_manifest(const json& doc, const std::string& source, const std::string& dir) {
    CaseManifestLoad result;
    result.manifest.dir = dir;
    const Errors e{source, &result.errors};
    if (!doc.is_object()) {
        e.add("(top level)", "expected a JSON object");
        return result;
    }
    const auto format = doc.find("format");
    if (format == doc.end()) {
        e.add("format", std::string("missing (expected \"") + kCaseFormat + "\")");
        return result;
    }
    if (!format->is_string() || format->get<std::string>() != kCaseFormat) {
        e.add("format", "unknown format " + shown(format->is_string() ? format->get<std::string>() : format->dump()) +
                            " (expected " + kCaseFormat + ")");
        return result;
    }
    CaseManifest& m = result.manifest;
    // Informative names; the sites and passes stand without them.
    const std::pair<const char*, std::string*> names[] = {{"scene", &m.scene}, {"visual", &m.visual}, {"probe", &m.probe}};
    for (const auto& [key, out] : names) {
        const auto it = doc.find(key);
        if (it == doc.end()) continue;
        if (!it->is_string()) e.add(key, "expected a string, found " + shown(it->dump()));
        else *out = it->get<std::string>();
    }

    // The chart, relative to the manifest's folder.
    bool have_chart = false;
    if (const auto c = doc.find("chart"); c == doc.end()) {
        e.add("chart", "missing (the chart file's name)");
    } else if (!c->is_string() || c->get<std::string>().empty()) {
        e.add("chart", "expected a file name, found " + shown(c->dump()));
    } else {
        const std::string path = (fs::path(dir) / c->get<std::string>()).string();
        std::string text, why;
        json chart_doc;
        if (!textio::read_file(path, text, why)) {
            e.add("chart", "cannot read " + shown(path) + ": " + why);
        } else if (!textio::parse_json(path, text, chart_doc, why)) {
            result.errors.push_back(why);
        } else {
            ChartLoad chart = parse_chart(chart_doc, path);
            for (const std::string& s : chart.errors) result.errors.push_back(s);
            m.chart = std::move(chart.chart);
            have_chart = chart.ok();
        }
    }

    // Sites: each one charted, none twice.
    std::set<std::pair<int, Site>> seen;
    bool sites_read = false;  // every frame read: the passes can be checked against them
    if (const json* sites = array_member(e, doc, "sites")) {
        sites_read = true;
        for (std::size_t i = 0; i < sites->size(); ++i) {
            const std::string place = "sites[" + std::to_string(i) + "]";
            SiteFrame f;
            if (!read_site(e, (*sites)[i], place, &f)) {
                sites_read = false;
                continue;
            }
            if (!seen.insert({f.fdi, f.site}).second) {
                e.add(place, "site " + site_label(f.fdi, f.site) + " appears twice");
                continue;
            }
            if (have_chart) {
                const auto t = m.chart.teeth.find(f.fdi);
                if (t == m.chart.teeth.end() || !t->second.sites[std::size_t(f.site)])
                    e.add(place, "site " + site_label(f.fdi, f.site) + " is not in the chart");
            }
            m.sites.push_back(f);
        }
    }
    // Passes: each over a site of the manifest (not checked when a frame could not be read, so one
    // fault is not reported again at every pass over it).
    if (const json* passes = array_member(e, doc, "passes")) {
        for (std::size_t i = 0; i < passes->size(); ++i) {
            const std::string place = "passes[" + std::to_string(i) + "]";
            ProbingPass p;
            if (!read_pass(e, (*passes)[i], place, &p)) continue;
            if (sites_read && !seen.count({p.fdi, p.site}))
                e.add(place, "site " + site_label(p.fdi, p.site) + " has no frame in sites");
            m.passes.push_back(p);
        }
    }
    return result;
}

CaseManifestLoad load_case_manifest(const std::string& case_dir_or_json_path) {
    std::error_code ec;
    const bool is_dir = fs::is_directory(case_dir_or_json_path, ec);
    const fs::path file = is_dir ? fs::path(case_dir_or_json_path) / "case.json" : fs::path(case_dir_or_json_path);
    const std::string path = file.string();
    std::string dir = file.parent_path().string();
    if (dir.empty()) dir = ".";
    CaseManifestLoad result;
    result.manifest.dir = dir;
    std::string text, why;
    if (!textio::read_file(path, text, why)) {
        result.errors.push_back(one_line(path + ": " + why));
        return result;
    }
    json doc;
    if (!textio::parse_json(path, text, doc, why)) {
        result.errors.push_back(why);
        return result;
    }
    return parse_case_manifest(doc, path, dir);
}

}  // namespace sulcus
