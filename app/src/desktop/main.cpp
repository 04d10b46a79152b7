// sulcus: the desktop app (docs/app.md).
#include "desktop/app.h"

#include "sulcus/app/lesson_session.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

const char* const kHelp =
    "usage: sulcus [--case DIR] [--device auto|mouse|sim|phantom|spacemouse]\n"
    "              [--screenshot FILE.png] [--ids FILE.png] [--frames N] [--seconds S] [--ticks N]\n"
    "              [--report FILE.json] [--size WxH] [--gingiva ALPHA] [--sextant 1-6]\n"
    "              [--lingual] [--reference] [--msaa N]\n"
    "              [--lesson FILE [--content-root DIR]] [--record FILE|none] [--instructor]\n"
    "\n"
    "Opens a patient case (a folder built by `sulcus-cli content case`) in a window: the probe in\n"
    "the pocket, the chart, the force, the device. Without a haptic device the mouse drives the\n"
    "probe (docs/app.md). With no --case, --lesson or --instructor it runs the bundled lesson\n"
    "healthy_11 when it is found, else opens the bundled case healthy_11.\n"
    "\n"
    "  --case DIR        the case folder (scene.json, case.glb, case.json)\n"
    "  --lesson FILE     run a lesson (sulcus.lesson/1, docs/lessons.md) on its built case (that\n"
    "                    replaces --case): steps, hints, feedback and the scores at the end\n"
    "  --content-root D  the folder the lesson's paths are relative to (default: the parent of the\n"
    "                    lesson's folder; instructor saves go to the bundled content root)\n"
    "  --record FILE     record the session (sulcus.recording/2) for `sulcus-cli replay`; a\n"
    "                    lesson is recorded by default to $SULCUS_SESSIONS_DIR, else\n"
    "                    $XDG_DATA_HOME/sulcus/sessions, else ~/.local/share/sulcus/sessions, as\n"
    "                    <lesson>-<UTC time>.rec; --record none records nothing\n"
    "  --instructor      edit the case's reference chart and save it, with a starter lesson, as a\n"
    "                    new case in the content root (then built in the background)\n"
    "  --device NAME     auto (a Phantom when one answers, else the mouse), mouse, sim (the\n"
    "                    simulated hand probing every site and charting it), phantom, spacemouse\n"
    "  --frames N        stop after N frames\n"
    "  --seconds S       stop once the servo loop has run S seconds (wall clock)\n"
    "  --ticks N         stop once the servo loop has made N ticks (the simulated hand's script\n"
    "                    time is N / rate); with several limits, all must be reached\n"
    "  --screenshot F    write the last frame to F (PNG)\n"
    "  --ids F           write the last frame's object ids to F (PNG: red = kind, green = FDI)\n"
    "  --report F        write the run's figures (servo rate, deadline misses, ...) to F (JSON)\n"
    "  --size WxH        window size (default 1600x900)\n"
    "  --gingiva A       start with the gingiva see-through at opacity A (0.1-1)\n"
    "  --sextant N       start with the view of sextant N (1-6); --lingual from lingual\n"
    "  --reference       show the case's reference chart beside the trainee's\n"
    "  --msaa N          samples per pixel of the 3D view (default 4; 0 on a software renderer)\n"
    "  --telemetry-queue N  ticks the UI's telemetry queue holds (default 8192, 65536 with a\n"
    "                    lesson); small values make it drop samples, for tests\n"
    "\n"
    "Exit 0 on a clean run, 1 when a picture or report could not be written or a non-finite force\n"
    "was sent or the recording could not be completed, 2 on bad arguments, a case or lesson that\n"
    "does not load, no display or no device.\n";

[[noreturn]] void usage(const std::string& what) {
    std::fprintf(stderr, "sulcus: %s\n", what.c_str());
    std::exit(2);
}

double number(const std::string& flag, const char* text, double lo, double hi) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
        usage(flag + ": '" + text + "' is not a number in " + std::to_string(lo) + " .. " + std::to_string(hi));
    return v;
}

// The bundled case next to the binary (build/bin/../cases/NAME), else under the source tree's
// build folder when run from the source root.
std::string default_case() {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const fs::path p = exe.parent_path().parent_path() / "cases" / "healthy_11";
        if (fs::exists(p / "scene.json")) return p.string();
    }
    return "build/cases/healthy_11";
}

}  // namespace

int main(int argc, char** argv) {
    sulcus::desktop::AppOptions o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) usage(a + " needs a value");
            return argv[++i];
        };
        if (a == "--help" || a == "-h") {
            std::fputs(kHelp, stdout);
            return 0;
        } else if (a == "--case") {
            o.case_dir = value();
        } else if (a == "--device") {
            o.device = value();
            if (o.device != "auto" && o.device != "mouse" && o.device != "sim" && o.device != "phantom" &&
                o.device != "spacemouse")
                usage("--device: unknown device '" + o.device + "' (auto, mouse, sim, phantom, spacemouse)");
        } else if (a == "--screenshot") {
            o.screenshot = value();
        } else if (a == "--ids") {
            o.ids = value();
        } else if (a == "--report") {
            o.report = value();
        } else if (a == "--frames") {
            o.frames = int(number(a, value(), 1, 1e7));
        } else if (a == "--seconds") {
            o.seconds = number(a, value(), 0.001, 1e6);
        } else if (a == "--ticks") {
            o.ticks = uint64_t(number(a, value(), 1, 1e12));
        } else if (a == "--size") {
            const char* v = value();
            int w = 0, h = 0;
            char tail = 0;
            if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 320 || h < 240 || w > 8192 || h > 8192)
                usage(std::string("--size: '") + v + "' is not WxH (320x240 .. 8192x8192)");
            o.width = w;
            o.height = h;
        } else if (a == "--gingiva") {
            o.gingiva_alpha = number(a, value(), 0.1, 1.0);
        } else if (a == "--sextant") {
            o.sextant = int(number(a, value(), 1, 6));
        } else if (a == "--lingual") {
            o.lingual = true;
        } else if (a == "--msaa") {
            o.msaa = int(number(a, value(), 0, 16));
        } else if (a == "--reference") {
            o.reference = true;
        } else if (a == "--lesson") {
            o.lesson = value();
        } else if (a == "--content-root") {
            o.content_root = value();
        } else if (a == "--record") {
            o.record = value();
            if (o.record.empty()) usage("--record: give a file, or none");
        } else if (a == "--instructor") {
            o.instructor = true;
        } else if (a == "--telemetry-queue") {
            o.telemetry_queue = std::size_t(number(a, value(), 16, 1 << 20));
        } else {
            usage("unknown argument '" + a + "' (--help lists them)");
        }
    }
    if ((!o.screenshot.empty() || !o.ids.empty()) && o.frames <= 0 && o.seconds <= 0.0 && o.ticks == 0)
        usage("--screenshot and --ids need --frames N, --seconds S or --ticks N (which frame to write)");
    if (!o.content_root.empty() && o.lesson.empty() && !o.instructor)
        usage("--content-root goes with --lesson or --instructor");
    if (o.case_dir.empty() && o.lesson.empty() && !o.instructor) {
        // The bundled lesson when the content is there, else the bundled case alone.
        namespace fs = std::filesystem;
        const fs::path lesson = fs::path(sulcus::default_content_root()) / "lessons" / "healthy_11.json";
        std::error_code ec;
        if (fs::is_regular_file(lesson, ec)) o.lesson = lesson.string();
    }
    if (o.case_dir.empty()) o.case_dir = default_case();
    sulcus::desktop::App app(o);
    return app.run();
}
