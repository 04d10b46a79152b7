// Reading, checking and writing `sulcus.chart/1`. Every fault is reported (not only the first), each
// as one line naming the file and the JSON pointer of the value.
#include "sulcus/content/chart.h"

#include "sulcus/engine/json_text.h"

#include <cmath>

namespace sulcus {

using json = nlohmann::json;
using textio::num;
using textio::one_line;
using textio::Reporter;
using textio::pointer_token;
using textio::shown;

namespace {

bool valid_permanent_fdi(int fdi) { return fdi / 10 >= 1 && fdi / 10 <= 4 && fdi % 10 >= 1 && fdi % 10 <= 8; }

// "36" -> 36; rejects "036", "3.6", "".
bool parse_fdi_key(const std::string& key, int* out) {
    if (key.size() != 2 || key[0] < '1' || key[0] > '9' || key[1] < '0' || key[1] > '9') return false;
    *out = (key[0] - '0') * 10 + (key[1] - '0');
    return true;
}

bool parse_furcation_side(const std::string& s, FurcationSide* out) {
    static const std::pair<const char*, FurcationSide> names[] = {
        {"B", FurcationSide::B}, {"L", FurcationSide::L}, {"M", FurcationSide::M}, {"D", FurcationSide::D}};
    for (const auto& [n, side] : names)
        if (s == n) {
            *out = side;
            return true;
        }
    return false;
}

void read_number(const Reporter& r, const json& obj, const char* key, const std::string& place, double lo,
                 double hi, const char* unit, double* out, bool required) {
    const auto it = obj.find(key);
    const std::string here = place + "/" + key;
    if (it == obj.end()) {
        if (required) r.error(here, "missing");
        return;
    }
    if (!it->is_number() || !std::isfinite(it->get<double>()) || it->get<double>() < lo || it->get<double>() > hi) {
        r.error(here, std::string("expected a number in [") + num(lo) + ", " + num(hi) + "] " + unit + ", found " +
                          shown(it->dump()));
        return;
    }
    *out = it->get<double>();
}

void read_flag(const Reporter& r, const json& obj, const char* key, const std::string& place, bool* out) {
    const auto it = obj.find(key);
    if (it == obj.end()) return;
    if (!it->is_boolean()) {
        r.error(place + "/" + key, "expected true or false, found " + shown(it->dump()));
        return;
    }
    *out = it->get<bool>();
}

// "tissue": "healthy" | "inflamed" | {"yield_curve_N_mm": [[force N, depth mm], ...]}.
void read_tissue(const Reporter& r, const json& obj, const std::string& place, std::optional<Tissue>* out) {
    const auto it = obj.find("tissue");
    if (it == obj.end()) return;
    const std::string here = place + "/tissue";
    const char* expected = "expected \"healthy\", \"inflamed\" or {\"yield_curve_N_mm\": [[force N, depth mm], ...]}";
    if (it->is_string()) {
        TissuePreset p;
        if (!parse_tissue_preset(it->get<std::string>(), &p)) {
            r.error(here, "unknown tissue " + shown(it->get<std::string>()) + " (" + expected + ")");
            return;
        }
        *out = Tissue::of(p);
        return;
    }
    if (!it->is_object()) {
        r.error(here, std::string(expected) + ", found " + shown(it->dump()));
        return;
    }
    for (auto k = it->begin(); k != it->end(); ++k)
        if (k.key() != "yield_curve_N_mm") r.warning(here + "/" + pointer_token(k.key()), "unknown key (ignored)");
    const auto c = it->find("yield_curve_N_mm");
    const std::string cplace = here + "/yield_curve_N_mm";
    if (c == it->end()) {
        r.error(cplace, "missing");
        return;
    }
    if (!c->is_array()) {
        r.error(cplace, "expected an array of [force N, depth mm] points, found " + shown(c->dump()));
        return;
    }
    YieldCurve curve;
    for (size_t i = 0; i < c->size(); ++i) {
        const json& pt = (*c)[i];
        if (!pt.is_array() || pt.size() != 2 || !pt[0].is_number() || !pt[1].is_number()) {
            r.error(cplace + "/" + std::to_string(i), "expected [force N, depth mm], found " + shown(pt.dump()));
            return;
        }
        curve.points_N_mm.push_back({pt[0].get<double>(), pt[1].get<double>()});
    }
    int bad = -1;
    const std::string why = validate_yield_curve(curve, &bad);
    if (!why.empty()) {
        r.error(bad >= 0 ? cplace + "/" + std::to_string(bad) : cplace, why);
        return;
    }
    *out = Tissue::of(curve);
}

void read_site(const Reporter& r, const json& v, const std::string& place, SiteRecord* site) {
    if (!v.is_object()) {
        r.error(place, "expected an object with pd_mm");
        return;
    }
    for (auto it = v.begin(); it != v.end(); ++it) {
        static const char* known[] = {"pd_mm", "gm_mm", "bop", "suppuration", "plaque", "calculus", "tissue"};
        if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return it.key() == k; }) ==
            std::end(known))
            r.warning(place + "/" + pointer_token(it.key()), "unknown key (ignored)");
    }
    read_number(r, v, "pd_mm", place, 0.0, kMaxProbingDepthMm, "mm", &site->pd_mm, true);
    read_number(r, v, "gm_mm", place, kMinGingivalMarginMm, kMaxGingivalMarginMm, "mm", &site->gm_mm, false);
    read_flag(r, v, "bop", place, &site->bop);
    read_flag(r, v, "suppuration", place, &site->suppuration);
    read_flag(r, v, "plaque", place, &site->plaque);
    read_flag(r, v, "calculus", place, &site->calculus);
    read_tissue(r, v, place, &site->tissue);
}

