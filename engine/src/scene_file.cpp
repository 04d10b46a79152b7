// Reader of the scene file `sulcus.scene/1` and its trajectory CSV (DESIGN.md, "Scene").
//
// Every fault becomes one line "file: place: what is wrong" (places in the JSON are JSON
// pointers, places in the CSV are line numbers). The reader goes on after a fault so that one
// run reports all of them; only an unknown `format` stops it, since the rest of a file of
// another format cannot be read meaningfully.
#include "sulcus/engine/scene_file.h"

#include "sulcus/engine/json_text.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace sulcus {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr const char* kFormat = "sulcus.scene/1";
constexpr double kSceneQuatTolerance = 1e-6;       // |q| - 1 allowed in the scene file
constexpr double kTrajectoryQuatTolerance = 1e-3;  // |q| - 1 allowed in a trajectory row
constexpr double kMaxRateHz = 100000.0;
// A broken CSV with a million rows must not print a million lines.
constexpr size_t kMaxTrajectoryErrors = 50;

using textio::num;
using textio::one_line;
using textio::pointer_token;
using textio::shown;

using textio::Reporter;

// Mesh and trajectory paths are relative to the scene file's folder.
std::string resolve(const std::string& scene_path, const std::string& relative) {
    const fs::path rel(relative);
    if (rel.is_absolute()) return rel.lexically_normal().string();
    const fs::path dir = fs::path(scene_path).parent_path();
    return (dir / rel).lexically_normal().string();
}

void warn_unknown_keys(const Reporter& r, const json& obj, const std::string& place,
                       std::initializer_list<const char*> known) {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
        const bool ok = std::any_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; });
        if (!ok) r.warning(place + "/" + pointer_token(it.key()), "unknown key (ignored)");
    }
}

bool finite_number(const json& v, double& out) {
    if (!v.is_number()) return false;
    out = v.get<double>();
    return std::isfinite(out);
}

// A JSON array of exactly n finite numbers.
bool read_numbers(const Reporter& r, const json& v, const std::string& place, size_t n, double* out) {
    if (!v.is_array() || v.size() != n) {
        r.error(place, "expected an array of " + std::to_string(n) + " numbers");
        return false;
    }
    bool ok = true;
    for (size_t i = 0; i < n; ++i) {
        if (!finite_number(v[i], out[i])) {
            r.error(place + "/" + std::to_string(i), "expected a finite number, found " + shown(v[i].dump()));
            ok = false;
        }
    }
    return ok;
}

bool read_string(const Reporter& r, const json& obj, const std::string& place, const char* key,
                 std::string& out) {
    const std::string here = place + "/" + key;
    const auto it = obj.find(key);
    if (it == obj.end()) {
        r.error(here, "missing");
        return false;
    }
    if (!it->is_string() || it->get_ref<const std::string&>().empty()) {
        r.error(here, "expected a non-empty string");
        return false;
    }
    out = it->get<std::string>();
    return true;
}

// Checks that the referenced file exists before handing it to a loader, so that a missing
// file is reported at its place in the scene.
bool check_file(const Reporter& r, const std::string& place, const std::string& resolved) {
    std::error_code ec;
    const fs::file_status st = fs::status(resolved, ec);
    if (ec || !fs::exists(st)) {
        r.error(place, "file not found: " + resolved);
        return false;
    }
    if (fs::is_directory(st)) {
        r.error(place, "is a folder, not a file: " + resolved);
        return false;
    }
    return true;
}

// Limits of the materials section.
constexpr size_t kMaxMaterials = 1024;
constexpr size_t kMaxCurvePoints = 8;
constexpr size_t kMaxRegions = 4096;

int material_index(const std::vector<ContactMaterial>& materials, const std::string& name) {
    for (size_t i = 0; i < materials.size(); ++i)
        if (materials[i].name == name) return int(i);
    return -1;
}

