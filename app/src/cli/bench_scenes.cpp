#include "cli/bench_scenes.h"

#include "sulcus/content/case_manifest.h"
#include "sulcus/content/paper_scenes.h"
#include "sulcus/content/probes.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace sulcus::cli {

namespace fs = std::filesystem;

namespace {

constexpr const char* kQuadrant = "quadrant_44_47";
constexpr const char* kTwoRegions = "quadrant_two_regions";
constexpr const char* kDenseWedge = "dense_wedge_250k";

size_t count_triangles(const SceneFile& s) {
    size_t n = 0;
    for (const SceneObject& o : s.objects) n += o.mesh.triangles.size();
    return n;
}

// 0 to 1 over u in [0, 1], flat at both ends: every scripted motion eases in and out.
double smooth(double u) {
    u = std::clamp(u, 0.0, 1.0);
    return u * u * (3.0 - 2.0 * u);
}

// The tick poses of the two-region session at site 46 B: the probe goes down the pocket as the
// case's own pass does, presses into the floor, leans against the root (its side on the root, its
// tip on the floor: two contact regions), walks along the sulcus in strokes while leaning, backs
// off and comes out. Everything is a function of the tick index.
std::vector<Pose> two_region_ticks(const SceneFile& scene, const CaseManifest& m, std::string* error) {
    const SiteFrame* site = nullptr;
    const ProbingPass* pass = nullptr;
    for (const SiteFrame& s : m.sites)
        if (s.fdi == 46 && s.site == Site::B) site = &s;
    for (const ProbingPass& p : m.passes)
        if (p.fdi == 46 && p.site == Site::B) pass = &p;
    if (!site || !pass) {
        *error = m.dir + "/case.json: the case has no site 46 B";
        return {};
    }
    size_t cursor = 0;
    const Pose above = sample_trajectory(scene.trajectory, pass->t_start, cursor);
    cursor = 0;
    const Pose floor = sample_trajectory(scene.trajectory, pass->t_floor, cursor);
    const Vec3 tangent = glm::normalize(glm::cross(site->axis, site->outward));
    const double rate = scene.rate_hz;
    // Phases (s) and their extents (m, rad).
    const double t_descend = 0.5, t_press = 0.3, t_lean = 0.5, t_walk = 3.0, t_back = 0.3, t_rise = 0.5;
    const double press_m = 0.1e-3, lean_m = 0.1e-3, lean_rad = 0.0, stroke_m = 0.6e-3;
    const double total = t_descend + t_press + t_lean + t_walk + t_back + t_rise;
    const long n = long(std::floor(total * rate)) + 1;
    std::vector<Pose> ticks;
    ticks.reserve(size_t(n));
    const Vec3 pressed = floor.position - press_m * site->axis;
    for (long i = 0; i < n; ++i) {
        double t = double(i) / rate;
        Vec3 tip = pressed;
        double lean = 0.0, walk = 0.0;
        if (t < t_descend) {
            tip = glm::mix(above.position, floor.position, smooth(t / t_descend));
        } else if ((t -= t_descend) < t_press) {
            tip = glm::mix(floor.position, pressed, smooth(t / t_press));
        } else if ((t -= t_press) < t_lean) {
            lean = smooth(t / t_lean);
        } else if ((t -= t_lean) < t_walk) {
            lean = 1.0;
            // Two strokes each way, starting and ending at the site.
            walk = stroke_m * std::sin(2.0 * M_PI * 2.0 * t / t_walk);
        } else if ((t -= t_walk) < t_back) {
            lean = 1.0 - smooth(t / t_back);
        } else {
            t -= t_back;
            tip = glm::mix(pressed, above.position, smooth(t / t_rise));
        }
        // Leaning: toward the tooth (-outward), the shank tilted the same way about the tip
        // (about -tangent the long axis turns toward -outward).
        const Quat q = glm::angleAxis(lean * lean_rad, -tangent) * floor.orientation;
        ticks.push_back(Pose{tip - lean * lean_m * site->outward + walk * tangent, glm::normalize(q)});
    }
    return ticks;
}

// A closed ellipsoid of latitude/longitude bands (2 * lon * (lat - 1) triangles), its radius
// rippled a little (a crown's surface is not a quadric, and the ripples keep the mesh free of
// the symmetries a perfect ellipsoid has), outward faces counter-clockwise.
TriMesh rippled_ellipsoid(const Vec3& centre, const Vec3& radii, int lat, int lon) {
    TriMesh m;
    auto point = [&](double theta, double phi) {
        const double ripple = 1.0 + 0.015 * std::sin(7.0 * theta) * std::sin(5.0 * phi);
        const Vec3 u(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
        return centre + ripple * radii * u;
    };
    m.vertices.push_back(centre + Vec3(0.0, radii.y, 0.0));
    for (int i = 1; i < lat; ++i)
        for (int j = 0; j < lon; ++j) m.vertices.push_back(point(M_PI * i / lat, 2.0 * M_PI * j / lon));
    m.vertices.push_back(centre - Vec3(0.0, radii.y, 0.0));
    const uint32_t south = uint32_t(m.vertices.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * lon + (j % lon)); };
    for (int j = 0; j < lon; ++j) m.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
    for (int i = 1; i < lat - 1; ++i)
        for (int j = 0; j < lon; ++j) {
            m.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)});
            m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)});
        }
    for (int j = 0; j < lon; ++j) m.triangles.push_back({south, ring(lat - 1, j), ring(lat - 1, j + 1)});
    return m;
}

