// sulcus-cli bench: the step timed over the fixed bench scenes, with its stages, counters and
// heap allocations; optionally our proximity queries against a peer library's on the same poses.
#include "cli/bench_run.h"
#include "cli/bench_scenes.h"
#include "cli/commands.h"
#include "cli/peer_fcl.h"
#include "sulcus/app/lesson_session.h"
#include "sulcus/app/text.h"
#include "sulcus/engine/runner.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace sulcus::cli {

const char* const kHelpBench =
    "usage: sulcus-cli bench [SCENE...] [--json FILE] [--peer fcl] [--max-ticks N] [--list]\n"
    "                        [--ticks DIR] [--check-every N] [--runs N] [--content-root DIR]\n"
    "                        [--cases DIR]\n"
    "\n"
    "Times the servo step over a fixed, deterministic set of scenes (the paper scenes, the\n"
    "bundled quadrant case probed at every site at full resolution, and a scripted session on it\n"
    "with the probe in contact in two regions), one step per tick on this thread. Only the step is\n"
    "inside the clock. Prints a table; --json writes\n"
    "  {\"machine\", \"scenes\": [{\"name\", \"triangles\", \"steps\", \"step_time_us\": {median, p99,\n"
    "   p999, max}, \"stages_us\": {stage: {median, p99}}, \"allocations_per_step\",\n"
    "   \"triangles_tested_per_step\", \"candidates_per_step\", ...}]}\n"
    "Every 10th tick with a force is checked exactly for penetration and gap, after the timed steps.\n"
    "First, a half-second spin on the clock measures what the machine takes from a running\n"
    "thread (\"machine\": {\"interruptions\"}): a step timed across such a gap is that much longer.\n"
    "\n"
    "  SCENE            run only these (names from --list)\n"
    "  --peer fcl       also time our proximity and collision queries against FCL's on the same\n"
    "                   meshes and poses (graphic poses of the run), as a time ratio\n"
    "  --max-ticks N    only the first N ticks of each scene (for profiling)\n"
    "  --check-every N  the exact checks on every N-th tick with a force instead (0: none)\n"
    "  --runs N         run each scene N times from a fresh state: every run must give the same\n"
    "                   answers to the bit; \"least_of_runs\" has the step time per tick the least\n"
    "                   over the runs (what the step costs, less the machine's interruptions)\n"
    "  --ticks DIR      also write each scene's ticks, one row per step with its status, stage\n"
    "                   times, counters, graphic pose and force, to DIR/<scene>_ticks.csv ('/' in a\n"
    "                   name as '_'): to find the slow ticks, and to compare two builds' answers\n"
    "  --list           print the scene names and exit\n";

namespace {

std::string cpu_model() {
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) {
            const size_t c = line.find(':');
            if (c != std::string::npos) return line.substr(c + 2);
        }
    return "unknown";
}

nlohmann::json machine_json() {
    nlohmann::json m;
    m["cpu"] = cpu_model();
    m["hardware_threads"] = std::thread::hardware_concurrency();
#if defined(__clang__)
    m["compiler"] = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
    m["compiler"] = std::string("gcc ") + __VERSION__;
#endif
#if defined(__OPTIMIZE__)
    m["optimized"] = true;
#else
    m["optimized"] = false;
#endif
    m["threads_used"] = 1;
    return m;
}

nlohmann::json pct_json(const Percentiles& p, bool full) {
    nlohmann::json j{{"median", p.median}, {"p99", p.p99}};
    if (full) {
        j["p999"] = p.p999;
        j["max"] = p.max;
    }
    return j;
}

nlohmann::json peer_json(const std::string& scene, const PeerComparison& c) {
    nlohmann::json j{{"scene", scene}};
    if (!c.error.empty()) j["error"] = c.error;
    nlohmann::json qs = nlohmann::json::array();
    for (const PeerQueryTiming& q : c.queries)
        qs.push_back({{"query", q.query},
                      {"queries", q.queries},
                      {"ours_us", pct_json(q.ours_us, true)},
                      {"peer_us", pct_json(q.peer_us, true)},
                      {"ratio", q.ratio},
                      {"max_difference_m", q.max_difference_m},
                      {"disagreements", q.disagreements}});
    j["queries"] = qs;
    return j;
}