// "materials": {"name": {"kind": "rigid"|"compliant", "stiffness_N_per_m" | "yield_curve_N_mm",
// "friction_static", "friction_kinetic"}}.
void read_materials(const Reporter& r, const json& v, std::vector<ContactMaterial>& out) {
    const std::string place = "/materials";
    if (!v.is_object()) {
        r.error(place, "expected an object mapping material names to materials");
        return;
    }
    if (v.size() > kMaxMaterials) {
        r.error(place, "has " + std::to_string(v.size()) + " materials (at most " + std::to_string(kMaxMaterials) + ")");
        return;
    }
    for (auto it = v.begin(); it != v.end(); ++it) {
        const std::string here = place + "/" + pointer_token(it.key());
        const json& m = *it;
        ContactMaterial mat;
        mat.name = it.key();
        if (!m.is_object()) {
            r.error(here, "expected an object");
            continue;
        }
        warn_unknown_keys(r, m, here, {"kind", "stiffness_N_per_m", "yield_curve_N_mm", "friction_static",
                                       "friction_kinetic"});
        std::string kind;
        if (read_string(r, m, here, "kind", kind)) {
            if (kind == "compliant")
                mat.compliant = true;
            else if (kind != "rigid")
                r.error(here + "/kind", "expected \"rigid\" or \"compliant\", found " + shown(kind));
        }
        const auto stiff = m.find("stiffness_N_per_m");
        const auto curve = m.find("yield_curve_N_mm");
        if (!mat.compliant && (stiff != m.end() || curve != m.end())) {
            r.error(here, "a rigid material takes no stiffness or yield curve");
        } else if (mat.compliant && (stiff == m.end()) == (curve == m.end())) {
            r.error(here, "a compliant material needs exactly one of \"stiffness_N_per_m\" and \"yield_curve_N_mm\"");
        } else if (stiff != m.end()) {
            double k = 0.0;
            if (!finite_number(*stiff, k) || !(k > 0.0))
                r.error(here + "/stiffness_N_per_m", "expected a positive finite number, found " + shown(stiff->dump()));
            else
                mat.yield_curve.push_back({1.0, 1.0 / k});
        } else if (curve != m.end()) {
            const std::string cp = here + "/yield_curve_N_mm";
            if (!curve->is_array() || curve->size() < 2 || curve->size() > kMaxCurvePoints) {
                r.error(cp, "expected 2 to " + std::to_string(kMaxCurvePoints) + " [force N, depth mm] points");
            } else {
                double f0 = 0.0, d0 = 0.0, slope0 = 0.0;
                bool ok = true;
                for (size_t i = 0; i < curve->size() && ok; ++i) {
                    const std::string pp = cp + "/" + std::to_string(i);
                    double fd[2];
                    if (!read_numbers(r, (*curve)[i], pp, 2, fd)) {
                        ok = false;
                        break;
                    }
                    if (i == 0) {
                        if (fd[0] != 0.0 || fd[1] != 0.0) {
                            r.error(pp, "the curve must start at [0, 0]");
                            ok = false;
                        }
                        continue;
                    }
                    if (!(fd[0] > f0) || !(fd[1] > d0)) {
                        r.error(pp, "force and depth must both increase along the curve");
                        ok = false;
                        break;
                    }
                    const double slope = (fd[0] - f0) / (fd[1] - d0);  // N per mm
                    if (slope < slope0 * (1.0 - 1e-12)) {
                        r.error(pp, "the curve softens here (slope " + num(slope) + " N/mm after " + num(slope0) +
                                        " N/mm); it must stiffen or stay linear");
                        ok = false;
                        break;
                    }
                    slope0 = slope;
                    f0 = fd[0];
                    d0 = fd[1];
                    mat.yield_curve.push_back({fd[0], fd[1] * 1e-3});
                }
                if (!ok) mat.yield_curve.clear();
            }
        }
        double mu[2] = {0.0, 0.0};
        bool given[2] = {false, false};
        const char* keys[2] = {"friction_static", "friction_kinetic"};
        for (int k = 0; k < 2; ++k) {
            const auto f = m.find(keys[k]);
            if (f == m.end()) continue;
            if (!finite_number(*f, mu[k]) || mu[k] < 0.0 || mu[k] > 10.0) {
                r.error(here + "/" + keys[k], "expected a number in [0, 10], found " + shown(f->dump()));
                mu[k] = 0.0;
            } else {
                given[k] = true;
            }
        }
        if (given[0] && !given[1]) mu[1] = mu[0];
        if (given[1] && !given[0]) mu[0] = mu[1];
        if (mu[1] > mu[0]) r.error(here + "/friction_kinetic", "exceeds friction_static (" + num(mu[0]) + ")");
        mat.friction_static = mu[0];
        mat.friction_kinetic = std::min(mu[0], mu[1]);
        out.push_back(std::move(mat));
    }
}