// Two dense crown-like ellipsoids (about 125k triangles each) with a 0.3 mm gap at their
// equators, and the Williams probe's collision tip going down between them: it wedges in the gap
// touching both (two contact regions), is pressed 0.4 mm further (about 0.4 N), strokes along the gap, rocks
// side to side, and comes out. Rigid, frictionless; everything is a function of the tick index.
BenchScene dense_wedge_scene() {
    BenchScene b;
    b.name = kDenseWedge;
    SceneFile& s = b.scene;
    s.name = kDenseWedge;
    s.path = "(built in: dense_wedge_250k)";
    const double mm = 1e-3;
    const Vec3 radii(4.0 * mm, 5.0 * mm, 4.5 * mm);
    const double gap = 0.3 * mm;
    for (int side = -1; side <= 1; side += 2) {
        SceneObject o;
        o.name = side < 0 ? "crown_left" : "crown_right";
        o.mesh = rippled_ellipsoid(Vec3(side * (radii.x + 0.5 * gap), 0.0, 0.0), radii, 250, 250);
        s.objects.push_back(std::move(o));
    }
    s.tool.name = "williams_tip";
    s.tool.mesh = make_probe_tip_collision(ProbeKind::Williams);
    s.rate_hz = 1000.0;
    b.triangles = count_triangles(s);
    const double t_descend = 0.6, t_press = 0.3, t_stroke = 2.0, t_rock = 1.0, t_rise = 0.5;
    const double total = t_descend + t_press + t_stroke + t_rock + t_rise;
    const long n = long(std::floor(total * s.rate_hz)) + 1;
    // The tip starts above the crowns and goes down the gap to where it is a little narrower
    // than the probe, then 0.3 mm further.
    const Vec3 top(0.0, 6.5 * mm, 0.0), wedged(0.0, 1.0 * mm, 0.0), pressed = wedged - Vec3(0.0, 0.6 * mm, 0.0);
    b.ticks.reserve(size_t(n));
    for (long i = 0; i < n; ++i) {
        double t = double(i) / s.rate_hz;
        Vec3 p = pressed;
        double rock = 0.0;
        if (t < t_descend) {
            p = glm::mix(top, wedged, smooth(t / t_descend));
        } else if ((t -= t_descend) < t_press) {
            p = glm::mix(wedged, pressed, smooth(t / t_press));
        } else if ((t -= t_press) < t_stroke) {
            p = pressed + Vec3(0.0, 0.0, 1.0 * mm * std::sin(2.0 * M_PI * t / t_stroke));
        } else if ((t -= t_stroke) < t_rock) {
            rock = 6.0 * M_PI / 180.0 * std::sin(2.0 * M_PI * t / t_rock);
        } else {
            t -= t_rock;
            p = glm::mix(pressed, top, smooth(t / t_rise));
        }
        b.ticks.push_back(Pose{p, glm::angleAxis(rock, Vec3(0.0, 0.0, 1.0))});
    }
    return b;
}

}  // namespace

std::vector<Pose> trajectory_ticks(const SceneFile& scene) {
    std::vector<Pose> ticks;
    if (scene.trajectory.size() < 2) return ticks;
    const double t0 = scene.trajectory.front().t, t1 = scene.trajectory.back().t;
    const long n = long(std::floor((t1 - t0) * scene.rate_hz + 1e-9)) + 1;
    ticks.reserve(size_t(n));
    size_t cursor = 0;
    for (long i = 0; i < n; ++i)
        ticks.push_back(sample_trajectory(scene.trajectory, t0 + double(i) / scene.rate_hz, cursor));
    return ticks;
}

std::string scene_file_name(std::string name) {
    for (char& c : name)
        if (c == '/' || c == '\\' || c == ' ') c = '_';
    return name;
}

std::vector<std::string> bench_scene_names() {
    std::vector<std::string> names;
    for (const std::string& n : paper_scene_names()) names.push_back("paper/" + n);
    names.push_back(kQuadrant);
    names.push_back(kTwoRegions);
    names.push_back(kDenseWedge);
    return names;
}

BenchScenes load_bench_scenes(const std::vector<std::string>& names_in, const std::string& content_root,
                              const std::string& cases_dir) {
    BenchScenes out;
    const std::vector<std::string> all = bench_scene_names();
    const std::vector<std::string> names = names_in.empty() ? all : names_in;
    for (const std::string& name : names) {
        if (std::find(all.begin(), all.end(), name) == all.end()) {
            out.error = "bench: unknown scene '" + name + "' (the scenes: 'sulcus-cli bench --list')";
            return out;
        }
        if (name == kDenseWedge) {
            out.scenes.push_back(dense_wedge_scene());
            continue;
        }
        const bool quadrant = name == kQuadrant || name == kTwoRegions;
        const std::string path = quadrant ? (fs::path(cases_dir) / kQuadrant / "scene.json").string()
                                          : (fs::path(content_root) / "scenes" / (name + ".json")).string();
        SceneLoad load = load_scene(path);
        if (!load.ok()) {
            out.error = load.errors.front();
            return out;
        }
        BenchScene b;
        b.name = name;
        b.scene = std::move(load.scene);
        b.triangles = count_triangles(b.scene);
        if (name == kTwoRegions) {
            const CaseManifestLoad m = load_case_manifest((fs::path(cases_dir) / kQuadrant).string());
            if (!m.ok()) {
                out.error = m.errors.front();
                return out;
            }
            b.ticks = two_region_ticks(b.scene, m.manifest, &out.error);
            if (!out.error.empty()) return out;
        } else {
            b.ticks = trajectory_ticks(b.scene);
        }
        out.scenes.push_back(std::move(b));
    }
    return out;
}

}  // namespace sulcus::cli
