// sulcus-cli servo: the real-time servo loop against a device, with a timing summary.
#include "cli/commands.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"
#include "sulcus/haptics/recording.h"
#include "sulcus/haptics/phantom_device.h"
#include "sulcus/haptics/servo_loop.h"
#include "sulcus/haptics/sim_device.h"
#include "sulcus/haptics/spacemouse_device.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace sulcus::cli {

const char* const kHelpServo =
    "usage: sulcus-cli servo --device sim|phantom|spacemouse [--scene FILE] [--seconds N] [--record FILE]\n"
    "\n"
    "Runs the servo loop on its own thread at the scene's rate_hz (absolute deadlines on\n"
    "CLOCK_MONOTONIC; SCHED_FIFO when the system grants it): each tick reads the device, steps\n"
    "the renderer, passes the wrench through the safety layer and writes it to the device.\n"
    "Prints one summary: achieved rate, period jitter p50/p99/max, deadline misses, step time\n"
    "p50/p99/max and whether SCHED_FIFO was granted.\n"
    "\n"
    "  --device sim         a simulated hand holding the stylus, following the scene's trajectory\n"
    "  --device phantom     a Phantom / Touch through OpenHaptics (libHD.so loaded at run time;\n"
    "                       $SULCUS_LIBHD names another); the stylus's first reading is put on the\n"
    "                       trajectory's first pose\n"
    "  --device spacemouse  a 3Dconnexion SpaceMouse through hidapi (input only, no force),\n"
    "                       starting at the trajectory's first pose\n"
    "  --scene FILE    scene (sulcus.scene/1); default content/assets/scenes/paper/cavity_1mm.json\n"
    "                  relative to the current folder (run from the source root), else to\n"
    "                  $SULCUS_SOURCE_DIR\n"
    "  --seconds N     how long to run (default 5)\n"
    "  --record FILE   write the session (sulcus.recording/2) to FILE\n"
    "\n"
    "Exit 0 when the loop ran and sent only finite forces, 1 otherwise, 2 on bad input or a\n"
    "device that cannot be opened (the reason on one line).\n";

namespace {

constexpr const char* kDefaultScene = "content/assets/scenes/paper/cavity_1mm.json";

std::string default_scene() {
    if (std::filesystem::exists(kDefaultScene)) return kDefaultScene;
    if (const char* src = std::getenv("SULCUS_SOURCE_DIR")) {
        const std::filesystem::path p = std::filesystem::path(src) / kDefaultScene;
        if (std::filesystem::exists(p)) return p.string();
    }
    return kDefaultScene;  // load_scene names it in its error
}

}  // namespace