// "material" and "regions" of an object.
void read_object_materials(const Reporter& r, const json& v, const std::string& place,
                           const std::vector<ContactMaterial>& materials, SceneObject& out) {
    if (const auto it = v.find("material"); it != v.end()) {
        if (!it->is_string()) {
            r.error(place + "/material", "expected a material name");
        } else if ((out.material = material_index(materials, it->get<std::string>())) < 0) {
            r.error(place + "/material", "unknown material " + shown(it->get<std::string>()) + " (not in /materials)");
        }
    }
    const auto it = v.find("regions");
    if (it == v.end()) return;
    const std::string rp = place + "/regions";
    if (!it->is_array() || it->size() > kMaxRegions) {
        r.error(rp, "expected an array of at most " + std::to_string(kMaxRegions) + " regions");
        return;
    }
    for (size_t i = 0; i < it->size(); ++i) {
        const std::string here = rp + "/" + std::to_string(i);
        const json& g = (*it)[i];
        if (!g.is_object()) {
            r.error(here, "expected an object");
            continue;
        }
        warn_unknown_keys(r, g, here, {"name", "material", "center", "radius", "normal", "min_cos"});
        MaterialRegion reg;
        if (const auto n = g.find("name"); n != g.end() && n->is_string()) reg.name = n->get<std::string>();
        std::string mat;
        bool ok = read_string(r, g, here, "material", mat);
        if (ok && (reg.material = material_index(materials, mat)) < 0) {
            r.error(here + "/material", "unknown material " + shown(mat) + " (not in /materials)");
            ok = false;
        }
        double c[3];
        if (const auto f = g.find("center"); f == g.end()) {
            r.error(here + "/center", "missing");
            ok = false;
        } else if (read_numbers(r, *f, here + "/center", 3, c)) {
            reg.center = Vec3(c[0], c[1], c[2]);
        } else {
            ok = false;
        }
        if (const auto f = g.find("radius"); f == g.end() || !finite_number(*f, reg.radius_m) || !(reg.radius_m > 0.0)) {
            r.error(here + "/radius", "expected a positive radius in metres");
            ok = false;
        }
        if (const auto f = g.find("normal"); f != g.end()) {
            if (read_numbers(r, *f, here + "/normal", 3, c) && glm::length(Vec3(c[0], c[1], c[2])) > 0.0) {
                reg.normal = glm::normalize(Vec3(c[0], c[1], c[2]));
            } else {
                if (f->is_array() && f->size() == 3) r.error(here + "/normal", "must not be zero");
                ok = false;
            }
        }
        if (const auto f = g.find("min_cos"); f != g.end()) {
            if (!finite_number(*f, reg.min_cos) || reg.min_cos < -1.0 || reg.min_cos > 1.0) {
                r.error(here + "/min_cos", "expected a number in [-1, 1]");
                ok = false;
            }
        }
        if (ok) out.regions.push_back(reg);
    }
}

// name + mesh (+ pose for objects); loads the mesh.
void read_body(const Reporter& r, const json& v, const std::string& place, bool has_pose, SceneObject& out) {
    if (!v.is_object()) {
        r.error(place, "expected an object with \"name\" and \"mesh\"");
        return;
    }
    if (has_pose)
        warn_unknown_keys(r, v, place, {"name", "mesh", "position", "orientation", "material", "regions"});
    else
        warn_unknown_keys(r, v, place, {"name", "mesh"});
    read_string(r, v, place, "name", out.name);

    if (has_pose) {
        if (const auto it = v.find("position"); it != v.end()) {
            double p[3];
            if (read_numbers(r, *it, place + "/position", 3, p)) out.pose.position = Vec3(p[0], p[1], p[2]);
        }
        if (const auto it = v.find("orientation"); it != v.end()) {
            double q[4];
            const std::string here = place + "/orientation";
            if (read_numbers(r, *it, here, 4, q)) {
                const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
                if (!(std::abs(len - 1.0) <= kSceneQuatTolerance)) {
                    r.error(here, "quaternion [w, x, y, z] has length " + num(len) + " (must be unit within " +
                                      num(kSceneQuatTolerance) + ")");
                } else {
                    out.pose.orientation = Quat(q[0] / len, q[1] / len, q[2] / len, q[3] / len);
                }
            }
        }
    }

    std::string mesh;
    if (read_string(r, v, place, "mesh", mesh)) {
        out.mesh_path = resolve(r.file, mesh);
        if (check_file(r, place + "/mesh", out.mesh_path)) {
            MeshLoad load = load_mesh(out.mesh_path);
            if (load.ok())
                out.mesh = std::move(load.mesh);
            else
                r.errors->push_back(one_line(load.error));  // already "path: place: what"
        }
    }
}

