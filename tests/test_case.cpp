// Cases from charts: teeth on the arch, gingiva and pockets shaped from the chart, and a probe
// that goes down each site's line stopping at the charted depth.
#include "case_charts.h"
#include "case_geometry.h"
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
using test::site_record;
using test::uniform_chart;

TEST(Arch, QuadrantsOneAndThreeAreMirrored) {
    for (int q = 1; q <= 4; ++q)
        for (int p = 1; p <= 7; ++p) {
            const int fdi = q * 10 + p;
            const ToothPlacement pl = arch_placement(fdi);
            EXPECT_EQ(pl.mirror, q == 1 || q == 3) << fdi;
            // The tooth's occlusal direction points up for the lower jaw, down for the upper.
            const Vec3 occ = pl.to_case_direction(Vec3(0, 1, 0));
            EXPECT_NEAR(occ.y, q <= 2 ? -1.0 : 1.0, 1e-12) << fdi;
            // Buccal points away from the arch's centre, mesial toward the midline.
            const Vec3 buccal = pl.to_case_direction(Vec3(0, 0, 1));
            Vec3 centre(0.0, pl.position.y, -0.03);
            EXPECT_GT(glm::dot(buccal, pl.position - centre), 0.0) << fdi;
            const Vec3 mesial = pl.to_case_direction(Vec3(1, 0, 0));
            EXPECT_LT(std::abs(pl.position.x + 1e-3 * mesial.x), std::abs(pl.position.x) + 1e-9) << fdi;
            // Round trip of points.
            const Vec3 x(1e-3, 2e-3, -3e-3);
            const Vec3 back = pl.to_tooth(pl.to_case(x));
            EXPECT_NEAR(glm::length(back - x), 0.0, 1e-15) << fdi;
        }
}

TEST(Arch, NeighbouringCrownsDoNotOverlap) {
    for (int q = 1; q <= 4; ++q)
        for (int p = 1; p < 7; ++p) {
            const ToothPlacement a = arch_placement(q * 10 + p), b = arch_placement(q * 10 + p + 1);
            const double half = 0.5e-3 * (tooth_dimensions(q * 10 + p).crown_md_mm + tooth_dimensions(q * 10 + p + 1).crown_md_mm);
            const double d = glm::length(a.position - b.position);
            EXPECT_GT(d, half) << q * 10 + p;
            EXPECT_LT(d, half + 1e-3) << q * 10 + p;
        }
}

TEST(SiteInterpolation, ExactAndFlatAtSites) {
    const std::array<double, 6> theta{0.7, 1.57, 2.4, -0.7, -1.57, -2.4};
    const std::array<double, 6> v{1, 2, 3, 4, 5, 6};
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_NEAR(case_detail::site_interpolate(theta, v, theta[i]), v[i], 1e-12);
        const double h = 1e-4;
        const double slope = (case_detail::site_interpolate(theta, v, theta[i] + h) -
                              case_detail::site_interpolate(theta, v, theta[i] - h)) / (2 * h);
        EXPECT_NEAR(slope, 0.0, 1e-3);
    }
    // Between two sites the value stays within theirs.
    for (double t = 0.7; t < 1.57; t += 0.05) {
        const double x = case_detail::site_interpolate(theta, v, t);
        EXPECT_GE(x, 1.0 - 1e-12);
        EXPECT_LE(x, 2.0 + 1e-12);
    }
}

TEST(Case, RejectsIncompleteCharts) {
    Chart c = uniform_chart({11}, 2.0, 0.0);
    c.teeth[11].sites[size_t(Site::DL)].reset();
    EXPECT_THROW(build_case(c, quick_settings()), std::invalid_argument);
    EXPECT_THROW(build_case(uniform_chart({18}, 2.0, 0.0), quick_settings()), std::invalid_argument);
}

TEST(Case, SitesSitOnTheChartedMarginAndFloor) {
    Chart c = uniform_chart({11}, 2.0, 0.0);
    c.teeth[11].sites[size_t(Site::B)] = site_record(3.0, -1.5, true);
    c.teeth[11].sites[size_t(Site::ML)] = site_record(1.0, 1.0, false);
    const PatientCase pc = build_case(c, quick_settings());
    ASSERT_EQ(pc.sites.size(), 6u);
    const ToothShape shape(11);
    for (const SiteFrame& f : pc.sites) {
        const SiteRecord& rec = *c.teeth[11].sites[size_t(f.site)];
        const Vec3 m = pc.teeth[0].to_tooth(f.margin_point), fl = pc.teeth[0].to_tooth(f.floor_point);
        EXPECT_NEAR(m.y, shape.cej_height(f.theta_rad) + rec.gm_mm * 1e-3, 1e-12) << site_name(f.site);
        EXPECT_NEAR(m.y - fl.y, rec.pd_mm * 1e-3, 1e-12) << site_name(f.site);
        EXPECT_NEAR(glm::dot(f.margin_point - f.floor_point, f.axis), rec.pd_mm * 1e-3, 1e-12);
    }
    for (const auto& [name, mesh] : pc.solids) EXPECT_EQ(validate_mesh(mesh), "") << name << " " << mesh.triangles.size();
}

