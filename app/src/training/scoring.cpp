// Scoring a lesson from its rubric: arithmetic on the runtime's measurements, nothing else.
#include "sulcus/app/scoring.h"
#include "sulcus/app/text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <utility>

namespace sulcus {

namespace {

constexpr double kRadToDeg = 57.29577951308232;
// Charted depths and reference depths are given in tenths at most: a margin this small keeps an
// error of exactly 0.5 or 1 mm inside its band despite binary rounding.
constexpr double kBandSlack_mm = 1e-9;

std::string mm_text(double mm) { return format_text("%g mm", mm); }

// A value printed with no decimals, without "-0" for a small negative one.
double whole(double v) { return std::fabs(v) < 0.5 ? 0.0 : v; }

std::string join_sites(const std::vector<std::string>& names, std::size_t max_named = 6) {
    std::string out;
    for (std::size_t i = 0; i < names.size() && i < max_named; ++i) out += (i ? ", " : "") + names[i];
    if (names.size() > max_named) out += format_text(" and %zu more", names.size() - max_named);
    return out;
}

SiteScore score_site(const SiteMeasure& m, const Rubric& rb) {
    SiteScore s;
    s.ref = m.ref;
    s.interproximal = m.interproximal;
    s.reference_pd_mm = m.reference_pd_mm;
    s.charted_pd_mm = m.charted_pd_mm;
    if (m.charted_pd_mm) {
        const double e = *m.charted_pd_mm - m.reference_pd_mm;
        s.error_mm = e;
        if (std::fabs(e) <= rb.depth_exact_mm + kBandSlack_mm) {
            s.depth = DepthGrade::Exact;
            s.depth_score = 1.0;
        } else if (std::fabs(e) <= rb.depth_pass_mm + kBandSlack_mm) {
            s.depth = DepthGrade::Pass;
            s.depth_score = 0.5;
        } else {
            s.depth = DepthGrade::Fail;
        }
    }
    s.probed = m.visited;
    s.max_force_N = m.max_force_N;
    s.time_above_warning_s = m.time_above_warning_s;
    s.time_at_trauma_s = m.time_at_trauma_s;
    s.withdrawals = m.withdrawals;
    s.advance_mm = m.advance_m() * 1e3;
    s.walk_score = rb.walk_advance_mm > 0.0 ? std::min(1.0, s.advance_mm / rb.walk_advance_mm) : 1.0;
    if (m.visited) {
        s.deepest_mm = m.deepest_m * 1e3;
        s.force_N = m.force_at_deepest_N;
        if (s.force_N >= rb.force_trauma_N) {
            s.force = ForceGrade::Trauma;
        } else if (s.force_N > rb.force_warning_N) {
            s.force = ForceGrade::Warning;
            s.force_score = 0.5;
        } else if (s.force_N > rb.force_target_max_N) {
            s.force = ForceGrade::Firm;
            s.force_score = 0.75;
        } else if (s.force_N < rb.force_target_min_N) {
            s.force = ForceGrade::Light;
            s.force_score = 0.5;
        } else {
            s.force = ForceGrade::Target;
            s.force_score = 1.0;
        }
        s.angle_deg = m.angle_at_deepest_rad * kRadToDeg;
        s.tilt_deg = m.tilt_at_deepest_rad * kRadToDeg;
        s.angle_ok = m.interproximal
                         ? s.tilt_deg >= rb.angle_interproximal_min_deg && s.tilt_deg <= rb.angle_interproximal_max_deg
                         : s.angle_deg <= rb.angle_direct_max_deg;
    }

    // One sentence: depth, force, angle, stroke.
    std::string f = site_ref_name(m.ref) + ": ";
    if (m.charted_pd_mm)
        f += "charted " + mm_text(*m.charted_pd_mm) + ", reference " + mm_text(m.reference_pd_mm) + " (" +
             depth_grade_name(s.depth) + ")";
    else
        f += "not charted (reference " + mm_text(m.reference_pd_mm) + ")";
    if (m.visited) {
        f += format_text("; tip %.1f mm deep at %.2f N (%s)", s.deepest_mm, s.force_N, force_grade_name(s.force));
        if (m.interproximal)
            f += format_text("; tilted %.0f deg toward the contact (%s)", whole(s.tilt_deg),
                               s.angle_ok ? "good" : "tilt it under the contact");
        else
            f += format_text("; %.0f deg to the long axis (%s)", whole(s.angle_deg), s.angle_ok ? "good" : "keep it parallel");
        f += format_text("; walked %.1f mm", s.advance_mm);
        if (m.withdrawals > 0) f += format_text(", out of the sulcus %d time%s", m.withdrawals, m.withdrawals == 1 ? "" : "s");
    } else {
        f += "; never probed";
    }
    s.feedback = f + ".";
    return s;
}

double mean(double sum, int n) { return n > 0 ? sum / n : 0.0; }

}  // namespace

const char* depth_grade_name(DepthGrade g) {
    switch (g) {
        case DepthGrade::NotCharted: return "not charted";
        case DepthGrade::Exact: return "exact";
        case DepthGrade::Pass: return "within tolerance";
        case DepthGrade::Fail: return "off";
    }
    return "?";
}

const char* force_grade_name(ForceGrade g) {
    switch (g) {
        case ForceGrade::NotProbed: return "not probed";
        case ForceGrade::Light: return "light";
        case ForceGrade::Target: return "right";
        case ForceGrade::Firm: return "firm";
        case ForceGrade::Warning: return "too firm";
        case ForceGrade::Trauma: return "traumatic";
    }
    return "?";
}

SessionMeasures session_measures(const LessonRuntime& runtime) {
    SessionMeasures m;
    m.sites = runtime.sites();
    m.time_s = runtime.end_s() - runtime.start_s();
    m.max_force_N = runtime.max_force_N();
    m.time_above_warning_s = runtime.time_above_warning_s();
    m.time_at_trauma_s = runtime.time_at_trauma_s();
    m.steps_total = static_cast<int>(runtime.steps().size());
    for (const StepProgress& p : runtime.steps()) {
        m.steps_completed += p.completed ? 1 : 0;
        m.steps_skipped += p.skipped ? 1 : 0;
    }
    return m;
}

LessonScores score_measures(const Rubric& rb, const SessionMeasures& in) {
    LessonScores out;
    for (const SiteMeasure& m : in.sites)
        if (m.target) out.sites.push_back(score_site(m, rb));
    out.sites_target = static_cast<int>(out.sites.size());
    out.time_s = in.time_s;
    out.max_force_N = in.max_force_N;
    out.time_above_warning_s = in.time_above_warning_s;
    out.time_at_trauma_s = in.time_at_trauma_s;
    out.steps_total = in.steps_total;
    out.steps_completed = in.steps_completed;
    out.steps_skipped = in.steps_skipped;

    // Depth.
    int charted = 0, within = 0, exact = 0;
    double depth_sum = 0.0;
    const SiteScore* worst = nullptr;
    std::vector<std::string> missing;
    for (const SiteScore& s : out.sites) {
        if (!s.charted_pd_mm) {
            missing.push_back(site_ref_name(s.ref));
            continue;
        }
        ++charted;
        depth_sum += s.depth_score;
        if (s.depth != DepthGrade::Fail) ++within;
        if (s.depth == DepthGrade::Exact) ++exact;
        if (s.depth == DepthGrade::Fail && (!worst || std::fabs(*s.error_mm) > std::fabs(*worst->error_mm))) worst = &s;
    }
    out.sites_charted = charted;
    {
        RowScore r{"depth", mean(depth_sum, charted), charted > 0 && within >= rb.depth_pass_fraction * charted - kBandSlack_mm,
                   rb.weight_depth, ""};
        r.feedback = format_text("%d of %d charted sites within %g mm of the reference depth (%d within %g mm).", within,
                                   charted, rb.depth_pass_mm, exact, rb.depth_exact_mm);
        if (worst)
            r.feedback += " Largest error: " + site_ref_name(worst->ref) + " charted " + mm_text(*worst->charted_pd_mm) +
                          ", reference " + mm_text(worst->reference_pd_mm) + ".";
        if (charted == 0) r.feedback = "No site was charted.";
        out.rows.push_back(r);
    }

    // Force.
    int probed = 0, target = 0, light = 0, firm = 0, trauma = 0;
    double force_sum = 0.0;
    for (const SiteScore& s : out.sites) {
        if (!s.probed) continue;
        ++probed;
        force_sum += s.force_score;
        if (s.force == ForceGrade::Target) ++target;
        if (s.force == ForceGrade::Light) ++light;
        if (s.force == ForceGrade::Firm || s.force == ForceGrade::Warning) ++firm;
        if (s.force == ForceGrade::Trauma) ++trauma;
    }
    out.sites_probed = probed;
    {
        const bool no_trauma = out.time_at_trauma_s <= 0.0 && out.max_force_N < rb.force_trauma_N;
        RowScore r{"force", mean(force_sum, probed), probed > 0 && no_trauma && out.time_above_warning_s <= rb.max_time_above_warning_s,
                   rb.weight_force, ""};
        r.feedback = format_text(
            "At the pocket floor: %d of %d sites at %.2f-%.2f N, %d light, %d too firm, %d at %.2f N or more. "
            "%.1f s above %.2f N (%.1f s allowed), %.1f s at %.2f N or more; highest %.2f N.",
            target, probed, rb.force_target_min_N, rb.force_target_max_N, light, firm, trauma, rb.force_trauma_N,
            out.time_above_warning_s, rb.force_warning_N, rb.max_time_above_warning_s, out.time_at_trauma_s,
            rb.force_trauma_N, out.max_force_N);
        if (probed == 0) r.feedback = "No site was probed.";
        out.rows.push_back(r);
    }

    // Angulation.
    int direct = 0, direct_ok = 0, inter = 0, inter_ok = 0;
    for (const SiteScore& s : out.sites) {
        if (!s.probed) continue;
        (s.interproximal ? inter : direct) += 1;
        if (s.angle_ok) (s.interproximal ? inter_ok : direct_ok) += 1;
    }
    {
        const double score = mean(direct_ok + inter_ok, direct + inter);
        RowScore r{"angulation", score, direct + inter > 0 && score >= rb.angle_pass_fraction - kBandSlack_mm,
                   rb.weight_angulation, ""};
        r.feedback = format_text(
            "Parallel to the long axis (within %g deg) at %d of %d direct sites; tilted %g-%g deg under the contact at "
            "%d of %d interproximal sites.",
            rb.angle_direct_max_deg, direct_ok, direct, rb.angle_interproximal_min_deg, rb.angle_interproximal_max_deg,
            inter_ok, inter);
        out.rows.push_back(r);
    }

    // Walking stroke.
    int walked = 0;
    double walk_sum = 0.0;
    for (const SiteScore& s : out.sites) {
        walk_sum += s.walk_score;
        if (s.walk_score >= 1.0) ++walked;
    }
    {
        const int n = out.sites_target;
        RowScore r{"walking", mean(walk_sum, n), n > 0 && walked >= rb.walk_pass_fraction * n - kBandSlack_mm,
                   rb.weight_walking, ""};
        r.feedback = format_text(
            "The tip walked %g mm or more along the sulcus at %d of %d sites. Walk it in 1 mm steps with short "
            "up-and-down strokes.",
            rb.walk_advance_mm, walked, n);
        out.rows.push_back(r);
    }

    // Withdrawals, per side of each tooth with target sites.
    {
        std::map<std::pair<int, bool>, int> sides;  // (fdi, lingual) -> withdrawals
        for (const SiteScore& s : out.sites) sides[{s.ref.fdi, is_lingual_site(s.ref.site)}] += s.withdrawals;
        int total = 0, extra = 0;
        for (const auto& [side, n] : sides) {
            total += n;
            extra += std::max(0, n - rb.max_withdrawals_per_side);
        }
        const int n = out.sites_target;
        RowScore r{"withdrawals", n > 0 ? std::max(0.0, 1.0 - double(extra) / n) : 0.0, n > 0 && extra == 0,
                   rb.weight_withdrawals, ""};
        r.feedback = format_text(
            "%d withdrawal%s from the sulcus, %d more than the %d allowed per side of a tooth. Stay in the sulcus "
            "between strokes.",
            total, total == 1 ? "" : "s", extra, rb.max_withdrawals_per_side);
        out.rows.push_back(r);
    }

    // Completeness.
    {
        const int n = out.sites_target;
        const double score = mean(charted, n);
        RowScore r{"completeness", score, n > 0 && score >= rb.completeness_pass_fraction - kBandSlack_mm,
                   rb.weight_completeness, ""};
        r.feedback = format_text("Charted %d of %d sites; %d of %d steps done.", charted, n, out.steps_completed,
                                   out.steps_total);
        if (!missing.empty()) r.feedback += " Missing: " + join_sites(missing) + ".";
        out.rows.push_back(r);
    }

    // Time.
    {
        const double limit = rb.time_limit_s;
        RowScore r{"time", limit > 0.0 ? (out.time_s <= limit ? 1.0 : limit / out.time_s) : 1.0,
                   limit <= 0.0 || out.time_s <= limit, limit > 0.0 ? rb.weight_time : 0.0, ""};
        r.feedback = limit > 0.0 ? format_text("Took %.0f s (limit %.0f s).", out.time_s, limit)
                                 : format_text("Took %.0f s (no limit).", out.time_s);
        out.rows.push_back(r);
    }

    double wsum = 0.0, sum = 0.0;
    for (const RowScore& r : out.rows) {
        if (!(r.weight > 0.0)) continue;
        wsum += r.weight;
        sum += r.weight * r.score;
    }
    out.overall = wsum > 0.0 ? sum / wsum : 0.0;
    out.passed = out.overall >= rb.pass_score;
    return out;
}

nlohmann::json scores_to_json(const LessonScores& s) {
    using nlohmann::json;
    json j;
    j["overall"] = s.overall;
    j["passed"] = s.passed;
    j["sites_target"] = s.sites_target;
    j["sites_charted"] = s.sites_charted;
    j["sites_probed"] = s.sites_probed;
    j["steps_total"] = s.steps_total;
    j["steps_completed"] = s.steps_completed;
    j["steps_skipped"] = s.steps_skipped;
    j["time_s"] = s.time_s;
    j["max_force_N"] = s.max_force_N;
    j["time_above_warning_s"] = s.time_above_warning_s;
    j["time_at_trauma_s"] = s.time_at_trauma_s;
    json rows = json::array();
    for (const RowScore& r : s.rows)
        rows.push_back({{"name", r.name}, {"score", r.score}, {"passed", r.passed}, {"weight", r.weight}, {"feedback", r.feedback}});
    j["rows"] = rows;
    json sites = json::array();
    for (const SiteScore& x : s.sites) {
        json o;
        o["site"] = site_ref_name(x.ref);
        o["interproximal"] = x.interproximal;
        o["reference_pd_mm"] = x.reference_pd_mm;
        o["charted_pd_mm"] = x.charted_pd_mm ? json(*x.charted_pd_mm) : json(nullptr);
        o["error_mm"] = x.error_mm ? json(*x.error_mm) : json(nullptr);
        o["depth"] = depth_grade_name(x.depth);
        o["depth_score"] = x.depth_score;
        o["probed"] = x.probed;
        o["deepest_mm"] = x.deepest_mm;
        o["force_N"] = x.force_N;
        o["force"] = force_grade_name(x.force);
        o["force_score"] = x.force_score;
        o["max_force_N"] = x.max_force_N;
        o["time_above_warning_s"] = x.time_above_warning_s;
        o["time_at_trauma_s"] = x.time_at_trauma_s;
        o["angle_deg"] = x.angle_deg;
        o["tilt_deg"] = x.tilt_deg;
        o["angle_ok"] = x.angle_ok;
        o["advance_mm"] = x.advance_mm;
        o["walk_score"] = x.walk_score;
        o["withdrawals"] = x.withdrawals;
        o["feedback"] = x.feedback;
        sites.push_back(o);
    }
    j["sites"] = sites;
    return j;
}

namespace {

std::string value_text(const nlohmann::json& v) {
    std::string t = v.dump();
    if (t.size() > 80) t = t.substr(0, 77) + "...";
    return t;
}

std::string difference(const nlohmann::json& a, const nlohmann::json& b, const std::string& path) {
    const std::string here = path.empty() ? "(document)" : path;
    if (a.type() != b.type() && !(a.is_number() && b.is_number()))
        return here + ": stored " + value_text(a) + ", recomputed " + value_text(b);
    if (a.is_object()) {
        for (auto it = a.begin(); it != a.end(); ++it) {
            const std::string p = path.empty() ? it.key() : path + "." + it.key();
            if (!b.contains(it.key())) return p + ": stored " + value_text(it.value()) + ", not recomputed";
            if (std::string d = difference(it.value(), b.at(it.key()), p); !d.empty()) return d;
        }
        for (auto it = b.begin(); it != b.end(); ++it)
            if (!a.contains(it.key()))
                return (path.empty() ? it.key() : path + "." + it.key()) + ": not stored, recomputed " + value_text(it.value());
        return "";
    }
    if (a.is_array()) {
        const std::size_t n = std::min(a.size(), b.size());
        for (std::size_t i = 0; i < n; ++i)
            if (std::string d = difference(a[i], b[i], path + "[" + std::to_string(i) + "]"); !d.empty()) return d;
        if (a.size() != b.size())
            return here + ": stored " + std::to_string(a.size()) + " entries, recomputed " + std::to_string(b.size());
        return "";
    }
    if (a.is_number() && b.is_number()) {
        // Bit for bit: the same double (integers stored by the reader compare by value).
        if (a.is_number_float() || b.is_number_float()) {
            const double x = a.get<double>(), y = b.get<double>();
            if (std::memcmp(&x, &y, sizeof x) == 0) return "";
        } else if (a == b) {
            return "";
        }
        return here + ": stored " + value_text(a) + ", recomputed " + value_text(b);
    }
    return a == b ? "" : here + ": stored " + value_text(a) + ", recomputed " + value_text(b);
}

}  // namespace

std::string first_json_difference(const nlohmann::json& stored, const nlohmann::json& recomputed) {
    return difference(stored, recomputed, "");
}

}  // namespace sulcus
