// sulcus-cli tissue: the force-depth curve of each pocket-floor tissue setting, measured through
// the servo step (docs/tissue.md).
#include "cli/commands.h"
#include "sulcus/app/svg_plot.h"
#include "sulcus/app/tissue_probe.h"
#include "sulcus/engine/runner.h"

#include <cstdio>
#include <filesystem>
#include <string>

namespace sulcus::cli {

const char* const kHelpTissue =
    "usage: sulcus-cli tissue [--out DIR]\n"
    "\n"
    "Presses a Williams probe's tip, through the servo step, slowly into a flat layer of each\n"
    "pocket-floor tissue preset (healthy, inflamed) up to 1 N, and prints the depth reached at\n"
    "0.20, 0.25 and 0.50 N against the documented curve. With --out, writes DIR/force_depth.svg\n"
    "(depth against force, measured and documented) and DIR/force_depth.csv.\n";

namespace {

// Depth at force f by linear interpolation in a run's samples (force ascending).
double depth_at(const TissueProbeRun& run, double f) {
    const auto& s = run.samples;
    for (size_t i = 1; i < s.size(); ++i)
        if (s[i].force_N >= f) {
            const double u = (f - s[i - 1].force_N) / (s[i].force_N - s[i - 1].force_N);
            return s[i - 1].depth_m + u * (s[i].depth_m - s[i - 1].depth_m);
        }
    return s.empty() ? 0.0 : s.back().depth_m;
}

}  // namespace

int cmd_tissue(const std::vector<std::string>& args) {
    std::string out;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--out" && i + 1 < args.size()) out = args[++i];
        else return usage("tissue: unknown argument '" + args[i] + "'");
    }
    PlotFigure fig;
    fig.title = "Pocket floor: depth against probing force (Williams tip, through the servo step)";
    std::string csv = "tissue,force_N,depth_mm,exact_depth_mm\n";
    std::printf("%-9s %-8s %-14s %-14s\n", "tissue", "force_N", "measured_mm", "documented_mm");
    for (TissuePreset p : kAllTissuePresets) {
        const YieldCurve& curve = tissue_preset_curve(p);
        const TissueProbeRun run = probe_tissue(curve, ProbeKind::Williams, 1.0);
        if (!run.error.empty()) {
            std::fprintf(stderr, "sulcus-cli: tissue %s: %s\n", tissue_preset_name(p), run.error.c_str());
            return kInternal;
        }
        for (double f : {0.20, 0.25, 0.50})
            std::printf("%-9s %-8.2f %-14.4f %-14.4f\n", tissue_preset_name(p), f, depth_at(run, f) * 1e3,
                        curve.depth_mm_at(f));
        PlotPanel panel;
        panel.title = std::string(tissue_preset_name(p));
        panel.x_label = "probing force (N)";
        panel.y_label = "depth below the onset (mm)";
        PlotSeries measured{"measured (step)", {}, {}, "#1f77b4"};
        for (const TissueProbeSample& s : run.samples) {
            measured.x.push_back(s.force_N);
            measured.y.push_back(s.depth_m * 1e3);
            char line[128];
            std::snprintf(line, sizeof line, "%s,%.9g,%.9g,%.9g\n", tissue_preset_name(p), s.force_N, s.depth_m * 1e3,
                          s.exact_depth_m * 1e3);
            csv += line;
        }
        PlotSeries documented{"documented curve", {}, {}, "#d62728"};
        for (const auto& pt : curve.points_N_mm) {
            documented.x.push_back(pt[0]);
            documented.y.push_back(pt[1]);
        }
        panel.series = {documented, measured};
        fig.panels.push_back(panel);
    }
    if (!out.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(out, ec);
        std::string error;
        const std::string base = (std::filesystem::path(out) / "force_depth").string();
        if (!write_svg(fig, base + ".svg", &error) || !write_file_atomic(base + ".csv", csv, &error)) {
            std::fprintf(stderr, "%s\n", error.c_str());
            return kUsage;
        }
    }
    return kOk;
}

}  // namespace sulcus::cli
