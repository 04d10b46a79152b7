// The bench's own scenes (app/src/cli/bench_scenes.cpp) for the engine's tests: one loaded by
// name, and its model built with given settings.
#pragma once

#include "cli/bench_scenes.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>

namespace sulcus::test {

// Bench scene `name` (the quadrant's from the built cases); empty, after a failed expectation,
// when it does not load.
inline cli::BenchScene load_bench_scene(const std::string& name) {
    cli::BenchScenes s = cli::load_bench_scenes({name}, std::string(SULCUS_SOURCE_DIR) + "/content/assets",
                                                std::string(SULCUS_BINARY_DIR) + "/cases");
    EXPECT_EQ(s.error, "");
    EXPECT_EQ(s.scenes.size(), 1u);
    return s.scenes.empty() ? cli::BenchScene{} : std::move(s.scenes.front());
}

// The model of bench scene `b` with `settings` (their haptic part the scene's own).
inline std::unique_ptr<Model> bench_model(const cli::BenchScene& b, RendererSettings settings) {
    settings.haptic = b.scene.haptic;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    EXPECT_TRUE(mb.model) << mb.error;
    return std::move(mb.model);
}

}  // namespace sulcus::test
