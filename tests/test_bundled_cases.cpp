// The bundled cases (content/assets/cases/*/chart.json, built into build/cases/ by the build):
// at every site, the probe (tip, shank and handle) inserted along the long axis stops at the
// charted depth — the graphic tip, when the rendered force first reaches 0.25 N, is within 0.2 mm
// of the charted floor (pd below the gingival margin) — and pushed on to 0.5 N it goes the
// documented extra depth of the site's tissue further (about 0.5 mm where inflamed), within 0.1 mm.
#include "probing_check.h"

#include "sulcus/content/chart.h"
#include "sulcus/content/gltf_io.h"
#include "sulcus/engine/json_text.h"

#include <gtest/gtest.h>

namespace sulcus {
namespace {

using json = nlohmann::json;

std::string case_dir(const std::string& name) { return std::string(SULCUS_BINARY_DIR) + "/cases/" + name; }

Vec3 vec(const json& j) { return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }

void check_case(const std::string& name) {
    const std::string dir = case_dir(name);
    const SceneLoad scene = load_scene(dir + "/scene.json");
    ASSERT_TRUE(scene.ok()) << scene.errors.front();
    std::string text, why;
    json manifest;
    ASSERT_TRUE(textio::read_file(dir + "/case.json", text, why)) << why;
    ASSERT_TRUE(textio::parse_json(dir + "/case.json", text, manifest, why)) << why;
    ASSERT_EQ(manifest.value("format", ""), "sulcus.case/1");

    // Every charted site has a frame and a pass.
    const ChartLoad chart = load_chart(std::string(SULCUS_SOURCE_DIR) + "/content/assets/cases/" + name + "/chart.json");
    ASSERT_TRUE(chart.ok());
    size_t charted = 0;
    for (const auto& [fdi, t] : chart.chart.teeth)
        for (const auto& s : t.sites) charted += s.has_value();
    ASSERT_EQ(manifest["sites"].size(), charted);
    ASSERT_EQ(manifest["passes"].size(), charted);

    std::vector<PassToCheck> passes;
    int inflamed = 0;
    for (const json& p : manifest["passes"]) {
        PassToCheck c{};
        c.fdi = p["fdi"].get<int>();
        ASSERT_TRUE(parse_site(p["site"].get<std::string>(), &c.site));
        c.t_start = p["t_start"].get<double>();
        c.t_end = p["t_end"].get<double>();
        bool found = false;
        for (const json& s : manifest["sites"])
            if (s["fdi"].get<int>() == c.fdi && s["site"].get<std::string>() == p["site"].get<std::string>()) {
                c.floor_point = vec(s["floor_point"]);
                c.axis = vec(s["axis"]);
                c.extra_firm_m = s["extra_depth_at_0_5_N_mm"].get<double>() * 1e-3;
                if (s["tissue"] == "inflamed") ++inflamed;
                // The site frame agrees with the chart: the floor is pd below the margin.
                const double pd = chart.chart.teeth.at(c.fdi).sites[size_t(c.site)]->pd_mm * 1e-3;
                EXPECT_NEAR(glm::dot(vec(s["margin_point"]) - c.floor_point, c.axis), pd, 1e-9);
                found = true;
            }
        ASSERT_TRUE(found);
        passes.push_back(c);
    }
    const ModelBuild mb = build_model(scene.scene, RendererSettings{});
    ASSERT_TRUE(mb.model) << mb.error;
    // The case uses what it declares: a probe of several pieces, compliant gingiva, friction.
    EXPECT_GE(mb.model->tool.pieces.size(), 3u);
    EXPECT_TRUE(mb.model->any_compliant);
    EXPECT_TRUE(mb.model->any_friction);
    const ProbingFigures fig =
        expect_probe_stops_at_floor(*mb.model, scene.scene.trajectory, passes, scene.scene.rate_hz, 0.2e-3, 0.1e-3);
    EXPECT_EQ(fig.firm_checked, int(passes.size()));
    std::printf("%s: %d inflamed sites of %zu\n", name.c_str(), inflamed, passes.size());
}

// Both tissues occur in the bundled cases, so both settings are exercised above.
TEST(BundledCases, InflamedAndHealthySitesAreBundled) {
    int inflamed = 0, healthy = 0;
    for (const char* name : {"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        std::string text, why;
        json manifest;
        ASSERT_TRUE(textio::read_file(case_dir(name) + "/case.json", text, why)) << why;
        ASSERT_TRUE(textio::parse_json(name, text, manifest, why)) << why;
        for (const json& s : manifest["sites"]) {
            inflamed += s["tissue"] == "inflamed";
            healthy += s["tissue"] == "healthy";
        }
    }
    EXPECT_GE(inflamed, 3);
    EXPECT_GE(healthy, 3);
}

TEST(BundledCases, Healthy11ProbesToTheChartedDepth) { check_case("healthy_11"); }
TEST(BundledCases, Periodontitis36ProbesToTheChartedDepth) { check_case("periodontitis_36"); }
TEST(BundledCases, Quadrant44To47ProbesToTheChartedDepth) { check_case("quadrant_44_47"); }

TEST(BundledCases, CaseFileRoundTripsThroughGltf) {
    // The visual file carries the chart and a node per tooth with its FDI number.
    const AssetLoad a = read_glb(case_dir("periodontitis_36") + "/case.glb");
    ASSERT_TRUE(a.ok()) << a.error;
    EXPECT_EQ(a.asset.extras.value("format", ""), "sulcus.case/1");
    const ChartLoad c = parse_chart(a.asset.extras["chart"], "case.glb extras");
    ASSERT_TRUE(c.ok());
    EXPECT_EQ(c.chart.teeth.count(36), 1u);
    bool tooth = false, gum = false, probe = false;
    for (const AssetNode& n : a.asset.nodes) {
        tooth |= n.name == "tooth 36" && n.extras.value("fdi", 0) == 36 && n.extras["sites"].size() == 6;
        gum |= n.name == "gingiva lower";
        probe |= n.name.rfind("probe", 0) == 0;
    }
    EXPECT_TRUE(tooth && gum && probe);
}

}  // namespace
}  // namespace sulcus
