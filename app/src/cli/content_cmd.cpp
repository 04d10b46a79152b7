// `sulcus-cli content ...`: cases from charts, single teeth and probes as glTF, file checks and
// mesh import.
#include "cli/commands.h"

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/content/gltf_io.h"
#include "sulcus/content/mesh_import.h"
#include "sulcus/content/probes.h"
#include "sulcus/content/tooth.h"
#include "sulcus/content/tooth_asset.h"
#include "sulcus/engine/json_text.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/scene_file.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace sulcus::cli {

const char* const kHelpContent =
    "usage: sulcus-cli content SUBCOMMAND [ARGS]\n"
    "\n"
    "  case CHART.json --out DIR [--probe KIND]\n"
    "        builds the patient case of a periodontal chart (sulcus.chart/1): the charted teeth on\n"
    "        the arch, gingiva and bone shaped from the chart, and writes DIR/scene.json (runnable\n"
    "        by 'sulcus-cli run'), one .glb per tooth and gingiva, case.glb (everything, with the\n"
    "        chart and site frames as metadata), probing.csv (the probe inserted at every site),\n"
    "        case.json (sites, their floor tissue and probing passes) and chart.json. Each site's\n"
    "        floor yields as its tissue says (docs/tissue.md: 'tissue' in the chart, else inflamed\n"
    "        where it bleeds, healthy where not). KIND: williams (default), unc15, cpi, marquis, nabers.\n"
    "  tooth FDI --out FILE.glb [--collision]\n"
    "        writes one procedural tooth (11-17, 21-27, 31-37, 41-47) in its tooth frame; the\n"
    "        visual resolution by default, the collision resolution with --collision\n"
    "  probe KIND --out FILE.glb\n"
    "        writes a probe: the visual body with its markings, and its collision tip as a node\n"
    "  check FILE\n"
    "        validates a mesh (OBJ, OFF, STL, PLY, glTF, GLB), a scene (sulcus.scene/1) or a chart\n"
    "        (sulcus.chart/1); prints what it found, or one line per fault\n"
    "  import MESH --unit UNIT --out FILE.glb\n"
    "        reads a mesh a school already has (a scan, an exported model) in UNIT (m, cm, mm, um,\n"
    "        in), scales it to metres and writes it as glTF\n"
    "\n"
    "exit status: 0 done; 1 check found faults; 2 bad input or usage; 3 internal error\n";

