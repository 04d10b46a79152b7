// A probe leaning in the compliant tissue of a full-resolution case: the bench's two-region
// session at 46 B (tip pressed into the pocket floor, side against the root, the gingiva's wall
// giving way along the shank). Every tick finds its answer in the pass it starts with, or one
// more: a contact where the tissue gives way counts as real where the tool really is that deep
// in it, not only on the face whose plane holds it, so the step does not run pass after pass
// (and then hold) on contacts that are there. And no tissue triangle is entered deeper than the
// tissue gives way.
#include "cli/bench_scenes.h"
#include "geometry.h"
#include "sulcus/engine/renderer.h"
#include "tool_placement.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace sulcus;

namespace {

cli::BenchScene load_session() {
    cli::BenchScenes s = cli::load_bench_scenes({"quadrant_two_regions"}, std::string(SULCUS_SOURCE_DIR) + "/content/assets",
                                                std::string(SULCUS_BINARY_DIR) + "/cases");
    EXPECT_EQ(s.error, "");
    EXPECT_EQ(s.scenes.size(), 1u);
    return s.scenes.empty() ? cli::BenchScene{} : std::move(s.scenes.front());
}

TEST(CompliantSession, LeaningInTheTissueNeedsNoPassAfterPass) {
    cli::BenchScenes s = cli::load_bench_scenes({"quadrant_two_regions"}, std::string(SULCUS_SOURCE_DIR) + "/content/assets",
                                                std::string(SULCUS_BINARY_DIR) + "/cases");
    ASSERT_EQ(s.error, "");
    ASSERT_EQ(s.scenes.size(), 1u);
    const cli::BenchScene& b = s.scenes.front();
    RendererSettings settings;
    settings.haptic = b.scene.haptic;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    ASSERT_TRUE(mb.model) << mb.error;
    State state = make_state(b.ticks.front());
    int contact = 0, soft = 0, two_regions = 0, extra = 0, held = 0, most_passes = 0;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        const StepResult r = step(*mb.model, state, b.ticks[i]);
        held += r.status == StepStatus::Held;
        if (r.status != StepStatus::Contact) continue;
        ++contact;
        soft += r.stats.soft_zones > 0;
        two_regions += r.stats.regions >= 2;
        extra += r.stats.passes > 0;
        most_passes = std::max(most_passes, r.stats.passes);
    }
    // The session is what it says: in contact most of the time, in the tissue, in two regions.
    EXPECT_GT(contact, 4000);
    EXPECT_GT(soft, 4000);
    EXPECT_GT(two_regions, 2500);
    // No tick holds its last pose, none runs out of passes, and extra passes are rare.
    EXPECT_EQ(held, 0);
    EXPECT_LE(most_passes, 2);
    EXPECT_LE(extra, contact / 100);
}

// At every 10th tick, each piece of the tool at the graphic pose overlaps no triangle of the
// gingiva (by the separating-axis test: the least overlap over all axes) deeper than the deepest
// give of the tissue at that tick, within the constraint tolerance.
TEST(CompliantSession, NoTissueTriangleIsEnteredDeeperThanTheTissueGives) {
    const cli::BenchScene b = load_session();
    ASSERT_FALSE(b.ticks.empty());
    RendererSettings settings;
    settings.haptic = b.scene.haptic;
    ModelBuild mb = build_model(b.scene.tool.mesh, b.scene.objects, settings, b.scene.materials);
    ASSERT_TRUE(mb.model) << mb.error;
    const Model& model = *mb.model;
    const ModelTool& tool = model.tool;
    std::vector<Vec3> vertices(tool.mesh.vertices.size()), normals(tool.face_normals.size());
    std::vector<double> offsets(tool.face_normals.size());
    State state = make_state(b.ticks.front());
    int checked = 0, overlapped = 0;
    double deepest_excess = -1e300;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        const StepResult r = step(model, state, b.ticks[i]);
        if (i % 10 != 0 || (r.status != StepStatus::Contact && r.status != StepStatus::Free)) continue;
        ++checked;
        const Quat q = r.graphic.orientation;
        place_tool_vertices(tool, q, r.graphic.position, vertices.data());
        place_tool_planes(tool, q, r.graphic.position, normals.data(), offsets.data());
        for (size_t k = 0; k < tool.pieces.size(); ++k) {
            const ConvexView view = tool_convex_view(tool, k, vertices.data(), normals.data(), offsets.data(), &q);
            Aabb box;
            for (int v = 0; v < view.vertex_count; ++v) box.grow(view.vertices[v]);
            for (const ModelObject& obj : model.objects) {
                if (!obj.compliant) continue;
                obj.bvh.query(box, [&](uint32_t tri) {
                    const auto& t = obj.mesh.triangles[tri];
                    const double sep = separate_convex_triangle(view, obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]],
                                                                obj.mesh.vertices[t[2]])
                                           .separation;
                    if (sep < 0.0) {
                        ++overlapped;
                        deepest_excess = std::max(deepest_excess, -sep - r.stats.soft_depth_m);
                    }
                    return true;
                });
            }
        }
    }
    EXPECT_GT(checked, 400);
    EXPECT_GT(overlapped, 10000);  // the tool is in the tissue much of the time
    EXPECT_LE(deepest_excess, settings.constraint_tol_m + 1e-12);
}

}  // namespace
