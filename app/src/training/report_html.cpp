// The session report as one self-contained HTML page: summary, rubric rows, the chart (reference
// against trainee), per-site scores, force over time, and the feedback the trainee was given.
#include "sulcus/app/lesson_session.h"
#include "sulcus/app/svg_plot.h"
#include "sulcus/app/text.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace sulcus {

namespace {

// A value for "%.1f" without "-0.0" for a small negative one.
double tenth(double v) { return std::fabs(v) < 0.05 ? 0.0 : v; }

const char* css() {
    return R"(body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:24px auto;max-width:1100px;color:#1d2330;background:#fafbfc}
h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:28px 0 8px;border-bottom:1px solid #d7dbe2;padding-bottom:4px}
.sub{color:#5a6270;font-size:13px}.verdict{display:inline-block;padding:6px 14px;border-radius:6px;font-weight:600;font-size:18px;margin:12px 0}
.pass{background:#dff3e4;color:#17602f}.fail{background:#fbe3e1;color:#8d1f16}
table{border-collapse:collapse;font-size:13px;background:#fff}td,th{border:1px solid #d7dbe2;padding:4px 7px;text-align:center}
th{background:#eef1f5;font-weight:600}td.l,th.l{text-align:left}.bar{background:#e6e9ee;width:120px;height:10px;border-radius:5px;display:inline-block;vertical-align:middle}
.bar i{display:block;height:10px;border-radius:5px;background:#3b7dd8}.ok{color:#17602f;font-weight:600}.no{color:#8d1f16;font-weight:600}
.c-exact{background:#cdebd5}.c-pass{background:#f6ecc4}.c-fail{background:#f5cdc8}.c-none{background:#f0f0f0;color:#888}
.fb td{font-size:12px}.warning{color:#8d1f16}.note{color:#6b4e00}.hint{color:#2d5f9a}.step{color:#444}
.small{font-size:12px;color:#5a6270})";
}

std::string depth_class(const SiteScore& s) {
    switch (s.depth) {
        case DepthGrade::Exact: return "c-exact";
        case DepthGrade::Pass: return "c-pass";
        case DepthGrade::Fail: return "c-fail";
        case DepthGrade::NotCharted: return "c-none";
    }
    return "c-none";
}

const SiteScore* find_site(const LessonScores& s, int fdi, Site site) {
    for (const SiteScore& x : s.sites)
        if (x.ref.fdi == fdi && x.ref.site == site) return &x;
    return nullptr;
}

// The chart as clinicians lay it out: a column per site, facial row above lingual, per tooth.
std::string chart_table(const LessonOutcome& o) {
    std::string h = "<table><tr><th class=l>tooth</th><th class=l>side</th><th colspan=3>sites</th><th class=l>"
                    "reference PD (mm)</th><th class=l>charted PD (mm)</th><th>BOP ref / charted</th></tr>\n";
    for (const auto& [fdi, tooth] : o.reference.teeth) {
        for (int side = 0; side < 2; ++side) {
            const Site sites[3] = {side == 0 ? Site::DB : Site::DL, side == 0 ? Site::B : Site::L, side == 0 ? Site::MB : Site::ML};
            h += "<tr>";
            if (side == 0) h += "<td rowspan=2><b>" + std::to_string(fdi) + "</b></td>";
            h += std::string("<td class=l>") + (side == 0 ? "facial" : "lingual") + "</td>";
            std::string ref, got, bop;
            for (Site s : sites) {
                h += std::string("<td>") + site_name(s) + "</td>";
                const auto& rec = tooth.sites[static_cast<std::size_t>(s)];
                const SiteScore* sc = find_site(o.scores, fdi, s);
                ref += "<span style='display:inline-block;width:34px'>" + (rec ? format_text("%g", rec->pd_mm) : std::string("-")) + "</span>";
                std::string cell = "-", cls = "c-none";
                if (sc && sc->charted_pd_mm) {
                    cell = format_text("%g", *sc->charted_pd_mm);
                    cls = depth_class(*sc);
                }
                got += "<span class='" + cls + "' style='display:inline-block;width:34px'>" + cell + "</span>";
                bool trainee_bop = false;
                if (const auto t = o.trainee.teeth.find(fdi); t != o.trainee.teeth.end())
                    if (const auto& tr = t->second.sites[static_cast<std::size_t>(s)]) trainee_bop = tr->bop;
                bop += std::string(rec && rec->bop ? "&#9679;" : "&#9675;") + "/" + (trainee_bop ? "&#9679;" : "&#9675;") + " ";
            }
            h += "<td class=l>" + ref + "</td><td class=l>" + got + "</td><td>" + bop + "</td></tr>\n";
        }
    }
    h += "</table><p class=small>Charted cells: green exact (within the rubric's exact band), yellow within the pass "
         "band, red off. Filled dot: bleeding on probing.</p>\n";
    return h;
}

std::string force_plot(const LessonOutcome& o, const Rubric& rb) {
    if (o.force.max_N.empty()) return "<p>No ticks.</p>";
    PlotFigure fig;
    fig.width_px = 1060;
    fig.panel_height_px = 300;
    PlotPanel p;
    p.title = "Force on the tissue (highest in each " + format_text("%g", o.force.bin_s * 1e3) + " ms)";
    p.x_label = "time (s)";
    p.y_label = "force (N)";
    PlotSeries force{"force", {}, {}, "#1f5fae"};
    for (std::size_t i = 0; i < o.force.max_N.size(); ++i) {
        force.x.push_back((double(i) + 0.5) * o.force.bin_s);
        force.y.push_back(o.force.max_N[i]);
    }
    const double t_end = double(o.force.max_N.size()) * o.force.bin_s;
    auto level = [&](const std::string& name, double v, const char* colour) {
        return PlotSeries{name + format_text(" %.2f N", v), {0.0, t_end}, {v, v}, colour};
    };
    p.series.push_back(force);
    p.series.push_back(level("target from", rb.force_target_min_N, "#2e9d4f"));
    p.series.push_back(level("warning above", rb.force_warning_N, "#d89a1c"));
    p.series.push_back(level("trauma at", rb.force_trauma_N, "#c23b22"));
    fig.panels.push_back(p);
    return render_svg(fig);
}

}  // namespace

std::string report_html(const LessonOutcome& o) {
    const LessonScores& s = o.scores;
    const Rubric& rb = o.lesson.rubric;
    std::string h = "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>" + xml_escape(o.lesson.title) +
                    " - session report</title><style>" + css() + "</style></head><body>\n";
    h += "<h1>" + xml_escape(o.lesson.title) + "</h1>\n";
    h += "<div class=sub>Case " + xml_escape(std::filesystem::path(o.case_dir).filename().string()) + " &middot; device " +
         xml_escape(o.metadata.device) + " &middot; recorded " + xml_escape(o.metadata.start_time) + " &middot; " +
         std::to_string(o.ticks) + " ticks at " + format_text("%g", o.metadata.rate_hz) + " Hz &middot; " +
         format_text("%.1f", s.time_s) + " s</div>\n";
    h += std::string("<div class='verdict ") + (s.passed ? "pass" : "fail") + "'>" + format_text("Score %.0f %%", s.overall * 100.0) +
         (s.passed ? " &mdash; passed" : " &mdash; not passed") + format_text(" (pass at %.0f %%)", rb.pass_score * 100.0) + "</div>\n";
    h += "<div class=sub>Replay: " + std::string(o.first_mismatch < 0 ? "every force as recorded" : "forces differ from tick " + std::to_string(o.first_mismatch)) +
         (o.stored_scores ? (first_json_difference(*o.stored_scores, o.scores_json).empty() ? "; scores as stored" : "; scores differ from the stored ones")
                          : "; no stored scores") +
         (o.truncated ? "; the recording was cut short" : "") + "</div>\n";

    h += "<h2>Rubric</h2>\n<table><tr><th class=l>row</th><th>score</th><th></th><th>weight</th><th>result</th><th class=l>feedback</th></tr>\n";
    for (const RowScore& r : s.rows) {
        h += "<tr><td class=l><b>" + xml_escape(r.name) + "</b></td><td>" + format_text("%.0f %%", r.score * 100.0) +
             "</td><td><span class=bar><i style='width:" + format_text("%.0f", std::round(r.score * 120.0)) + "px'></i></span></td><td>" +
             (r.weight > 0 ? format_text("%.2f", r.weight) : std::string("&ndash;")) + "</td><td class=" + (r.passed ? "ok>pass" : "no>not yet") +
             "</td><td class=l>" + xml_escape(r.feedback) + "</td></tr>\n";
    }
    h += "</table>\n";

    h += "<h2>Chart</h2>\n" + chart_table(o);

    h += "<h2>Sites</h2>\n<table><tr><th>site</th><th>ref PD</th><th>charted</th><th>depth</th><th>deepest (mm)</th>"
         "<th>force there (N)</th><th>force</th><th>max (N)</th><th>&gt; warning (s)</th><th>angle (deg)</th><th>tilt (deg)</th>"
         "<th>angle</th><th>walked (mm)</th><th>out</th></tr>\n";
    for (const SiteScore& x : s.sites) {
        h += "<tr><td><b>" + site_ref_name(x.ref) + "</b></td><td>" + format_text("%g", x.reference_pd_mm) + "</td><td class=" +
             depth_class(x) + ">" + (x.charted_pd_mm ? format_text("%g", *x.charted_pd_mm) : std::string("-")) + "</td><td>" +
             depth_grade_name(x.depth) + "</td>";
        if (x.probed) {
            h += "<td>" + format_text("%.2f", x.deepest_mm) + "</td><td>" + format_text("%.3f", x.force_N) + "</td><td class=" +
                 (x.force == ForceGrade::Target ? "ok" : "no") + ">" + force_grade_name(x.force) + "</td><td>" +
                 format_text("%.3f", x.max_force_N) + "</td><td>" + format_text("%.2f", x.time_above_warning_s) + "</td><td>" +
                 format_text("%.1f", tenth(x.angle_deg)) + "</td><td>" + (x.interproximal ? format_text("%.1f", tenth(x.tilt_deg)) : std::string("&ndash;")) +
                 "</td><td class=" + (x.angle_ok ? "ok>good" : "no>off") + "</td>";
        } else {
            h += "<td colspan=8 class=no>never probed</td>";
        }
        h += "<td>" + format_text("%.2f", x.advance_mm) + "</td><td>" + std::to_string(x.withdrawals) + "</td></tr>\n";
    }
    h += "</table>\n";

    h += "<h2>Force over time</h2>\n" + force_plot(o, rb);

    h += "<h2>Feedback given</h2>\n<table class=fb><tr><th>time (s)</th><th>kind</th><th class=l>from</th><th class=l>message</th></tr>\n";
    for (const Feedback& fb : o.feedback)
        h += "<tr><td>" + format_text("%.2f", fb.time_s) + "</td><td class=" + feedback_level_name(fb.level) + ">" +
             feedback_level_name(fb.level) + "</td><td class=l>" + xml_escape(fb.source) + "</td><td class=l>" + xml_escape(fb.message) + "</td></tr>\n";
    h += "</table>\n<p class=small>" + xml_escape(o.lesson_path) + " &middot; " + kReportFormat + "</p>\n</body></html>\n";
    return h;
}

}  // namespace sulcus