void read_haptic(const Reporter& r, const json& v, HapticSettings& h) {
    const std::string place = "/haptic";
    if (!v.is_object()) {
        r.error(place, "expected an object");
        return;
    }
    struct Field {
        const char* key;
        double* value;
    };
    const Field fields[] = {
        {"stiffness_N_per_m", &h.stiffness_N_per_m},
        {"rotational_stiffness_Nm_per_rad", &h.rotational_stiffness_Nm_per_rad},
        {"weight_translational", &h.weight_translational},
        {"weight_rotational", &h.weight_rotational},
    };
    for (auto it = v.begin(); it != v.end(); ++it) {
        const std::string here = place + "/" + pointer_token(it.key());
        const Field* f = nullptr;
        for (const Field& candidate : fields)
            if (it.key() == candidate.key) f = &candidate;
        if (!f) {
            r.warning(here, "unknown key (ignored)");
            continue;
        }
        double x = 0.0;
        if (!finite_number(*it, x) || !(x > 0.0))
            r.error(here, "expected a positive finite number, found " + shown(it->dump()));
        else
            *f->value = x;
    }
}

std::vector<std::string> split_fields(const std::string& line) {
    std::vector<std::string> out;
    size_t start = 0;
    while (true) {
        const size_t comma = line.find(',', start);
        out.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return out;
}

std::string trim(const std::string& s) {
    const char* ws = " \t\r\f\v";
    const size_t a = s.find_first_not_of(ws);
    if (a == std::string::npos) return {};
    const size_t b = s.find_last_not_of(ws);
    return s.substr(a, b - a + 1);
}

// A whole field as a finite double (std::from_chars: locale-independent, no partial parses).
bool parse_finite(const std::string& field, double& out) {
    if (field.empty()) return false;
    const char* first = field.data();
    const char* last = first + field.size();
    if (*first == '+') ++first;  // from_chars rejects a leading '+', people write it
    const auto r = std::from_chars(first, last, out);
    return r.ec == std::errc() && r.ptr == last && std::isfinite(out);
}

double qdot(const Quat& a, const Quat& b) { return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z; }

// Spherical linear interpolation along the shorter arc, normalised. The angle comes from
// atan2 of |a-b| and |a+b|, which stays accurate for small angles where acos(dot) does not.
Quat slerp_short(const Quat& a, Quat b, double u) {
    if (qdot(a, b) < 0.0) b = -b;
    const Quat d = a - b;
    const Quat s = a + b;
    const double half = std::atan2(std::sqrt(qdot(d, d)), std::sqrt(qdot(s, s)));  // theta / 2
    const double theta = 2.0 * half;
    Quat q;
    if (theta < 1e-9) {
        q = a * (1.0 - u) + b * u;  // sin(x) ~ x: slerp and lerp agree to rounding here
    } else {
        const double sin_theta = std::sin(theta);
        q = a * (std::sin((1.0 - u) * theta) / sin_theta) + b * (std::sin(u * theta) / sin_theta);
    }
    return glm::normalize(q);
}

}  // namespace