// One row per tick: what the step did and how long each stage took.
bool write_ticks_csv(const std::string& path, const BenchRun& run) {
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) return false;
    std::fprintf(f, "tick,status,step_us,detect_us,gather_us,solve_us,select_us,force_us,triangles_near,"
                    "triangles_tested,atoms_gathered,candidates,atoms,qp_solves,qp_iterations,relinearizations,"
                    "passes,rescues,released,gather_truncated,regions,soft_depth_m,allocations,px_m,py_m,pz_m,qw,qx,qy,qz,"
                    "fx_N,fy_N,fz_N,compliant_gathers,quiet_triangles,edge_queries,edge_memos_ahead,face_searches,deferred,least_step_us\n");
    for (size_t i = 0; i < run.ticks.size(); ++i) {
        const BenchTick& t = run.ticks[i];
        const StepStats& s = t.stats;
        // The answer to the last bit (%.17g), so that runs of two builds compare exactly.
        const Vec3& p = t.graphic.position;
        const Quat& q = t.graphic.orientation;
        std::fprintf(f,
                     "%zu,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%.9g,%ld,"
                     "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%d,%d,%d,%d,%.3f\n",
                     i, to_string(t.status), t.step_us, s.times.detect_us, s.times.gather_us, s.times.solve_us,
                     s.times.select_us, s.times.force_us, s.triangles_near, s.triangles_tested, s.atoms_gathered,
                     s.candidates, s.atoms, s.qp_solves, s.qp_iterations, s.relinearizations, s.passes, s.rescues,
                     int(s.released), int(s.gather_truncated), s.regions, s.soft_depth_m, t.allocations, p.x, p.y, p.z,
                     q.w, q.x, q.y, q.z, t.force_N.x, t.force_N.y, t.force_N.z, s.compliant_gathers,
                     s.quiet_triangles, s.edge_queries, s.edge_memos_ahead, s.face_searches, int(s.deferred),
                     t.least_step_us);
    }
    return std::fclose(f) == 0;
}

}  // namespace