void expect_case_probes_to_floor(const PatientCase& pc, double tolerance) {
    std::vector<SceneObject> objects;
    for (const auto& [name, mesh] : pc.solids) {
        if (name.rfind("bone", 0) == 0) continue;
        SceneObject o;
        o.name = name;
        o.mesh = mesh;
        objects.push_back(o);
    }
    const ModelBuild mb = build_model(make_probe_tip_collision(ProbeKind::Williams), objects, RendererSettings{});
    ASSERT_TRUE(mb.model) << mb.error;
    const Trajectory tr = probing_trajectory(pc);
    std::vector<TrajectorySample> samples;
    for (const auto& [t, p] : tr.samples) samples.push_back({t, p});
    std::vector<PassToCheck> passes;
    for (const ProbingPass& p : tr.passes) {
        const auto site = std::find_if(pc.sites.begin(), pc.sites.end(),
                                       [&](const SiteFrame& s) { return s.fdi == p.fdi && s.site == p.site; });
        PassToCheck c{};
        c.fdi = p.fdi;
        c.site = p.site;
        c.t_start = p.t_start;
        c.t_end = p.t_end;
        c.floor_point = site->floor_point;
        c.axis = site->axis;
        passes.push_back(c);
    }
    expect_probe_stops_at_floor(*mb.model, samples, passes, 1000.0, tolerance);
}

// Charts with recession, enlargement and furcations of every grade on premolar, molar and canine:
// every mesh of the case (teeth, gingiva, bone) is a valid solid.
TEST(Case, ChartsWithRecessionEnlargementAndFurcationsGiveValidMeshes) {
    Chart c = uniform_chart({14, 16, 33}, 4.0, -2.0);
    for (Site s : kAllSites) c.teeth[16].sites[size_t(s)] = site_record(5.0, 2.0, true);
    for (Site s : kAllSites) c.teeth[33].sites[size_t(s)] = site_record(2.0, 1.5, false);
    c.teeth[14].furcation = {{FurcationSide::M, 2}, {FurcationSide::D, 3}};
    c.teeth[16].furcation = {{FurcationSide::B, 3}, {FurcationSide::M, 1}, {FurcationSide::D, 2}};
    CaseSettings s = quick_settings();
    s.bone = true;
    const PatientCase pc = build_case(c, s);
    EXPECT_EQ(pc.teeth.size(), 3u);
    EXPECT_EQ(pc.sites.size(), 18u);
    int gums = 0, bones = 0;
    for (const auto& [name, mesh] : pc.solids) {
        EXPECT_EQ(validate_mesh(mesh), "") << name;
        gums += name.rfind("gingiva", 0) == 0;
        bones += name.rfind("bone", 0) == 0;
    }
    EXPECT_EQ(gums, 2);  // both jaws
    EXPECT_EQ(bones, 2);
}

TEST(CaseFiles, ExportImportGivesTheSameMeshesAndMetadata) {
    Chart c = uniform_chart({45}, 3.0, -0.5);
    const PatientCase pc = build_case(c, quick_settings());
    const std::string dir = (std::filesystem::temp_directory_path() / "sulcus_case_roundtrip").string();
    std::filesystem::remove_all(dir);
    ASSERT_EQ(write_case(pc, ProbeKind::Williams, dir), "");
    const AssetLoad back = read_glb(dir + "/case.glb");
    ASSERT_TRUE(back.ok()) << back.error;
    EXPECT_EQ(back.asset.extras, pc.asset.extras);  // format, chart, site frames
    for (const AssetNode& n : pc.asset.nodes) {
        const auto it = std::find_if(back.asset.nodes.begin(), back.asset.nodes.end(),
                                     [&](const AssetNode& b) { return b.name == n.name; });
        ASSERT_NE(it, back.asset.nodes.end()) << n.name;
        EXPECT_EQ(it->extras, n.extras) << n.name;
        ASSERT_EQ(it->parts.size(), n.parts.size()) << n.name;
        for (size_t k = 0; k < n.parts.size(); ++k) {
            const TriMesh& a = n.parts[k].mesh;
            const TriMesh& b = it->parts[k].mesh;
            EXPECT_EQ(b.triangles, a.triangles) << n.name;
            ASSERT_EQ(b.vertices.size(), a.vertices.size()) << n.name;
            for (size_t v = 0; v < a.vertices.size(); ++v)
                for (int d = 0; d < 3; ++d) ASSERT_EQ(b.vertices[v][d], double(float(a.vertices[v][d]))) << n.name;
            EXPECT_EQ(back.asset.materials[size_t(it->parts[k].material)], pc.asset.materials[size_t(n.parts[k].material)]);
        }
    }
    // The scene the files make loads, and its solids are the case's (to float precision).
    const SceneLoad scene = load_scene(dir + "/scene.json");
    ASSERT_TRUE(scene.ok()) << scene.errors.front();
    // Tooth, gingiva and a yielding floor layer per site; bone is display-only.
    EXPECT_EQ(scene.scene.objects.size(), 2u + pc.sites.size());
    for (const SceneObject& o : scene.scene.objects) {
        const auto it = std::find_if(pc.solids.begin(), pc.solids.end(), [&](const auto& s) { return s.first == o.name; });
        ASSERT_NE(it, pc.solids.end()) << o.name;
        EXPECT_EQ(o.mesh.triangles.size(), it->second.triangles.size()) << o.name;
        EXPECT_NEAR(mesh_volume(o.mesh), mesh_volume(it->second), 1e-6 * mesh_volume(it->second)) << o.name;
    }
    std::filesystem::remove_all(dir);
}


TEST(CaseProbing, HealthyCentralIncisorStopsAtTheFloor) {
    Chart c = uniform_chart({11}, 2.0, 0.5);
    c.teeth[11].sites[size_t(Site::MB)] = site_record(3.0, 0.0, false);
    c.teeth[11].sites[size_t(Site::DL)] = site_record(1.0, 0.0, false);
    expect_case_probes_to_floor(build_case(c, quick_settings()), 0.2e-3);
}

}  // namespace
}  // namespace sulcus