void read_tooth(const Reporter& r, const json& v, const std::string& place, ToothRecord* tooth) {
    if (!v.is_object()) {
        r.error(place, "expected an object with \"sites\"");
        return;
    }
    for (auto it = v.begin(); it != v.end(); ++it)
        if (it.key() != "sites" && it.key() != "mobility" && it.key() != "furcation")
            r.warning(place + "/" + pointer_token(it.key()), "unknown key (ignored)");
    const auto sites = v.find("sites");
    if (sites == v.end()) {
        r.error(place + "/sites", "missing");
    } else if (!sites->is_object()) {
        r.error(place + "/sites", "expected an object keyed by site (MB, B, DB, ML, L, DL)");
    } else {
        for (auto it = sites->begin(); it != sites->end(); ++it) {
            const std::string here = place + "/sites/" + pointer_token(it.key());
            Site s;
            if (!parse_site(it.key(), &s)) {
                r.error(here, "unknown site " + shown(it.key()) + " (expected MB, B, DB, ML, L or DL)");
                continue;
            }
            SiteRecord rec;
            read_site(r, it.value(), here, &rec);
            tooth->sites[size_t(s)] = rec;
        }
    }
    if (const auto m = v.find("mobility"); m != v.end()) {
        if (!m->is_number_integer() || m->get<int64_t>() < 0 || m->get<int64_t>() > 3)
            r.error(place + "/mobility", "expected an integer 0-3, found " + shown(m->dump()));
        else
            tooth->mobility = int(m->get<int64_t>());
    }
    if (const auto f = v.find("furcation"); f != v.end()) {
        if (!f->is_object()) {
            r.error(place + "/furcation", "expected an object keyed by entrance (B, L, M, D)");
            return;
        }
        const std::vector<FurcationSide> allowed = furcation_sides(tooth->fdi);
        for (auto it = f->begin(); it != f->end(); ++it) {
            const std::string here = place + "/furcation/" + pointer_token(it.key());
            FurcationSide side;
            if (!parse_furcation_side(it.key(), &side)) {
                r.error(here, "unknown furcation entrance " + shown(it.key()) + " (expected B, L, M or D)");
                continue;
            }
            if (std::find(allowed.begin(), allowed.end(), side) == allowed.end()) {
                std::string list;
                for (FurcationSide a : allowed) list += std::string(list.empty() ? "" : ", ") + furcation_side_name(a);
                r.error(here, "tooth " + std::to_string(tooth->fdi) + " has no " + it.key() + " furcation" +
                                  (list.empty() ? " (it has a single root)" : " (entrances: " + list + ")"));
                continue;
            }
            if (!it->is_number_integer() || it->get<int64_t>() < 0 || it->get<int64_t>() > 4) {
                r.error(here, "expected a grade 0-4, found " + shown(it->dump()));
                continue;
            }
            tooth->furcation[side] = int(it->get<int64_t>());
        }
    }
}

}  // namespace

Tissue site_tissue(const SiteRecord& site) {
    if (site.tissue) return *site.tissue;
    return Tissue::of(site.bop ? TissuePreset::Inflamed : TissuePreset::Healthy);
}

const char* furcation_side_name(FurcationSide s) {
    switch (s) {
        case FurcationSide::B: return "B";
        case FurcationSide::L: return "L";
        case FurcationSide::M: return "M";
        case FurcationSide::D: return "D";
    }
    return "?";
}

