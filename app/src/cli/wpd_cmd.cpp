// sulcus-cli wpd: error against run time over the renderer's accuracy settings. Each setting is
// swept alone about the defaults; every run is compared tick by tick with a reference run at the
// tightest value of every setting, and checked exactly for penetration and gap.
#include "cli/bench_run.h"
#include "cli/bench_scenes.h"
#include "cli/commands.h"
#include "sulcus/app/lesson_session.h"
#include "sulcus/app/svg_plot.h"
#include "sulcus/app/text.h"
#include "sulcus/engine/runner.h"
#include "so3.h"

#include <climits>
#include <cstdio>
#include <filesystem>
#include <functional>

namespace sulcus::cli {

const char* const kHelpWpd =
    "usage: sulcus-cli wpd SCENE... --out DIR [--max-ticks N] [--check-every N]\n"
    "                      [--content-root DIR] [--cases DIR]\n"
    "\n"
    "Error against run time (a work-precision diagram) for each scene: every accuracy setting of\n"
    "the step (constraint tolerance, re-linearizations, QP feasibility tolerance, candidate sets,\n"
    "candidate tie radius) is swept alone about the defaults. Each run's error -- the largest\n"
    "penetration and gap in contact (exact checks), and the pose and force error against a\n"
    "reference run at the tightest value of every setting -- is set against its step time\n"
    "(median, p99). Writes DIR/<scene>/wpd.csv and DIR/<scene>/wpd.svg (log-log).\n"
    "\n"
    "  SCENE             a bench scene name ('sulcus-cli bench --list') or a scene file\n"
    "  --max-ticks N     only the first N ticks of each scene\n"
    "  --check-every N   exact checks on every N-th tick with a force (default 1)\n";

namespace {

struct Knob {
    std::string name;
    std::string label;  // for the legend
    std::vector<double> values;
    double tightest;
    std::function<void(RendererSettings&, double)> apply;
    std::function<double(const RendererSettings&)> current;
};

std::vector<Knob> knobs() {
    return {
        {"constraint_tol_m", "constraint tolerance (m)", {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}, 1e-10,
         [](RendererSettings& s, double v) { s.constraint_tol_m = v; },
         [](const RendererSettings& s) { return s.constraint_tol_m; }},
        {"max_relinearizations", "re-linearizations", {1, 2, 4, 12, 32, 64}, 64,
         [](RendererSettings& s, double v) { s.max_relinearizations = int(v); },
         [](const RendererSettings& s) { return double(s.max_relinearizations); }},
        {"qp_feasibility_tol", "QP feasibility tolerance", {1e-6, 1e-9, 1e-12, 1e-14, 1e-15}, 1e-15,
         [](RendererSettings& s, double v) { s.qp.feasibility_tol = v; },
         [](const RendererSettings& s) { return s.qp.feasibility_tol; }},
        {"max_candidates", "candidate sets", {1, 2, 4, 8, 16, 32}, 32,
         [](RendererSettings& s, double v) { s.max_candidates = int(v); },
         [](const RendererSettings& s) { return double(s.max_candidates); }},
        {"tie_tol_m", "candidate tie radius (m)", {1e-9, 1e-7, 1e-6, 1e-5, 1e-4}, 1e-4,
         [](RendererSettings& s, double v) { s.tie_tol_m = v; },
         [](const RendererSettings& s) { return s.tie_tol_m; }},
    };
}

struct Point {
    std::string knob;
    double value = 0;
    bool is_default = false;
    Percentiles time;
    double penetration = 0, gap = 0, pose_error = 0, rotation_error = 0, force_error = 0;
};

// Largest differences of a run from the reference, tick by tick.
void compare(const BenchRun& run, const BenchRun& ref, Point& p) {
    const size_t n = std::min(run.ticks.size(), ref.ticks.size());
    for (size_t i = 0; i < n; ++i) {
        const BenchTick &a = run.ticks[i], &b = ref.ticks[i];
        p.pose_error = std::max(p.pose_error, glm::length(a.graphic.position - b.graphic.position));
        p.rotation_error = std::max(
            p.rotation_error, glm::length(quat_log(a.graphic.orientation * glm::conjugate(b.graphic.orientation))));
        p.force_error = std::max(p.force_error, glm::length(a.force_N - b.force_N));
    }
}

Percentiles step_times(const BenchRun& run) {
    std::vector<double> t;
    t.reserve(run.ticks.size());
    for (const BenchTick& k : run.ticks) t.push_back(k.step_us);
    return percentiles(t);
}

// Zero errors have no place on a log axis: they are drawn at this floor (the CSV has the zeros).
constexpr double kPlotFloor = 1e-15;

bool write_outputs(const std::string& scene, const std::vector<Point>& points, const std::string& dir,
                   std::string* error) {
    std::string csv =
        "scene,setting,value,is_default,step_median_us,step_p99_us,max_penetration_m,max_gap_in_contact_m,"
        "pose_error_m,rotation_error_rad,force_error_N\n";
    for (const Point& p : points)
        csv += format_text("%s,%s,%.17g,%d,%.3f,%.3f,%.6e,%.6e,%.6e,%.6e,%.6e\n", scene.c_str(), p.knob.c_str(), p.value,
                           int(p.is_default), p.time.median, p.time.p99, p.penetration, p.gap, p.pose_error,
                           p.rotation_error, p.force_error);
    if (!write_file_atomic(dir + "/wpd.csv", csv, error)) return false;

    PlotFigure fig;
    fig.title = "Error against step time: " + scene + " (each setting swept alone; ring = defaults)";
    fig.panel_height_px = 300;
    struct Metric {
        const char* title;
        const char* unit;
        double Point::*field;
    };
    const Metric metrics[] = {
        {"pose error against the reference", "m", &Point::pose_error},
        {"force error against the reference", "N", &Point::force_error},
        {"largest penetration (exact check)", "m", &Point::penetration},
        {"largest gap while a force is rendered (exact check)", "m", &Point::gap},
    };
    const std::vector<Knob> ks = knobs();
    for (const Metric& m : metrics) {
        PlotPanel panel;
        panel.title = std::string(m.title) + " (0 drawn at 1e-15)";
        panel.x_label = "median step time (us)";
        panel.y_label = std::string(m.unit);
        panel.log_x = panel.log_y = true;
        PlotSeries def;
        def.name = "defaults";
        def.colour = "#000000";
        def.markers = true;
        for (const Knob& k : ks) {
            PlotSeries s;
            s.name = k.label;
            s.markers = true;
            for (const Point& p : points) {
                if (p.knob != k.name) continue;
                s.x.push_back(p.time.median);
                s.y.push_back(std::max(p.*m.field, kPlotFloor));
            }
            panel.series.push_back(s);
        }
        for (const Point& p : points)
            if (p.knob == "defaults") {
                def.x.push_back(p.time.median);
                def.y.push_back(std::max(p.*m.field, kPlotFloor));
            }
        panel.series.push_back(def);
        fig.panels.push_back(panel);
    }
    return write_svg(fig, dir + "/wpd.svg", error);
}

}  // namespace

int cmd_wpd(const std::vector<std::string>& args) {
    std::string out_dir, content_root, cases_dir;
    std::vector<std::string> names;
    BenchRunOptions opt;
    opt.check_every = 1;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--out" || a == "--max-ticks" || a == "--check-every" || a == "--content-root" || a == "--cases") {
            if (i + 1 >= args.size()) return usage("wpd: " + a + " needs a value");
            const std::string& v = args[++i];
            if (a == "--out") out_dir = v;
            else if (a == "--content-root") content_root = v;
            else if (a == "--cases") cases_dir = v;
            else {
                long n = 0;
                if (!parse_whole(v, 1, INT_MAX, &n))
                    return usage("wpd: " + a + " needs a positive whole number, not '" + v + "'");
                if (a == "--max-ticks") opt.max_ticks = n;
                else opt.check_every = int(n);
            }
        } else if (!a.empty() && a[0] == '-') {
            return usage("wpd: unknown option '" + a + "'");
        } else {
            names.push_back(a);
        }
    }
    if (names.empty()) return usage("wpd: no scene given");
    if (out_dir.empty()) return usage("wpd: --out DIR is required");
    if (content_root.empty()) content_root = default_content_root();
    if (cases_dir.empty()) cases_dir = default_cases_dir();
    for (const std::string& name : names) {
        BenchScene scene;
        if (name.size() > 5 && name.substr(name.size() - 5) == ".json") {
            SceneLoad load = load_scene(name);
            if (!load.ok()) {
                std::fprintf(stderr, "%s\n", load.errors.front().c_str());
                return kUsage;
            }
            scene.name = load.scene.name;
            scene.scene = std::move(load.scene);
            scene.ticks = trajectory_ticks(scene.scene);
        } else {
            BenchScenes loaded = load_bench_scenes({name}, content_root, cases_dir);
            if (!loaded.error.empty()) {
                std::fprintf(stderr, "%s\n", loaded.error.c_str());
                return kUsage;
            }
            scene = std::move(loaded.scenes.front());
        }
        const std::string dir = (std::filesystem::path(out_dir) / scene_file_name(scene.name)).string();
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec) {
            std::fprintf(stderr, "%s: cannot create: %s\n", dir.c_str(), ec.message().c_str());
            return kUsage;
        }
        const std::vector<Knob> ks = knobs();
        RendererSettings tight;
        for (const Knob& k : ks) k.apply(tight, k.tightest);
        const BenchRun ref = run_bench(scene, tight, opt);
        if (!ref.error.empty()) {
            std::fprintf(stderr, "%s\n", ref.error.c_str());
            return kUsage;
        }
        std::vector<Point> points;
        auto measure = [&](const std::string& knob, double value, const RendererSettings& s, bool is_default) {
            const BenchRun run = run_bench(scene, s, opt);
            Point p;
            p.knob = knob;
            p.value = value;
            p.is_default = is_default;
            p.time = step_times(run);
            p.penetration = run.max_penetration_m;
            p.gap = run.max_gap_in_contact_m;
            compare(run, ref, p);
            points.push_back(p);
            std::printf("%-24s %-22s %-10.3g median %8.1f us  p99 %8.1f us  pen %.2e m  gap %.2e m  pose %.2e m  force %.2e N\n",
                        scene.name.c_str(), knob.c_str(), value, p.time.median, p.time.p99, p.penetration, p.gap,
                        p.pose_error, p.force_error);
            std::fflush(stdout);
        };
        const RendererSettings defaults;
        measure("defaults", 0.0, defaults, true);
        for (const Knob& k : ks)
            for (double v : k.values) {
                RendererSettings s;
                k.apply(s, v);
                measure(k.name, v, s, v == k.current(defaults));
            }
        std::string error;
        if (!write_outputs(scene.name, points, dir, &error)) {
            std::fprintf(stderr, "%s\n", error.c_str());
            return kUsage;
        }
    }
    return kOk;
}

}  // namespace sulcus::cli
