// The fixed, deterministic scenes of `sulcus-cli bench` and `sulcus-cli wpd`: the paper scenes,
// the bundled quadrant case probed site by site at full resolution, a scripted session on that
// quadrant that keeps the probe in contact in two regions at once (tip on the pocket floor, side
// on the root, in the compliant gingiva), and a dense rigid scene of about 250k triangles with
// the probe wedged between two crowns (two regions).
#pragma once

#include "sulcus/engine/scene_file.h"
#include "sulcus/engine/types.h"

#include <string>
#include <vector>

namespace sulcus::cli {

struct BenchScene {
    std::string name;
    SceneFile scene;          // tool, objects, materials, haptic settings
    std::vector<Pose> ticks;  // the haptic pose of every servo tick, in order
    size_t triangles = 0;     // object triangles
};

struct BenchScenes {
    std::vector<BenchScene> scenes;
    std::string error;  // one line when a scene cannot be loaded
};

// The names of the fixed set, in the order they run (the paper scenes as content lists them).
std::vector<std::string> bench_scene_names();

// A scene's name as a file or folder name ("paper/cavity_0mm" -> "paper_cavity_0mm").
std::string scene_file_name(std::string name);

// Loads the named scenes (all of them when `names` is empty). `content_root` holds
// scenes/paper/; `cases_dir` the built cases (build/cases).
BenchScenes load_bench_scenes(const std::vector<std::string>& names, const std::string& content_root,
                              const std::string& cases_dir);

// The haptic pose of every tick of a scene's own trajectory at its rate (as `sulcus-cli run`).
std::vector<Pose> trajectory_ticks(const SceneFile& scene);

}  // namespace sulcus::cli