std::vector<TrajectorySample> load_trajectory(const std::string& path, std::vector<std::string>& errors) {
    static const char* const kColumns[8] = {"t", "x", "y", "z", "qw", "qx", "qy", "qz"};
    std::vector<TrajectorySample> rows;
    const size_t errors_before = errors.size();
    size_t suppressed = 0;
    auto fault = [&](size_t line, const std::string& what) {
        if (errors.size() - errors_before < kMaxTrajectoryErrors)
            errors.push_back(one_line(path + ": line " + std::to_string(line) + ": " + what));
        else
            ++suppressed;
    };

    std::string text, why;
    if (!textio::read_file(path, text, why)) {
        errors.push_back(one_line(path + ": " + why));
        return {};
    }
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // UTF-8 byte-order mark

    std::istringstream in(text);
    std::string line;
    size_t line_no = 0;
    bool header_seen = false;
    size_t data_rows = 0;
    bool have_previous = false;
    TrajectorySample previous;
    while (std::getline(in, line)) {
        ++line_no;
        if (trim(line).empty()) continue;  // blank lines (often at the end) carry nothing
        const std::vector<std::string> fields = split_fields(line);

        if (!header_seen) {
            header_seen = true;
            bool ok = fields.size() == 8;
            for (size_t i = 0; ok && i < 8; ++i) ok = trim(fields[i]) == kColumns[i];
            if (!ok) {
                fault(line_no, "header is " + shown(trim(line)) + " (expected t,x,y,z,qw,qx,qy,qz)");
                // Without the right columns the rows cannot be read meaningfully.
                break;
            }
            continue;
        }

        ++data_rows;
        if (fields.size() != 8) {
            fault(line_no, "expected 8 values, found " + std::to_string(fields.size()));
            continue;
        }
        double v[8];
        bool row_ok = true;
        for (size_t i = 0; i < 8; ++i) {
            const std::string f = trim(fields[i]);
            if (!parse_finite(f, v[i])) {
                fault(line_no, std::string("column ") + kColumns[i] + ": not a number (" + shown(f) + ")");
                row_ok = false;
            }
        }
        if (!row_ok) continue;

        TrajectorySample s;
        s.t = v[0];
        s.pose.position = Vec3(v[1], v[2], v[3]);
        if (have_previous && !(s.t > previous.t)) {
            fault(line_no, "time " + num(s.t) + " is not after the previous " + num(previous.t));
            row_ok = false;
        }
        const double len = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
        if (!(std::abs(len - 1.0) <= kTrajectoryQuatTolerance)) {
            fault(line_no, "quaternion (qw,qx,qy,qz) has length " + num(len) + " (must be unit within " +
                               num(kTrajectoryQuatTolerance) + ")");
            row_ok = false;
        }
        if (!row_ok) continue;
        s.pose.orientation = Quat(v[4] / len, v[5] / len, v[6] / len, v[7] / len);
        // q and -q are the same rotation; keep neighbours in the same hemisphere so that
        // interpolation between rows takes the short way.
        if (have_previous && qdot(s.pose.orientation, previous.pose.orientation) < 0.0)
            s.pose.orientation = -s.pose.orientation;
        rows.push_back(s);
        previous = s;
        have_previous = true;
    }

    if (!header_seen) {
        fault(1, "empty file (expected the header t,x,y,z,qw,qx,qy,qz and at least 2 rows)");
    } else if (errors.size() == errors_before && data_rows < 2) {
        errors.push_back(one_line(path + ": line " + std::to_string(line_no) + ": at least 2 rows needed, found " +
                                  std::to_string(data_rows)));
    }
    if (suppressed > 0)
        errors.push_back(one_line(path + ": " + std::to_string(suppressed) + " more faults not shown"));
    if (errors.size() != errors_before) return {};
    return rows;
}