namespace {

struct Options {
    std::vector<std::string> positional;
    std::string out, probe = "williams", unit;
    bool collision = false;
};

bool parse_options(const std::string& sub, const std::vector<std::string>& args, Options& o, std::string& why) {
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&](std::string& into) {
            if (i + 1 >= args.size()) {
                why = sub + ": " + a + " needs a value";
                return false;
            }
            into = args[++i];
            return true;
        };
        if (a == "--out") {
            if (!value(o.out)) return false;
        } else if (a == "--probe") {
            if (!value(o.probe)) return false;
        } else if (a == "--unit") {
            if (!value(o.unit)) return false;
        } else if (a == "--collision") {
            o.collision = true;
        } else if (!a.empty() && a[0] == '-') {
            why = sub + ": unknown option '" + a + "'";
            return false;
        } else {
            o.positional.push_back(a);
        }
    }
    return true;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int cmd_case(const Options& o) {
    if (o.positional.size() != 1) return usage("content case: give one chart file");
    if (o.out.empty()) return usage("content case: --out DIR is required");
    ProbeKind kind;
    if (!parse_probe_kind(o.probe, &kind)) return usage("content case: unknown probe '" + o.probe + "'");
    const std::string& path = o.positional[0];
    const ChartLoad load = load_chart(path);
    for (const std::string& w : load.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    std::vector<std::string> errors = load.errors;
    if (load.ok()) check_chart_for_case(load.chart, path, errors);
    if (!errors.empty()) {
        for (const std::string& e : errors) std::fprintf(stderr, "%s\n", e.c_str());
        return kUsage;
    }
    const auto t0 = std::chrono::steady_clock::now();
    CaseSettings settings;
    settings.probe_profile_m = probe_radius_profile(make_probe_tip_collision(kind), settings.probe_profile_step_m);
    // The tip's radius: the profile where it stops growing like a ball (height = radius).
    for (size_t i = 0; i < settings.probe_profile_m.size(); ++i)
        if (double(i) * settings.probe_profile_step_m >= settings.probe_profile_m[i]) {
            settings.probe_radius_m = settings.probe_profile_m[i];
            break;
        }
    PatientCase pc;
    try {
        pc = build_case(load.chart, settings);
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
        return kUsage;
    }
    const std::string why = write_case(pc, kind, o.out);
    if (!why.empty()) {
        std::fprintf(stderr, "%s\n", why.c_str());
        return kUsage;
    }
    size_t tris = 0;
    for (const auto& [name, mesh] : pc.solids) tris += mesh.triangles.size();
    std::printf("case %s: %zu teeth, %zu sites, %zu solids, %zu triangles, %.1f s -> %s/scene.json\n", path.c_str(),
                pc.teeth.size(), pc.sites.size(), pc.solids.size(), tris, seconds_since(t0), o.out.c_str());
    return kOk;
}

int cmd_tooth(const Options& o) {
    if (o.positional.size() != 1) return usage("content tooth: give one FDI tooth number");
    if (o.out.empty()) return usage("content tooth: --out FILE.glb is required");
    int fdi = 0;
    try {
        size_t used = 0;
        fdi = std::stoi(o.positional[0], &used);
        if (used != o.positional[0].size()) fdi = 0;
    } catch (const std::exception&) {
        fdi = 0;
    }
    if (!is_supported_tooth(fdi))
        return usage("content tooth: '" + o.positional[0] + "' is not a supported FDI number (11-17, 21-27, 31-37, 41-47)");
    const ToothShape shape(fdi);
    const TriMesh mesh = make_tooth_mesh(fdi, o.collision ? tooth_collision_settings() : tooth_visual_settings());
    Asset asset;
    asset.materials = case_materials();
    asset.nodes.push_back(make_tooth_node(mesh, shape));
    asset.extras = {{"format", "sulcus.tooth/1"}, {"resolution", o.collision ? "collision" : "visual"}};
    const std::string why = write_glb(asset, o.out);
    if (!why.empty()) {
        std::fprintf(stderr, "%s\n", why.c_str());
        return kUsage;
    }
    std::printf("tooth %d: %zu triangles -> %s\n", fdi, mesh.triangles.size(), o.out.c_str());
    return kOk;
}

int cmd_probe(const Options& o) {
    if (o.positional.size() != 1) return usage("content probe: give one probe kind");
    if (o.out.empty()) return usage("content probe: --out FILE.glb is required");
    ProbeKind kind;
    if (!parse_probe_kind(o.positional[0], &kind))
        return usage("content probe: unknown probe '" + o.positional[0] + "' (williams, unc15, cpi, marquis, nabers)");
    Asset asset;
    asset.nodes.push_back(make_probe_node(kind, asset));
    AssetNode tip;
    tip.name = std::string("probe ") + probe_kind_name(kind) + " collision";
    tip.parts.push_back(MeshPart{make_probe_collision(kind), -1});
    tip.extras = {{"collision", true},
                  {"pieces", make_probe_collision_pieces(kind).size()},
                  {"frame", "probe: tip end at the origin, +Y toward the handle"}};
    asset.nodes.push_back(tip);
    asset.extras = {{"format", "sulcus.probe/1"}, {"probe", probe_kind_name(kind)}};
    const std::string why = write_glb(asset, o.out);
    if (!why.empty()) {
        std::fprintf(stderr, "%s\n", why.c_str());
        return kUsage;
    }
    std::printf("probe %s -> %s\n", probe_kind_name(kind), o.out.c_str());
    return kOk;
}

int cmd_check(const Options& o) {
    if (o.positional.size() != 1) return usage("content check: give one file");
    const std::string& path = o.positional[0];
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".json") {
        std::string text, why;
        nlohmann::json doc;
        if (!textio::read_file(path, text, why)) {
            std::fprintf(stderr, "%s: %s\n", path.c_str(), why.c_str());
            return kUsage;
        }
        if (!textio::parse_json(path, text, doc, why)) {
            std::fprintf(stderr, "%s\n", why.c_str());
            return kFailed;
        }
        const std::string format = doc.is_object() && doc.contains("format") && doc["format"].is_string()
                                       ? doc["format"].get<std::string>()
                                       : "";
        if (format == kChartFormat) {
            const ChartLoad load = parse_chart(doc, path);
            for (const std::string& w : load.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
            std::vector<std::string> notes;
            if (load.ok()) check_chart_for_case(load.chart, path, notes);
            for (const std::string& e : load.errors) std::fprintf(stderr, "%s\n", e.c_str());
            if (!load.ok()) return kFailed;
            for (const std::string& n : notes) std::fprintf(stderr, "note: not a buildable case: %s\n", n.c_str());
            size_t sites = 0;
            for (const auto& [fdi, t] : load.chart.teeth)
                for (const auto& s : t.sites) sites += s.has_value();
            std::printf("%s: chart ok: %zu teeth, %zu sites%s\n", path.c_str(), load.chart.teeth.size(), sites,
                        notes.empty() ? ", buildable as a case" : "");
            return kOk;
        }
        if (format == "sulcus.scene/1") {
            const SceneLoad load = load_scene(path);
            for (const std::string& w : load.scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
            for (const std::string& e : load.errors) std::fprintf(stderr, "%s\n", e.c_str());
            if (!load.ok()) return kFailed;
            std::printf("%s: scene ok: %zu objects, tool %s, %zu trajectory rows\n", path.c_str(),
                        load.scene.objects.size(), load.scene.tool.name.c_str(), load.scene.trajectory.size());
            return kOk;
        }
        std::fprintf(stderr, "%s: /format: %s (expected %s or sulcus.scene/1)\n", path.c_str(),
                     format.empty() ? "missing" : ("unknown format '" + format + "'").c_str(), kChartFormat);
        return kFailed;
    }
    const MeshLoad load = load_mesh(path);
    if (!load.ok()) {
        std::fprintf(stderr, "%s\n", load.error.c_str());
        return kFailed;
    }
    Aabb box{Vec3(1e300), Vec3(-1e300)};
    for (const Vec3& v : load.mesh.vertices) {
        box.lo = glm::min(box.lo, v);
        box.hi = glm::max(box.hi, v);
    }
    const Vec3 size = (box.hi - box.lo) * 1e3;
    std::printf("%s: mesh ok: %zu vertices, %zu triangles, closed and oriented, volume %.6g mm^3, size %.4g x %.4g x "
                "%.4g mm\n",
                path.c_str(), load.mesh.vertices.size(), load.mesh.triangles.size(), mesh_volume(load.mesh) * 1e9,
                size.x, size.y, size.z);
    return kOk;
}

int cmd_import(const Options& o) {
    if (o.positional.size() != 1) return usage("content import: give one mesh file");
    if (o.out.empty()) return usage("content import: --out FILE.glb is required");
    LengthUnit unit;
    if (o.unit.empty()) return usage("content import: --unit is required (m, cm, mm, um, in)");
    if (!parse_length_unit(o.unit, &unit)) return usage("content import: unknown unit '" + o.unit + "' (m, cm, mm, um, in)");
    const ImportResult r = import_mesh(o.positional[0], unit);
    if (!r.ok()) {
        std::fprintf(stderr, "%s\n", r.error.c_str());
        return kUsage;
    }
    if (!r.warning.empty()) std::fprintf(stderr, "warning: %s\n", r.warning.c_str());
    Asset asset;
    AssetNode node;
    node.name = std::filesystem::path(o.positional[0]).stem().string();
    node.parts.push_back(MeshPart{r.mesh, -1});
    node.extras = {{"source", o.positional[0]}, {"unit", o.unit}};
    asset.nodes.push_back(node);
    const std::string why = write_glb(asset, o.out);
    if (!why.empty()) {
        std::fprintf(stderr, "%s\n", why.c_str());
        return kUsage;
    }
    std::printf("imported %s (%s): %zu triangles -> %s\n", o.positional[0].c_str(), o.unit.c_str(),
                r.mesh.triangles.size(), o.out.c_str());
    return kOk;
}

}  // namespace

int cmd_content(const std::vector<std::string>& args) {
    if (args.empty()) return usage("content: give a subcommand (case, tooth, probe, check, import)");
    const std::string sub = args[0];
    Options o;
    std::string why;
    if (!parse_options("content " + sub, std::vector<std::string>(args.begin() + 1, args.end()), o, why))
        return usage(why);
    if (sub == "case") return cmd_case(o);
    if (sub == "tooth") return cmd_tooth(o);
    if (sub == "probe") return cmd_probe(o);
    if (sub == "check") return cmd_check(o);
    if (sub == "import") return cmd_import(o);
    return usage("content: unknown subcommand '" + sub + "'");
}

}  // namespace sulcus::cli
