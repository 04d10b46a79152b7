// Writes the bundled paper scenes (meshes, trajectories, scene files, README):
//   make_paper_scenes [DIR]    (default: content/assets/scenes/paper)
#include "sulcus/content/paper_scenes.h"

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    if (argc > 2) {
        std::fprintf(stderr, "usage: make_paper_scenes [DIR]\n");
        return 2;
    }
    const std::string dir = argc > 1 ? argv[1] : "content/assets/scenes/paper";
    std::string error;
    if (!sulcus::write_paper_scenes(dir, &error)) {
        std::fprintf(stderr, "make_paper_scenes: %s\n", error.c_str());
        return 1;
    }
    std::printf("wrote %zu scenes to %s\n", sulcus::paper_scene_names().size(), dir.c_str());
    return 0;
}
