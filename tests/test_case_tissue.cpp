// The tissue of a case with sites of several tissues (presets, an authored curve, bleeding),
// three teeth side by side: each site's tissue and floor layer, the scene's materials, and the
// probe's other pieces clear of the teeth while the tip is in a pocket. The case is built once
// for all of them (some 30 s), so these tests run in one process (tests/CMakeLists.txt).
#include "case_charts.h"
#include "case_geometry.h"
#include "mesh_checks.h"
#include "probing_check.h"

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/content/gltf_io.h"
#include "sulcus/content/probes.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/exact_check.h"
#include "sulcus/engine/json_text.h"
#include "sulcus/engine/scene_file.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include <cmath>
#include <filesystem>
#include <cstdio>

namespace sulcus {
namespace {

using test::quick_settings;
using test::uniform_chart;
using test::winding_number;

// Depth below `from` along -axis at which the line first meets the mesh (ray cast), or -1.
double first_hit_below(const TriMesh& m, const Vec3& from, const Vec3& axis) {
    const Vec3 d = -axis;
    double best = -1.0;
    for (const auto& t : m.triangles) {
        const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        const Vec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
        const double det = glm::dot(e1, p);
        if (std::abs(det) < 1e-30) continue;
        const Vec3 s = from - a;
        const double u = glm::dot(s, p) / det;
        if (u < 0.0 || u > 1.0) continue;
        const Vec3 q = glm::cross(s, e1);
        const double v = glm::dot(d, q) / det;
        if (v < 0.0 || u + v > 1.0) continue;
        const double dist = glm::dot(e2, q) / det;
        if (dist > 0.0 && (best < 0.0 || dist < best)) best = dist;
    }
    return best;
}

const TriMesh& solid(const PatientCase& pc, const std::string& name) {
    for (const auto& [n, m] : pc.solids)
        if (n == name) return m;
    throw std::runtime_error("no solid " + name);
}

// Tooth 46 with both presets, an authored curve, an authored tissue against bleeding, and the
// 45 and 47 beside it (neighbouring floors for the regions).
Chart mixed_tissue_chart() {
    Chart c = uniform_chart({45, 46, 47}, 4.0, -0.5);
    auto& s46 = c.teeth[46].sites;
    s46[size_t(Site::MB)]->bop = true;                                        // inflamed by bleeding
    s46[size_t(Site::B)]->bop = true;
    s46[size_t(Site::B)]->tissue = Tissue::of(TissuePreset::Healthy);          // authored, wins
    s46[size_t(Site::DB)]->tissue = Tissue::of(TissuePreset::Inflamed);        // authored, no bleeding
    s46[size_t(Site::ML)]->tissue = Tissue::of(YieldCurve{{{0, 0}, {0.25, 0.3}, {0.5, 0.55}, {1.0, 0.8}}});
    s46[size_t(Site::DL)]->pd_mm = 6.0;
    s46[size_t(Site::DL)]->bop = true;
    c.teeth[47].sites[size_t(Site::MB)]->bop = true;
    return c;
}

const PatientCase& mixed_case() {
    static const PatientCase pc = build_case(mixed_tissue_chart(), quick_settings());
    return pc;
}

TEST(CaseTissue, SitesTakeTheirTissueFromTheChartOrFromBleeding) {
    const PatientCase& pc = mixed_case();
    const Chart chart = mixed_tissue_chart();
    int inflamed = 0, healthy = 0, custom = 0;
    for (const SiteFrame& f : pc.sites) {
        const SiteRecord& rec = *chart.teeth.at(f.fdi).sites[size_t(f.site)];
        EXPECT_EQ(f.tissue, site_tissue(rec)) << f.fdi << site_name(f.site);
        inflamed += f.tissue == Tissue::of(TissuePreset::Inflamed);
        healthy += f.tissue == Tissue::of(TissuePreset::Healthy);
        custom += !f.tissue.is_preset;
    }
    auto at = [&](int fdi, Site s) {
        return *std::find_if(pc.sites.begin(), pc.sites.end(), [&](const SiteFrame& f) { return f.fdi == fdi && f.site == s; });
    };
    EXPECT_EQ(at(46, Site::MB).tissue, Tissue::of(TissuePreset::Inflamed));
    EXPECT_EQ(at(46, Site::B).tissue, Tissue::of(TissuePreset::Healthy));
    EXPECT_EQ(at(46, Site::DB).tissue, Tissue::of(TissuePreset::Inflamed));
    EXPECT_EQ(at(46, Site::L).tissue, Tissue::of(TissuePreset::Healthy));
    EXPECT_EQ(inflamed, 4);
    EXPECT_EQ(custom, 1);
    EXPECT_EQ(healthy, 18 - 5);
}

// The floor the probe meets is the top of the site's yielding layer, depth_at(0.25 N) above the
// charted floor on the probe's line, measured on the meshes; the gingiva's own floor lies the
// layer's depth below it; the site frame keeps the charted floor.
TEST(CaseTissue, FloorOnsetOnTheLayerIsTheTissuesDepthAboveTheChartedFloor) {
    const PatientCase& pc = mixed_case();
    const TriMesh& gum = solid(pc, "gingiva_lower");
    double worst = 0;
    for (const SiteFrame& f : pc.sites) {
        const double d25 = f.tissue.curve().depth_m_at(0.25);
        EXPECT_NEAR(glm::dot(f.margin_point - f.floor_point, f.axis), f.pd_m, 1e-12);
        EXPECT_NEAR(glm::dot(f.onset_point - f.floor_point, f.axis), d25, 1e-12) << f.fdi << site_name(f.site);
        EXPECT_NEAR(f.rest_depth_m, f.pd_m, 1e-12);
        // From just below the margin (inside the pocket) down the probe's line to the floor.
        const Vec3 from = f.margin_point - f.axis * 0.1e-3;
        const TriMesh& layer = solid(pc, "floor_" + std::to_string(f.fdi) + "_" + site_name(f.site));
        const double hit = first_hit_below(layer, from, f.axis);
        ASSERT_GT(hit, 0.0) << f.fdi << site_name(f.site);
        const double gum_hit = first_hit_below(gum, from, f.axis);
        EXPECT_GT(gum_hit, hit + kFloorLayerDepth - 0.03e-3) << f.fdi << site_name(f.site);
        const double onset_depth = 0.1e-3 + hit;
        const double err = onset_depth - (f.pd_m - d25);
        worst = std::max(worst, std::abs(err));
        EXPECT_NEAR(err, 0.0, 0.03e-3) << f.fdi << " " << site_name(f.site) << " " << f.tissue.label() << ": floor at "
                                       << onset_depth * 1e3 << " mm, expected " << (f.pd_m - d25) * 1e3;
    }
    std::printf("floor onset on the mesh within %.1f um of pd - depth_at(0.25 N)\n", worst * 1e6);
}

TEST(CaseTissue, TrajectoryPushesUntilTheForceWouldReachHalfANewton) {
    const PatientCase& pc = mixed_case();
    const Trajectory tr = probing_trajectory(pc);
    ASSERT_EQ(tr.passes.size(), pc.sites.size());
    for (const ProbingPass& p : tr.passes) {
        const SiteFrame& f = *std::find_if(pc.sites.begin(), pc.sites.end(),
                                           [&](const SiteFrame& s) { return s.fdi == p.fdi && s.site == p.site; });
        const YieldCurve& c = f.tissue.curve();
        const double expected = 0.5 / 1000.0 + (c.depth_m_at(0.5) - c.depth_m_at(0.25)) + 0.1e-3;
        EXPECT_NEAR(p.past_floor_m, expected, 1e-12);
        // The deepest haptic tip of the pass, below the charted floor along the axis.
        double deepest = -1e9;
        for (const auto& [t, pose] : tr.samples)
            if (t >= p.t_start && t <= p.t_end) deepest = std::max(deepest, glm::dot(f.floor_point - pose.position, f.axis));
        EXPECT_NEAR(deepest, expected, 1e-9) << p.fdi << site_name(p.site);
    }
}


TEST(CaseFiles, SceneDeclaresMaterialsAndAFloorLayerPerSite) {
    const PatientCase& pc = mixed_case();
    const std::string dir = (std::filesystem::temp_directory_path() / "sulcus_case_materials").string();
    std::filesystem::remove_all(dir);
    ASSERT_EQ(write_case(pc, ProbeKind::Williams, dir), "");
    std::string text, why;
    nlohmann::json scene;
    ASSERT_TRUE(textio::read_file(dir + "/scene.json", text, why)) << why;
    ASSERT_TRUE(textio::parse_json(dir + "/scene.json", text, scene, why)) << why;

    // Materials: rigid teeth and compliant gingiva with friction, one floor per distinct curve.
    const nlohmann::json& mats = scene["materials"];
    EXPECT_EQ(mats["tooth"]["kind"], "rigid");
    EXPECT_EQ(mats["gingiva"]["kind"], "compliant");
    EXPECT_EQ(mats["gingiva"]["stiffness_N_per_m"].get<double>(), 400.0);
    for (const auto& [name, m] : mats.items()) {
        EXPECT_GT(m["friction_static"].get<double>(), 0.0) << name;
        EXPECT_LE(m["friction_kinetic"].get<double>(), m["friction_static"].get<double>()) << name;
    }
    EXPECT_EQ(mats.size(), 5u);  // tooth, gingiva, floor_healthy, floor_inflamed, floor_custom_1
    for (TissuePreset p : kAllTissuePresets) {
        const nlohmann::json& m = mats[std::string("floor_") + tissue_preset_name(p)];
        EXPECT_EQ(m["kind"], "compliant");
        YieldCurve c;
        for (const auto& pt : m["yield_curve_N_mm"]) c.points_N_mm.push_back({pt[0].get<double>(), pt[1].get<double>()});
        EXPECT_EQ(c, tissue_preset_curve(p));
    }
    EXPECT_EQ(mats["floor_custom_1"]["yield_curve_N_mm"][1][1].get<double>(), 0.3);

    // Objects: teeth, one gingiva and a floor layer per site (bone is display only), each with its
    // material.
    ASSERT_EQ(scene["objects"].size(), 4u + pc.sites.size());
    const nlohmann::json* gum_object = nullptr;
    for (const auto& o : scene["objects"]) {
        const std::string name = o["name"];
        EXPECT_EQ(name.rfind("bone", 0), std::string::npos);
        if (name.rfind("tooth_", 0) == 0) {
            EXPECT_EQ(o["material"], "tooth");
        }
        if (name == "gingiva_lower") gum_object = &o;
    }
    ASSERT_NE(gum_object, nullptr);
    EXPECT_EQ((*gum_object)["material"], "gingiva");
    EXPECT_EQ(scene["tool"]["mesh"], "probe_williams.obj");

    // A layer per site in its tissue's material: a flat top at the onset under the whole tip.
    const TriMesh& gum = solid(pc, "gingiva_lower");
    for (const SiteFrame& f : pc.sites) {
        const std::string label = std::to_string(f.fdi) + "_" + site_name(f.site);
        const nlohmann::json* layer_object = nullptr;
        for (const auto& o : scene["objects"])
            if (o["name"] == "floor_" + label) layer_object = &o;
        ASSERT_NE(layer_object, nullptr) << label;
        const std::string expected_material = f.tissue.is_preset ? std::string("floor_") + f.tissue.label() : "floor_custom_1";
        EXPECT_EQ((*layer_object)["material"], expected_material) << label;
        const TriMesh& layer = solid(pc, "floor_" + label);
        EXPECT_EQ(validate_mesh(layer), "") << label;
        EXPECT_GT(mesh_volume(layer), 0.0) << label;
        EXPECT_GE(f.floor_half_width_m, 0.3e-3) << label;
        // Nothing of the layer above the onset.
        for (const Vec3& v : layer.vertices) EXPECT_LE(glm::dot(v - f.onset_point, f.axis), 1e-12) << label;
        // The tip's footprint lands on the flat top, and the gingiva is far below it there.
        const Vec3 side = glm::normalize(glm::cross(f.axis, f.outward));
        for (int k = 0; k < 8; ++k) {
            const double a = k * 3.14159265358979 / 4.0;
            const Vec3 from = f.margin_point - f.axis * 0.1e-3 + 0.25e-3 * (std::cos(a) * f.outward + std::sin(a) * side);
            const double hit = first_hit_below(layer, from, f.axis);
            ASSERT_GT(hit, 0.0) << label;
            EXPECT_NEAR(glm::dot(from - f.axis * hit - f.onset_point, f.axis), 0.0, 1e-9) << label << " footprint " << k;
            const double gum_hit = first_hit_below(gum, from, f.axis);
            EXPECT_TRUE(gum_hit < 0.0 || gum_hit > hit + 1.0e-3) << label << " footprint " << k;
        }
        // Layers of two sites never meet: the next site's onset is outside this layer.
        for (const SiteFrame& o : pc.sites) {
            if (&o != &f) {
                EXPECT_LT(winding_number(layer, o.onset_point - o.axis * 0.1e-3), 0.5) << label;
            }
        }
    }
    std::filesystem::remove_all(dir);
}

// The probe's other pieces (rest of the working end, shank, handle) never enter a tooth while
// the tip is in a pocket, down to the deepest haptic pose of every pass (exact_check per piece:
// it takes one convex tool).
TEST(CaseProbing, ShankAndHandleClearTheTeethWhileTheTipIsInAPocket) {
    const PatientCase& pc = mixed_case();
    const Trajectory tr = probing_trajectory(pc);
    std::vector<TrajectorySample> samples;
    for (const auto& [t, p] : tr.samples) samples.push_back({t, p});
    std::vector<PlacedMesh> teeth;
    for (const auto& [name, mesh] : pc.solids)
        if (name.rfind("tooth_", 0) == 0) teeth.push_back({&mesh, Pose{}});
    for (ProbeKind kind : {ProbeKind::Williams, ProbeKind::Unc15}) {
        const std::vector<TriMesh> pieces = make_probe_collision_pieces(kind);
        double least_gap = 1.0;
        size_t cursor = 0, poses = 0;
        for (const ProbingPass& p : tr.passes) {
            const SiteFrame& f = *std::find_if(pc.sites.begin(), pc.sites.end(),
                                               [&](const SiteFrame& s) { return s.fdi == p.fdi && s.site == p.site; });
            for (double t = p.t_start; t <= p.t_end; t += 0.01) {
                const Pose pose = sample_trajectory(samples, t, cursor);
                const double depth = glm::dot(f.margin_point - pose.position, f.axis);
                if (depth <= 0.0) continue;
                ++poses;
                for (size_t k = 1; k < pieces.size(); ++k) {
                    const ExactCheck e = exact_check(pieces[k], pose, teeth, 1e-3);
                    EXPECT_EQ(e.penetration_m, 0.0) << probe_kind_name(kind) << " piece " << k << " enters a tooth at "
                                                    << p.fdi << " " << site_name(p.site) << ", tip " << depth * 1e3 << " mm deep";
                    least_gap = std::min(least_gap, e.distance_m);
                }
            }
        }
        EXPECT_GT(poses, 1000u);
        std::printf("%s: %zu poses with the tip in a pocket, least gap shank/handle to a tooth %.3f mm\n",
                    probe_kind_name(kind), poses, least_gap * 1e3);
    }
}

}  // namespace
}  // namespace sulcus
