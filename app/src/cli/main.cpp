// sulcus-cli: the headless command line. Exit status: 0 done; 1 ran, but a requested check
// failed; 2 bad input or usage; 3 internal error.
#include "cli/commands.h"
#include "sulcus/app/run_plots.h"
#include "sulcus/engine/runner.h"
#include "sulcus/engine/scene_file.h"

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

namespace sulcus::cli {

int usage(const std::string& msg) {
    std::fprintf(stderr, "sulcus-cli: %s\n", msg.c_str());
    std::fprintf(stderr, "try 'sulcus-cli help'\n");
    return kUsage;
}

bool parse_whole(const std::string& text, long lo, long hi, long* out) {
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(text.c_str(), &end, 10);
    if (end == text.c_str() || *end != '\0' || errno == ERANGE || n < lo || n > hi) return false;
    *out = n;
    return true;
}

}  // namespace sulcus::cli

namespace {

using namespace sulcus::cli;

const char* kHelpMain =
    "usage: sulcus-cli COMMAND [ARGS]\n"
    "\n"
    "commands:\n"
    "  run SCENE.json [--out DIR] [--plot]   run a scene headless, one step per servo tick\n"
    "  content SUBCOMMAND ...                cases from charts, teeth, probes, checks, import\n"
    "  tissue [--out DIR]                    force-depth curves of the pocket-floor tissues\n"
    "  servo --device sim [--scene FILE] [--seconds N] [--record FILE]\n"
    "                                        the real-time servo loop with a device\n"
    "  devices [--json]                      list attached haptic and 6-DOF devices\n"
    "  replay RECORDING|FOLDER... [--check] [--report FILE] [--jobs N] [--shard I/N] [--junit FILE]\n"
    "                                        replay recorded lessons headless and score them\n"
    "  lesson check|new|record ...           validate, start or record a lesson\n"
    "  bench [SCENE...] [--json FILE] [--peer fcl]\n"
    "                                        time the step on the fixed bench scenes\n"
    "  wpd SCENE... --out DIR                error against run time over the accuracy settings\n"
    "  help [COMMAND]                        show help for a command\n"
    "\n"
    "exit status: 0 done; 1 ran, but a requested check failed; 2 bad input or usage;\n"
    "3 internal error\n";

const char* kHelpRun =
    "usage: sulcus-cli run SCENE.json [--out DIR] [--plot]\n"
    "\n"
    "Runs the scene (format sulcus.scene/1) headless: the haptic trajectory is sampled at the\n"
    "scene's rate_hz, each tick is one renderer step, and every tick's graphic pose is checked\n"
    "exactly for penetration and, where a force is rendered, for a gap.\n"
    "\n"
    "  --out DIR   where to write summary.json and steps.csv (default ./out/<scene name>)\n"
    "  --plot      also write force.svg (force and torque against time) and step_time.svg\n"
    "              (step time and its stages against time)\n"
    "\n"
    "Prints one summary line. Bad input (files, formats, values) exits 2 with one line per\n"
    "fault naming the file and the place.\n";

int cmd_run(const std::vector<std::string>& args) {
    std::string scene_path, out_dir;
    bool plot = false;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--out") {
            if (i + 1 >= args.size()) return usage("run: --out needs a folder");
            out_dir = args[++i];
        } else if (args[i] == "--plot") {
            plot = true;
        } else if (!args[i].empty() && args[i][0] == '-') {
            return usage("run: unknown option '" + args[i] + "'");
        } else if (scene_path.empty()) {
            scene_path = args[i];
        } else {
            return usage("run: more than one scene given ('" + args[i] + "')");
        }
    }
    if (scene_path.empty()) return usage("run: no scene file given");
    const sulcus::SceneLoad load = sulcus::load_scene(scene_path);
    for (const std::string& w : load.scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (!load.ok()) {
        for (const std::string& e : load.errors) std::fprintf(stderr, "%s\n", e.c_str());
        return kUsage;
    }
    if (out_dir.empty()) out_dir = (std::filesystem::path("out") / load.scene.name).string();
    const sulcus::RunResult run = sulcus::run_scene(load.scene, sulcus::RendererSettings{});
    if (!run.error.empty()) {
        std::fprintf(stderr, "%s\n", run.error.c_str());
        return kUsage;
    }
    std::string error;
    if (!sulcus::write_run(run, out_dir, &error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return kUsage;
    }
    if (plot && !sulcus::write_run_plots(run, out_dir, &error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return kUsage;
    }
    std::printf("%s\n", sulcus::summary_line(run.summary).c_str());
    return kOk;
}

int cmd_help(const std::vector<std::string>& args) {
    if (args.empty()) {
        std::fputs(kHelpMain, stdout);
        return kOk;
    }
    if (args[0] == "run") {
        std::fputs(kHelpRun, stdout);
        return kOk;
    }
    if (args[0] == "content") {
        std::fputs(kHelpContent, stdout);
        return kOk;
    }
    if (args[0] == "tissue") {
        std::fputs(kHelpTissue, stdout);
        return kOk;
    }
    if (args[0] == "servo") {
        std::fputs(kHelpServo, stdout);
        return kOk;
    }
    if (args[0] == "devices") {
        std::fputs(kHelpDevices, stdout);
        return kOk;
    }
    if (args[0] == "replay") {
        std::fputs(kHelpReplay, stdout);
        return kOk;
    }
    if (args[0] == "lesson") {
        std::fputs(kHelpLesson, stdout);
        return kOk;
    }
    if (args[0] == "bench") {
        std::fputs(kHelpBench, stdout);
        return kOk;
    }
    if (args[0] == "wpd") {
        std::fputs(kHelpWpd, stdout);
        return kOk;
    }
    return usage("help: unknown command '" + args[0] + "'");
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) {
            std::fputs(kHelpMain, stderr);
            return kUsage;
        }
        const std::string cmd = argv[1];
        std::vector<std::string> args(argv + 2, argv + argc);
        if (cmd == "run") return cmd_run(args);
        if (cmd == "content") return cmd_content(args);
        if (cmd == "tissue") return cmd_tissue(args);
        if (cmd == "servo") return cmd_servo(args);
        if (cmd == "devices") return cmd_devices(args);
        if (cmd == "replay") return cmd_replay(args);
        if (cmd == "lesson") return cmd_lesson(args);
        if (cmd == "bench") return cmd_bench(args);
        if (cmd == "wpd") return cmd_wpd(args);
        if (cmd == "help" || cmd == "--help" || cmd == "-h") return cmd_help(args);
        return usage("unknown command '" + cmd + "'");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sulcus-cli: internal error: %s\n", e.what());
        return kInternal;
    } catch (...) {
        std::fprintf(stderr, "sulcus-cli: internal error\n");
        return kInternal;
    }
}