std::vector<FurcationSide> furcation_sides(int fdi) {
    const int quadrant = fdi / 10, pos = fdi % 10;
    const bool upper = quadrant == 1 || quadrant == 2;
    if (pos >= 6 && pos <= 8) {
        if (upper) return {FurcationSide::B, FurcationSide::M, FurcationSide::D};
        return {FurcationSide::B, FurcationSide::L};
    }
    if (pos == 4 && upper) return {FurcationSide::M, FurcationSide::D};
    return {};
}

ChartLoad parse_chart(const json& doc, const std::string& source) {
    ChartLoad result;
    const Reporter r{source, &result.errors, &result.warnings};
    if (!doc.is_object()) {
        r.error("(top level)", "expected a JSON object");
        return result;
    }
    const auto format = doc.find("format");
    if (format == doc.end()) {
        r.error("/format", std::string("missing (expected \"") + kChartFormat + "\")");
        return result;
    }
    if (!format->is_string() || format->get<std::string>() != kChartFormat) {
        r.error("/format", "unknown format " + shown(format->is_string() ? format->get<std::string>() : format->dump()) +
                               " (expected " + kChartFormat + ")");
        return result;
    }
    for (auto it = doc.begin(); it != doc.end(); ++it)
        if (it.key() != "format" && it.key() != "teeth" && it.key() != "patient" && it.key() != "notes")
            r.warning("/" + pointer_token(it.key()), "unknown key (ignored)");
    const auto teeth = doc.find("teeth");
    if (teeth == doc.end()) {
        r.error("/teeth", "missing");
        return result;
    }
    if (!teeth->is_object()) {
        r.error("/teeth", "expected an object keyed by FDI tooth number");
        return result;
    }
    for (auto it = teeth->begin(); it != teeth->end(); ++it) {
        const std::string here = "/teeth/" + pointer_token(it.key());
        int fdi = 0;
        if (!parse_fdi_key(it.key(), &fdi) || !valid_permanent_fdi(fdi)) {
            r.error(here, "not an FDI permanent tooth number (11-18, 21-28, 31-38, 41-48): " + shown(it.key()));
            continue;
        }
        ToothRecord tooth;
        tooth.fdi = fdi;
        read_tooth(r, it.value(), here, &tooth);
        result.chart.teeth[fdi] = tooth;
    }
    return result;
}

ChartLoad load_chart(const std::string& path) {
    ChartLoad result;
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
    return parse_chart(doc, path);
}

json chart_to_json(const Chart& chart) {
    json teeth = json::object();
    for (const auto& [fdi, tooth] : chart.teeth) {
        json sites = json::object();
        for (Site s : kAllSites) {
            const auto& rec = tooth.sites[size_t(s)];
            if (!rec) continue;
            json j = {{"pd_mm", rec->pd_mm}, {"gm_mm", rec->gm_mm}, {"bop", rec->bop}};
            if (rec->suppuration) j["suppuration"] = true;
            if (rec->plaque) j["plaque"] = true;
            if (rec->calculus) j["calculus"] = true;
            if (rec->tissue) {
                if (rec->tissue->is_preset) {
                    j["tissue"] = tissue_preset_name(rec->tissue->preset);
                } else {
                    json pts = json::array();
                    for (const auto& [f, d] : rec->tissue->custom.points_N_mm) pts.push_back({f, d});
                    j["tissue"] = {{"yield_curve_N_mm", pts}};
                }
            }
            sites[site_name(s)] = j;
        }
        json t = {{"sites", sites}};
        if (tooth.mobility) t["mobility"] = tooth.mobility;
        if (!tooth.furcation.empty()) {
            json f = json::object();
            for (const auto& [side, grade] : tooth.furcation) f[furcation_side_name(side)] = grade;
            t["furcation"] = f;
        }
        teeth[std::to_string(fdi)] = t;
    }
    return {{"format", kChartFormat}, {"teeth", teeth}};
}

void check_chart_for_case(const Chart& chart, const std::string& source, std::vector<std::string>& errors) {
    if (chart.teeth.empty()) errors.push_back(one_line(source + ": /teeth: no teeth charted"));
    for (const auto& [fdi, tooth] : chart.teeth) {
        const std::string here = "/teeth/" + std::to_string(fdi);
        if (!is_supported_tooth(fdi)) {
            errors.push_back(one_line(source + ": " + here +
                                      ": the case generator builds teeth 11-17, 21-27, 31-37 and 41-47 only"));
            continue;
        }
        for (Site s : kAllSites)
            if (!tooth.sites[size_t(s)])
                errors.push_back(one_line(source + ": " + here + "/sites/" + site_name(s) +
                                          ": missing (a case needs all six sites)"));
    }
}

}  // namespace sulcus