int cmd_servo(const std::vector<std::string>& args) {
    std::string device_name, scene_path, record_path;
    double seconds = 5.0;
    for (size_t i = 0; i < args.size(); ++i) {
        auto value = [&]() -> const std::string* { return i + 1 < args.size() ? &args[++i] : nullptr; };
        if (args[i] == "--device") {
            const std::string* v = value();
            if (!v) return usage("servo: --device needs a name (sim)");
            device_name = *v;
        } else if (args[i] == "--scene") {
            const std::string* v = value();
            if (!v) return usage("servo: --scene needs a file");
            scene_path = *v;
        } else if (args[i] == "--seconds") {
            const std::string* v = value();
            if (!v) return usage("servo: --seconds needs a number");
            char* end = nullptr;
            seconds = std::strtod(v->c_str(), &end);
            if (end == v->c_str() || *end != '\0' || !std::isfinite(seconds) || seconds <= 0.0)
                return usage("servo: --seconds: '" + *v + "' is not a positive number");
        } else if (args[i] == "--record") {
            const std::string* v = value();
            if (!v) return usage("servo: --record needs a file");
            record_path = *v;
        } else {
            return usage("servo: unknown argument '" + args[i] + "'");
        }
    }
    if (device_name.empty()) return usage("servo: no device given (--device sim|phantom|spacemouse)");
    if (device_name != "sim" && device_name != "phantom" && device_name != "spacemouse")
        return usage("servo: unknown device '" + device_name + "' (sim, phantom, spacemouse)");

    if (scene_path.empty()) scene_path = default_scene();
    const SceneLoad load = load_scene(scene_path);
    for (const std::string& w : load.scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (!load.ok()) {
        for (const std::string& e : load.errors) std::fprintf(stderr, "%s\n", e.c_str());
        return kUsage;
    }
    if (load.scene.trajectory.empty() && device_name == "sim") {
        std::fprintf(stderr, "%s: the simulated hand needs a trajectory\n", scene_path.c_str());
        return kUsage;
    }
    // Where the probing starts: the trajectory's first pose (the scene's origin without one).
    const Pose start = load.scene.trajectory.empty() ? Pose{} : load.scene.trajectory.front().pose;
    const ModelBuild build = build_model(load.scene, RendererSettings{});
    if (!build.model) {
        std::fprintf(stderr, "%s: %s\n", scene_path.c_str(), build.error.c_str());
        return kUsage;
    }

    ServoConfig config;
    config.rate_hz = load.scene.rate_hz;
    config.duration_s = seconds;
    std::unique_ptr<Device> device;
    if (device_name == "sim") {
        // The hand's script is in the scene's frame already.
        HandParameters hand_parameters;
        hand_parameters.dt_s = 1.0 / config.rate_hz;
        device = std::make_unique<SimulatedHand>(load.scene.trajectory, hand_parameters);
    } else if (device_name == "phantom") {
        device = std::make_unique<PhantomDevice>(PhantomOptions{});
        config.anchor = true;
        config.anchor_position_m = start.position;
    } else {
        SpaceMouseDeviceConfig sm;
        sm.rate_hz = config.rate_hz;
        sm.start_pose = start;
        sm.workspace_min_m = start.position - Vec3(0.05);
        sm.workspace_max_m = start.position + Vec3(0.05);
        device = std::make_unique<SpaceMouseDevice>(sm);
    }

    RecordingWriter recorder;
    if (!record_path.empty()) {
        RecordingMetadata meta;
        meta.case_path = scene_path;
        meta.device = device_name;
        meta.rate_hz = config.rate_hz;
        std::string err = recorder.open(record_path, meta);
        if (err.empty()) err = recorder.start_writer_thread();
        if (!err.empty()) {
            std::fprintf(stderr, "%s\n", err.c_str());
            return kUsage;
        }
    }

    ServoLoop loop;
    const std::string err = loop.start(config, *device, *build.model, record_path.empty() ? nullptr : &recorder);
    if (!err.empty()) {
        std::fprintf(stderr, "sulcus-cli: servo: %s\n", err.c_str());
        if (!record_path.empty()) (void)recorder.close();  // keeps the header: the file still opens
        return kUsage;
    }
    if (!loop.realtime()) std::fprintf(stderr, "warning: %s\n", loop.realtime_message().c_str());
    loop.wait();
    if (!record_path.empty()) {
        const std::string close_err = recorder.close();
        if (!close_err.empty()) {
            std::fprintf(stderr, "%s\n", close_err.c_str());
            return kFailed;
        }
    }

    const ServoStats st = loop.stats();
    std::printf("servo %s (%s, %g s): %llu ticks, rate %.1f Hz (nominal %.0f), period jitter p50/p99/max "
                "%.1f/%.1f/%.1f us, deadline misses %llu, step time p50/p99/max %.1f/%.1f/%.1f us, "
                "max force %.3f N, SCHED_FIFO %s\n",
                load.scene.name.c_str(), device->capabilities().name.c_str(), seconds,
                static_cast<unsigned long long>(st.ticks), st.achieved_rate_hz,
                st.nominal_rate_hz, st.jitter_us.p50, st.jitter_us.p99, st.jitter_us.max,
                static_cast<unsigned long long>(st.deadline_misses), st.step_us.p50, st.step_us.p99, st.step_us.max,
                st.max_force_sent_N, st.realtime ? "granted" : "refused");
    if (!record_path.empty()) {
        const RecordingStats rs = recorder.stats();
        std::printf("recorded %llu ticks to %s (%llu dropped)\n", static_cast<unsigned long long>(rs.ticks_written),
                    record_path.c_str(), static_cast<unsigned long long>(rs.ticks_dropped));
    }
    return st.non_finite_sent || st.ticks == 0 ? kFailed : kOk;
}

}  // namespace sulcus::cli
