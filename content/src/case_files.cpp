// Writing a case as files: the scene the runner reads, the meshes as glTF, the trajectory, and the
// manifest with the sites and probing passes (docs/cases.md).
#include "sulcus/content/case.h"
#include "sulcus/content/gltf_io.h"
#include "sulcus/engine/runner.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <system_error>

namespace sulcus {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Shortest text that reads back as the same double.
std::string exact(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

std::string trajectory_csv(const Trajectory& tr) {
    std::string csv = "t,x,y,z,qw,qx,qy,qz\n";
    for (const auto& [t, p] : tr.samples) {
        const double v[8] = {t, p.position.x, p.position.y, p.position.z, p.orientation.w, p.orientation.x,
                             p.orientation.y, p.orientation.z};
        for (int i = 0; i < 8; ++i) csv += exact(v[i]) + (i < 7 ? "," : "\n");
    }
    return csv;
}

std::string obj_text(const TriMesh& m) {
    std::string s = "# probe collision: closed convex pieces (one per connected component), probe frame\n"
                    "# (tip end at the origin, +Y toward the handle), metres\n";
    for (const Vec3& v : m.vertices) s += "v " + exact(v.x) + " " + exact(v.y) + " " + exact(v.z) + "\n";
    for (const auto& t : m.triangles)
        s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
    return s;
}


json curve_json(const YieldCurve& c) {
    json pts = json::array();
    for (const auto& [force, depth] : c.points_N_mm) pts.push_back({force, depth});
    return pts;
}

// The scene's materials (docs/tissue.md): rigid teeth, the gingiva's compliant wall, and one
// yielding floor per distinct tissue curve of the case. `floor_material` receives the material of
// every site, in the order of c.sites.
json scene_materials(const PatientCase& c, std::vector<std::string>& floor_material) {
    json m = {{"tooth", {{"kind", "rigid"}, {"friction_static", kToothFrictionStatic}, {"friction_kinetic", kToothFrictionKinetic}}},
              {"gingiva",
               {{"kind", "compliant"},
                {"stiffness_N_per_m", kGingivaStiffness_N_per_m},
                {"friction_static", kTissueFrictionStatic},
                {"friction_kinetic", kTissueFrictionKinetic}}}};
    std::vector<std::pair<YieldCurve, std::string>> used;
    int customs = 0;
    for (const SiteFrame& f : c.sites) {
        const YieldCurve& curve = f.tissue.curve();
        auto it = std::find_if(used.begin(), used.end(), [&](const auto& u) { return u.first == curve; });
        if (it == used.end()) {
            std::string name;
            for (TissuePreset p : kAllTissuePresets)
                if (tissue_preset_curve(p) == curve) name = std::string("floor_") + tissue_preset_name(p);
            if (name.empty()) name = "floor_custom_" + std::to_string(++customs);
            used.push_back({curve, name});
            m[name] = {{"kind", "compliant"},
                       {"yield_curve_N_mm", curve_json(curve)},
                       {"friction_static", kTissueFrictionStatic},
                       {"friction_kinetic", kTissueFrictionKinetic}};
            it = used.end() - 1;
        }
        floor_material.push_back(it->second);
    }
    return m;
}

}  // namespace

std::string write_case(const PatientCase& c, ProbeKind probe, const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return dir + ": cannot create the folder: " + ec.message();
    std::string error;
    auto put = [&](const std::string& name, const std::string& text) {
        if (!error.empty()) return;
        if (!write_file_atomic((fs::path(dir) / name).string(), text, &error) && error.empty())
            error = (fs::path(dir) / name).string() + ": cannot write";
    };

    std::vector<std::string> floor_material;
    const json materials = scene_materials(c, floor_material);

    // One glTF per solid of the scene (teeth and gingiva); the bone only in case.glb.
    json objects = json::array();
    for (const AssetNode& node : c.asset.nodes) {
        if (node.extras.value("tissue", "") == "bone") continue;
        std::string file = node.name;
        std::replace(file.begin(), file.end(), ' ', '_');
        file += ".glb";
        Asset one;
        one.materials = c.asset.materials;
        one.nodes.push_back(node);
        one.extras = {{"format", "sulcus.case/1"}, {"object", node.name}};
        const std::string why = write_glb(one, (fs::path(dir) / file).string());
        if (!why.empty()) return why;
        std::string name = node.name;
        std::replace(name.begin(), name.end(), ' ', '_');
        json object = {{"name", name}, {"mesh", file}};
        const std::string tissue = node.extras.value("tissue", "");
        if (tissue == "gingiva") {
            object["material"] = "gingiva";
        } else if (tissue == "floor") {
            // The site's yielding layer in its tissue's material.
            std::string material = "gingiva";
            for (size_t i = 0; i < c.sites.size(); ++i)
                if (c.sites[i].fdi == node.extras.value("fdi", 0) && site_name(c.sites[i].site) == node.extras.value("site", ""))
                    material = floor_material[i];
            object["material"] = material;
        } else {
            object["material"] = "tooth";
        }
        objects.push_back(object);
    }

    const TriMesh tool = make_probe_collision(probe);
    const std::string tool_file = std::string("probe_") + probe_kind_name(probe) + ".obj";
    put(tool_file, obj_text(tool));

    const double stiffness_N_per_m = 1000.0;
    const Trajectory tr = probing_trajectory(c, 6e-3, stiffness_N_per_m, kFirmProbeForce_N);
    put("probing.csv", trajectory_csv(tr));

    const json scene = {{"format", "sulcus.scene/1"},
                        {"materials", materials},
                        {"objects", objects},
                        {"tool", {{"name", std::string("probe_") + probe_kind_name(probe)}, {"mesh", tool_file}}},
                        {"haptic",
                         {{"stiffness_N_per_m", stiffness_N_per_m},
                          {"rotational_stiffness_Nm_per_rad", 0.03},
                          {"weight_translational", 1.0},
                          {"weight_rotational", 1e-4}}},
                        {"trajectory", "probing.csv"},
                        {"rate_hz", 1000}};
    put("scene.json", scene.dump(2) + "\n");
    put("chart.json", chart_to_json(c.chart).dump(2) + "\n");

    json passes = json::array();
    for (const ProbingPass& p : tr.passes)
        passes.push_back({{"fdi", p.fdi}, {"site", site_name(p.site)}, {"t_start", p.t_start},
                          {"t_floor", p.t_floor}, {"t_end", p.t_end}, {"past_floor_mm", p.past_floor_m * 1e3}});
    json manifest = {{"format", "sulcus.case/1"},
                     {"chart", "chart.json"},
                     {"scene", "scene.json"},
                     {"visual", "case.glb"},
                     {"probe", probe_kind_name(probe)},
                     {"sites", c.asset.extras.value("sites", json::array())},
                     {"passes", passes}};
    put("case.json", manifest.dump(2) + "\n");
    if (!error.empty()) return error;

    // Everything in one file for viewers: every node, the probe at the trajectory's start.
    Asset all = c.asset;
    const int base = int(all.materials.size());
    Asset probe_asset;
    AssetNode probe_node = make_probe_node(probe, probe_asset);
    for (const Material& m : probe_asset.materials) all.materials.push_back(m);
    for (MeshPart& part : probe_node.parts)
        if (part.material >= 0) part.material += base;
    if (!tr.samples.empty()) probe_node.pose = tr.samples.front().second;
    all.nodes.push_back(probe_node);
    return write_glb(all, (fs::path(dir) / "case.glb").string());
}

}  // namespace sulcus