SceneLoad load_scene(const std::string& path) {
    SceneLoad result;
    SceneFile& scene = result.scene;
    scene.path = path;
    scene.name = fs::path(path).stem().string();
    const Reporter r{path, &result.errors, &scene.warnings};

    std::string text, why;
    if (!textio::read_file(path, text, why)) {
        result.errors.push_back(one_line(path + ": " + why));
        return result;
    }

    json doc;
    if (!textio::parse_json(path, text, doc, why)) {
        result.errors.push_back(why);
        return result;
    }

    if (!doc.is_object()) {
        r.error("(top level)", "expected a JSON object");
        return result;
    }

    if (const auto it = doc.find("format"); it == doc.end()) {
        r.error("/format", std::string("missing (expected ") + kFormat + ")");
    } else if (!it->is_string() || it->get_ref<const std::string&>() != kFormat) {
        const std::string found = it->is_string() ? it->get<std::string>() : it->dump();
        r.error("/format", "unknown format " + shown(found) + " (expected " + kFormat + ")");
        return result;
    }
    warn_unknown_keys(r, doc, "", {"format", "objects", "tool", "materials", "haptic", "trajectory", "rate_hz"});
    if (const auto it = doc.find("materials"); it != doc.end()) read_materials(r, *it, scene.materials);

    // Objects: each loaded, names unique.
    if (const auto it = doc.find("objects"); it == doc.end()) {
        r.error("/objects", "missing (expected a non-empty array of objects)");
    } else if (!it->is_array() || it->empty()) {
        r.error("/objects", "expected a non-empty array of objects");
    } else {
        for (size_t i = 0; i < it->size(); ++i) {
            const std::string place = "/objects/" + std::to_string(i);
            SceneObject obj;
            read_body(r, (*it)[i], place, /*has_pose=*/true, obj);
            if ((*it)[i].is_object()) read_object_materials(r, (*it)[i], place, scene.materials, obj);
            for (size_t j = 0; j < scene.objects.size(); ++j) {
                if (!obj.name.empty() && scene.objects[j].name == obj.name)
                    r.error(place + "/name", "duplicate name " + shown(obj.name));
            }
            scene.objects.push_back(std::move(obj));
        }
    }

    if (const auto it = doc.find("tool"); it == doc.end())
        r.error("/tool", "missing (expected an object with \"name\" and \"mesh\")");
    else
        read_body(r, *it, "/tool", /*has_pose=*/false, scene.tool);

    if (const auto it = doc.find("haptic"); it != doc.end()) read_haptic(r, *it, scene.haptic);

    if (const auto it = doc.find("rate_hz"); it != doc.end()) {
        double rate = 0.0;
        if (!finite_number(*it, rate) || !(rate > 0.0) || rate > kMaxRateHz)
            r.error("/rate_hz", "expected a number in (0, " + num(kMaxRateHz) + "], found " + shown(it->dump()));
        else
            scene.rate_hz = rate;
    }

    std::string trajectory;
    if (read_string(r, doc, "", "trajectory", trajectory)) {
        scene.trajectory_path = resolve(path, trajectory);
        if (check_file(r, "/trajectory", scene.trajectory_path))
            scene.trajectory = load_trajectory(scene.trajectory_path, result.errors);
    }
    return result;
}

Pose sample_trajectory(const std::vector<TrajectorySample>& trajectory, double t, size_t& cursor) {
    if (trajectory.empty()) return Pose{};
    const size_t n = trajectory.size();
    // Clamped at both ends; NaN counts as before the start.
    if (!(t > trajectory.front().t)) {
        cursor = 0;
        return trajectory.front().pose;
    }
    if (t >= trajectory.back().t) {
        cursor = n - 1;
        return trajectory.back().pose;
    }
    // Now trajectory[0].t < t < trajectory[n-1].t: find i with t_i <= t < t_{i+1}.
    auto brackets = [&](size_t i) { return i + 1 < n && trajectory[i].t <= t && t < trajectory[i + 1].t; };
    size_t i = cursor;
    if (!brackets(i)) {
        if (brackets(i + 1)) {
            i = i + 1;  // the usual case when sampling forward at a rate above the rows'
        } else {
            const auto after = std::upper_bound(trajectory.begin(), trajectory.end(), t,
                                                [](double v, const TrajectorySample& s) { return v < s.t; });
            i = static_cast<size_t>(after - trajectory.begin()) - 1;
        }
    }
    cursor = i;

    const TrajectorySample& a = trajectory[i];
    const TrajectorySample& b = trajectory[i + 1];
    if (t == a.t) return a.pose;
    const double u = (t - a.t) / (b.t - a.t);
    Pose p;
    p.position = a.pose.position + (b.pose.position - a.pose.position) * u;
    p.orientation = slerp_short(a.pose.orientation, b.pose.orientation, u);
    return p;
}

}  // namespace sulcus