int cmd_bench(const std::vector<std::string>& args) {
    std::string json_path, peer, content_root, cases_dir, ticks_dir;
    std::vector<std::string> names;
    long max_ticks = 0, check_every = 10, runs = 1;
    bool list = false;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--json" || a == "--peer" || a == "--max-ticks" || a == "--content-root" || a == "--cases" ||
            a == "--ticks" || a == "--check-every" || a == "--runs") {
            if (i + 1 >= args.size()) return usage("bench: " + a + " needs a value");
            const std::string& v = args[++i];
            if (a == "--json") json_path = v;
            else if (a == "--peer") peer = v;
            else if (a == "--content-root") content_root = v;
            else if (a == "--cases") cases_dir = v;
            else if (a == "--ticks") ticks_dir = v;
            else if (a == "--runs") {
                if (!parse_whole(v, 1, 1000, &runs))
                    return usage("bench: --runs needs a whole number from 1 to 1000, not '" + v + "'");
            } else if (a == "--check-every") {
                if (!parse_whole(v, 0, INT_MAX, &check_every))
                    return usage("bench: --check-every needs a whole number, not '" + v + "'");
            } else if (!parse_whole(v, 1, LONG_MAX, &max_ticks))
                return usage("bench: --max-ticks needs a positive whole number, not '" + v + "'");
        } else if (a == "--list") {
            list = true;
        } else if (!a.empty() && a[0] == '-') {
            return usage("bench: unknown option '" + a + "'");
        } else {
            names.push_back(a);
        }
    }
    if (!peer.empty() && peer != "fcl") return usage("bench: unknown peer '" + peer + "' (known: fcl)");
    if (!peer.empty() && !fcl_available()) {
        std::fprintf(stderr, "sulcus-cli: bench: this build has no FCL (install Debian libfcl-dev and rebuild)\n");
        return kUsage;
    }
    if (content_root.empty()) content_root = default_content_root();
    if (cases_dir.empty()) cases_dir = default_cases_dir();
    if (list) {
        for (const std::string& n : bench_scene_names()) std::printf("%s\n", n.c_str());
        return kOk;
    }
    // One scene at a time: the quadrant's meshes are large.
    const std::vector<std::string> all = bench_scene_names();
    const std::vector<std::string> order = names.empty() ? all : names;
    for (const std::string& n : order)
        if (std::find(all.begin(), all.end(), n) == all.end())
            return usage("bench: unknown scene '" + n + "' (the scenes: 'sulcus-cli bench --list')");
    if (!ticks_dir.empty()) {
        // Made before any scene runs, so that a bad directory costs no run.
        std::error_code ec;
        std::filesystem::create_directories(ticks_dir, ec);
        if (ec || !std::filesystem::is_directory(ticks_dir)) {
            std::fprintf(stderr, "sulcus-cli: bench: %s: cannot create: %s\n", ticks_dir.c_str(),
                         ec ? ec.message().c_str() : "not a directory");
            return kUsage;
        }
    }
    nlohmann::json out;
    out["machine"] = machine_json();
    {
        const Interruptions in = probe_interruptions(0.5);
        out["machine"]["interruptions"] = {{"probe_s", in.seconds},
                                           {"threshold_us", 5.0},
                                           {"per_second", in.per_second},
                                           {"lost_fraction", in.lost_fraction},
                                           {"length_us", pct_json(in.length_us, true)}};
        std::printf("machine: %.0f interruptions per second of 5 us or more, %.1f %% of the time; length median "
                    "%.1f us, p99 %.1f us, max %.1f us\n",
                    in.per_second, 100.0 * in.lost_fraction, in.length_us.median, in.length_us.p99, in.length_us.max);
    }
    out["scenes"] = nlohmann::json::array();
    nlohmann::json peers = nlohmann::json::array();
    std::printf("%-28s %9s %7s %7s %9s %9s %9s %9s %7s %8s %6s %10s\n", "scene", "triangles", "steps", "contact",
                "median_us", "p99_us", "p999_us", "max_us", "allocs", "tests", "cands", "max_pen_m");
    for (const std::string& name : order) {
        BenchScenes loaded = load_bench_scenes({name}, content_root, cases_dir);
        if (!loaded.error.empty()) {
            std::fprintf(stderr, "%s\n", loaded.error.c_str());
            return kUsage;
        }
        const BenchScene& b = loaded.scenes.front();
        BenchRunOptions opt;
        opt.max_ticks = max_ticks;
        opt.check_every = int(check_every);
        opt.runs = int(runs);
        const BenchRun run = run_bench(b, RendererSettings{}, opt);
        if (!run.error.empty()) {
            std::fprintf(stderr, "%s\n", run.error.c_str());
            return kUsage;
        }
        std::vector<double> times, least, stage[kStageCount];
        long allocations = 0, contact = 0, two_regions = 0;
        double tests = 0, cands = 0;
        for (const BenchTick& t : run.ticks) {
            times.push_back(t.step_us);
            least.push_back(t.least_step_us);
            for (int k = 0; k < kStageCount; ++k) stage[k].push_back(stage_us(t.stats.times, k));
            allocations += t.allocations;
            contact += t.contact;
            two_regions += t.stats.regions >= 2;
            tests += t.stats.triangles_tested;
            cands += t.stats.candidates;
        }
        const double steps = double(std::max<size_t>(1, run.ticks.size()));
        const Percentiles st = percentiles(times);
        nlohmann::json stages;
        for (int k = 0; k < kStageCount; ++k) stages[kStageNames[k]] = pct_json(percentiles(stage[k]), false);
        out["scenes"].push_back({{"name", b.name},
                                 {"triangles", b.triangles},
                                 {"steps", run.ticks.size()},
                                 {"contact_steps", contact},
                                 {"steps_with_two_regions", two_regions},
                                 {"step_time_us", pct_json(st, true)},
                                 {"stages_us", stages},
                                 {"allocations_per_step", double(allocations) / steps},
                                 {"allocations", allocations},
                                 {"triangles_tested_per_step", tests / steps},
                                 {"candidates_per_step", cands / steps},
                                 {"checked_ticks", run.checked_ticks},
                                 {"max_penetration_m", run.max_penetration_m},
                                 {"max_gap_in_contact_m", run.max_gap_in_contact_m}});
        std::printf("%-28s %9zu %7zu %7ld %9.1f %9.1f %9.1f %9.1f %7.3f %8.1f %6.2f %10.2e\n", b.name.c_str(), b.triangles,
                    run.ticks.size(), contact, st.median, st.p99, st.p999, st.max, double(allocations) / steps,
                    tests / steps, cands / steps, run.max_penetration_m);
        if (runs > 1) {
            const Percentiles lt = percentiles(least);
            out["scenes"].back()["least_of_runs"] = {{"runs", runs}, {"step_time_us", pct_json(lt, true)}};
            std::printf("%-28s %9s %7s %7s %9.1f %9.1f %9.1f %9.1f   per tick the least of %ld runs, the same answers\n",
                        "", "", "", "", lt.median, lt.p99, lt.p999, lt.max, runs);
        }
        std::fflush(stdout);
        if (!ticks_dir.empty()) {
            const std::string path = (std::filesystem::path(ticks_dir) / (scene_file_name(b.name) + "_ticks.csv")).string();
            if (!write_ticks_csv(path, run)) {
                std::fprintf(stderr, "sulcus-cli: bench: %s: cannot write the ticks\n", path.c_str());
                return kUsage;
            }
        }
        if (!peer.empty()) {
            // The graphic poses of the run: where the tool really went, touching or near.
            std::vector<Pose> poses;
            const size_t stride = std::max<size_t>(1, run.ticks.size() / 400);
            for (size_t i = 0; i < run.ticks.size(); i += stride) poses.push_back(run.ticks[i].graphic);
            const PeerComparison c = compare_with_fcl(*run.model, poses);
            peers.push_back(peer_json(b.name, c));
            for (const PeerQueryTiming& q : c.queries)
                std::printf("  vs fcl %-10s %5ld poses: ours median %8.2f us, fcl %8.2f us, fcl/ours %6.2f\n",
                            q.query.c_str(), q.queries, q.ours_us.median, q.peer_us.median, q.ratio);
            if (!c.error.empty()) std::printf("  vs fcl: %s\n", c.error.c_str());
        }
    }
    if (!peer.empty()) out["peer"] = {{"name", peer}, {"scenes", peers}};
    if (!json_path.empty()) {
        std::string error;
        if (!write_file_atomic(json_path, out.dump(2) + "\n", &error)) {
            std::fprintf(stderr, "%s\n", error.c_str());
            return kUsage;
        }
    }
    return kOk;
}

}  // namespace sulcus::cli
