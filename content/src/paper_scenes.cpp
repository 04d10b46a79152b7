#include "sulcus/content/paper_scenes.h"

#include "sulcus/content/primitives.h"
#include "sulcus/engine/scene_file.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <stdexcept>
#include <system_error>

namespace sulcus {
namespace {

constexpr double kMm = 1e-3;
constexpr double kDeg = std::numbers::pi / 180.0;
// Distances below this count as touching, not overlap (metres).
constexpr double kTouchTolerance_m = 1e-9;

// Shortest decimal text that reads back to the same double (so files round-trip exactly).
std::string num(double v) {
    if (v == 0.0) v = 0.0;  // no "-0"
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

std::string mm_text(double metres) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", metres / kMm);
    return buf;
}

std::string fixed2(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    return buf;
}

std::string deg_text(double rad) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f", rad / kDeg);
    return buf;
}

void check(bool ok, const std::string& what) {
    if (!ok) throw std::logic_error(what);
}

Quat about(double angle_rad, const Vec3& axis) { return glm::angleAxis(angle_rad, glm::normalize(axis)); }

// ---------------------------------------------------------------------------------------------
// Trajectories

enum class Ease { Smooth, Linear };

// A haptic keyframe; `ease` shapes the segment that arrives at it (smoothstep starts and stops
// at rest, linear keeps a constant speed).
struct Key {
    double t;
    Vec3 p;
    Quat q;
    Ease ease = Ease::Smooth;
};

Pose keyed_pose(const std::vector<Key>& keys, double t) {
    if (t <= keys.front().t) return {keys.front().p, keys.front().q};
    for (size_t i = 1; i < keys.size(); ++i) {
        if (t > keys[i].t) continue;
        const Key &a = keys[i - 1], &b = keys[i];
        double s = (t - a.t) / (b.t - a.t);
        if (b.ease == Ease::Smooth) s = s * s * (3.0 - 2.0 * s);
        // Written so that a hold (a == b) reproduces its pose bit for bit.
        return {a.p + (b.p - a.p) * s, a.q == b.q ? a.q : glm::slerp(a.q, b.q, s)};
    }
    return {keys.back().p, keys.back().q};
}

// Samples `pose_at` `rows_per_s` times a second from t0 to t1, plus exactly at `exact_times`
// (keyframes, so the runner's linear interpolation passes through every corner of the path).
std::vector<TrajectorySample> sample(const std::function<Pose(double)>& pose_at, double t0, double t1,
                                     double rows_per_s, std::vector<double> exact_times) {
    exact_times.push_back(t0);
    exact_times.push_back(t1);
    std::vector<double> times = exact_times;
    for (long k = 0;; ++k) {
        // k / 1000 rounds once (0.102), where k * 0.001 gives 0.10200000000000001.
        const double t = t0 + static_cast<double>(k) / rows_per_s;
        if (t >= t1) break;
        bool near_exact = false;
        for (double e : exact_times) near_exact = near_exact || std::abs(e - t) < 1e-9;
        if (!near_exact) times.push_back(t);
    }
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end()), times.end());
    std::vector<TrajectorySample> out;
    for (double t : times) {
        Pose p = pose_at(t);
        p.orientation = glm::normalize(p.orientation);
        // Keep neighbouring quaternions in one hemisphere so any interpolation takes the short way.
        if (!out.empty() && glm::dot(out.back().pose.orientation, p.orientation) < 0.0)
            p.orientation = -p.orientation;
        out.push_back({t, p});
    }
    return out;
}

std::vector<TrajectorySample> sample_keys(const std::vector<Key>& keys, double rows_per_s) {
    std::vector<double> key_times;
    for (const Key& k : keys) key_times.push_back(k.t);
    for (size_t i = 1; i < keys.size(); ++i) check(keys[i].t > keys[i - 1].t, "keyframe times must increase");
    return sample([&](double t) { return keyed_pose(keys, t); }, keys.front().t, keys.back().t, rows_per_s, key_times);
}

// ---------------------------------------------------------------------------------------------
// Geometry checks

std::vector<Vec3> placed_vertices(const TriMesh& m, const Pose& pose) {
    std::vector<Vec3> out;
    out.reserve(m.vertices.size());
    for (const Vec3& v : m.vertices) out.push_back(pose.apply(v));
    return out;
}

std::vector<std::array<uint32_t, 2>> unique_edges(const TriMesh& m) {
    std::vector<std::array<uint32_t, 2>> edges;
    for (const auto& t : m.triangles)
        for (int i = 0; i < 3; ++i) {
            const uint32_t a = t[i], b = t[(i + 1) % 3];
            edges.push_back({std::min(a, b), std::max(a, b)});
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    return edges;
}

// Solid angle of triangle abc seen from the origin (Van Oosterom and Strackee).
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num_ = glm::dot(a, glm::cross(b, c));
    const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
    return 2.0 * std::atan2(num_, den);
}

bool inside_by_winding(const Vec3& p, const std::vector<Vec3>& v, const TriMesh& m) {
    double omega = 0.0;
    for (const auto& t : m.triangles) omega += solid_angle(v[t[0]] - p, v[t[1]] - p, v[t[2]] - p);
    return omega / (4.0 * std::numbers::pi) > 0.5;
}

// Distance from p to the triangle abc (closest-point by Voronoi regions).
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return glm::length(p - a);
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return glm::length(p - b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return glm::length(p - c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denom = 1.0 / (va + vb + vc);
    return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

double point_mesh_distance(const Vec3& p, const std::vector<Vec3>& v, const TriMesh& m) {
    double d = 1e300;
    for (const auto& t : m.triangles) d = std::min(d, point_triangle_distance(p, v[t[0]], v[t[1]], v[t[2]]));
    return d;
}

// Segment p0p1 passes through the interior of triangle abc, each side and the crossing point
// clear of the triangle's plane and edges by more than tol.
bool segment_crosses_triangle(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c,
                              double tol) {
    Vec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (len == 0.0) return false;
    n /= len;
    const double d0 = glm::dot(p0 - a, n), d1 = glm::dot(p1 - a, n);
    if (!((d0 > tol && d1 < -tol) || (d0 < -tol && d1 > tol))) return false;
    const Vec3 x = p0 + (p1 - p0) * (d0 / (d0 - d1));
    const Vec3 corners[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
        const Vec3 e = corners[(i + 1) % 3] - corners[i];
        const double inward = glm::dot(glm::cross(e, x - corners[i]), n) / glm::length(e);
        if (inward <= tol) return false;
    }
    return true;
}

bool edges_cross_faces(const std::vector<Vec3>& ev, const TriMesh& em, const std::vector<Vec3>& fv,
                       const TriMesh& fm, double tol) {
    for (const auto& e : unique_edges(em))
        for (const auto& t : fm.triangles)
            if (segment_crosses_triangle(ev[e[0]], ev[e[1]], fv[t[0]], fv[t[1]], fv[t[2]], tol)) return true;
    return false;
}

// Largest signed distance of a point from the face planes of a convex mesh (< 0 inside).
double convex_signed_distance(const Vec3& p, const std::vector<Vec3>& v, const TriMesh& m) {
    double d = -1e300;
    for (const auto& t : m.triangles) {
        const Vec3 n = glm::normalize(glm::cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]]));
        d = std::max(d, glm::dot(p - v[t[0]], n));
    }
    return d;
}

std::string check_convex(const TriMesh& m) {
    for (size_t i = 0; i < m.triangles.size(); ++i) {
        const auto& t = m.triangles[i];
        const Vec3 n = glm::normalize(glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
        for (const Vec3& p : m.vertices)
            if (glm::dot(p - m.vertices[t[0]], n) > kTouchTolerance_m)
                return "not convex: a vertex lies outside the plane of triangle " + std::to_string(i);
    }
    return "";
}

// Support of a mesh rotated by q: the largest extent along `dir` from the local origin.
double support(const TriMesh& m, const Quat& q, const Vec3& dir) {
    double s = -1e300;
    for (const Vec3& v : m.vertices) s = std::max(s, glm::dot(q * v, dir));
    return s;
}

// ---------------------------------------------------------------------------------------------
// Scene descriptions

struct ObjectSpec {
    std::string name;
    std::string mesh_file;
    Pose pose;
};

struct SceneSpec {
    std::string name;
    std::vector<ObjectSpec> objects;
    std::string tool_name;
    std::string tool_file;
    HapticSettings haptic;
    double rate_hz = 1000.0;
    std::vector<TrajectorySample> trajectory;
    std::string readme;  // Markdown section describing the scene
};

struct Bundle {
    std::map<std::string, TriMesh> meshes;  // by file name
    std::vector<SceneSpec> scenes;

    void add_mesh(const std::string& file, const TriMesh& mesh) {
        const auto it = meshes.find(file);
        if (it == meshes.end()) {
            meshes.emplace(file, mesh);
            return;
        }
        check(it->second.vertices == mesh.vertices && it->second.triangles == mesh.triangles,
              file + ": two different meshes under one file name");
    }
    const TriMesh& mesh(const std::string& file) const { return meshes.at(file); }
};

// Cube in a box-shaped cavity (section V.A, Fig. 10-11); `clearance_m` is the total free play
// along Y when the cube is centred.
SceneSpec cavity_scene(Bundle& b, const std::string& name, double clearance_m) {
    const double a = 5 * kMm;  // cube half side
    const Vec3 cavity_half(12 * kMm, a + 0.5 * clearance_m, 12 * kMm);
    const std::string cube_file = "cube_10mm.obj";
    const std::string box_file = name == "cavity_0mm" ? "cavity_box_0mm.obj" : "cavity_box_1mm.obj";
    b.add_mesh(cube_file, make_box(Vec3(a)));
    b.add_mesh(box_file, make_box_with_cavity(Vec3(20 * kMm, 15 * kMm, 20 * kMm), cavity_half));

    const Quat id(1, 0, 0, 0);
    const Vec3 o(0.0);
    const Vec3 z(0, 0, 1);
    const Vec3 up(0, 2 * kMm, 0), up_slid(3 * kMm, 2 * kMm, 0);
    const std::vector<Key> keys{
        {0.0, o, id},  {0.5, o, id},                                      // rest, no contact
        {1.25, o, about(-20 * kDeg, z)}, {2.0, o, id},                    // clockwise and back
        {2.75, o, about(20 * kDeg, z)},  {3.5, o, id},                    // anticlockwise and back
        {3.8, up, id}, {4.2, up_slid, id}, {4.6, up, id}, {5.0, o, id},   // press the ceiling, slide +X and back
        {5.5, o, id},                                                     // rest, no contact
    };
    SceneSpec s;
    s.name = name;
    s.objects = {{"cavity_box", box_file, Pose{}}};
    s.tool_name = "cube_10mm";
    s.tool_file = cube_file;
    s.trajectory = sample_keys(keys, 500.0);

    // The largest turn about Z of a centred square of half side a between walls +-h: a(cos + sin) = h.
    const double h = cavity_half.y;
    const double max_turn = std::asin(h / (a * std::numbers::sqrt2)) - 0.25 * std::numbers::pi;
    s.readme = "## " + name + ".json — cube in a narrow cavity (section V.A, Fig. 10-11)\n\n"
               "Tool: 10 mm cube (`cube_10mm.obj`, origin at its centre). Object: `" + box_file +
               "`, a 40 x 30 x 40 mm box with a hollow of 24 x " + mm_text(2 * h) +
               " x 24 mm centred at the origin: " + mm_text(clearance_m) + " mm total clearance along Y" +
               (clearance_m > 0 ? " (" + mm_text(0.5 * clearance_m) + " mm above and below the centred cube)"
                                : " — the cube touches floor and ceiling from the first tick") +
               ".\n\nHaptic trajectory (`" + name + ".csv`, smoothstep between keyframes, rows every 2 ms):\n\n"
               "| time (s) | haptic motion | expected graphic tool / contacts |\n|---|---|---|\n"
               "| 0.0-0.5 | rest at the origin | " +
               (clearance_m > 0 ? "free, no force" : "resting face-to-face on floor and ceiling, zero force") +
               " |\n"
               "| 0.5-2.0 | turn about +Z clockwise to -20 deg and back | " +
               (clearance_m > 0 ? "turns freely to about -" + deg_text(max_turn) +
                                      " deg (a(cos t + sin t) = h), then edges of the cube press floor and "
                                      "ceiling: restoring torque about Z"
                                : "no rotation at all (blocked by floor and ceiling): torque about Z only") +
               " |\n"
               "| 2.0-3.5 | turn anticlockwise to +20 deg and back | mirror image of the previous phase |\n"
               "| 3.5-5.0 | press up +2 mm, slide +3 mm along X, slide back, release | " +
               (clearance_m > 0 ? "rises 0.5 mm to the ceiling (face contact), force -Y of about 1.5 N, "
                                : "cannot rise: force -Y of about 2 N, ") +
               "slides along X with the haptic tool (no friction) |\n"
               "| 5.0-5.5 | rest at the origin | " +
               (clearance_m > 0 ? "free, no force" : "touching, zero force") + " |\n\n";
    return s;
}

// Line-shaped tool over a step with convex and concave edges (section V.B, Fig. 12-13).
SceneSpec line_tool_scene(Bundle& b) {
    const TriMesh tool = make_box(Vec3(0.5 * kMm, 15 * kMm, 0.5 * kMm));
    // Step profile: upper top y = 0 (x -30..0), wall at x = 0 down to the floor y = -10 (x 0..20),
    // wall up to y = +10 at x = 20, block to x = 30, bottom y = -20; extruded z -10..10 mm.
    const std::vector<Vec2> profile{{-30 * kMm, -20 * kMm}, {30 * kMm, -20 * kMm}, {30 * kMm, 10 * kMm},
                                    {20 * kMm, 10 * kMm},   {20 * kMm, -10 * kMm}, {0, -10 * kMm},
                                    {0, 0},                 {-30 * kMm, 0}};
    const TriMesh step = make_extruded_polygon(profile, -10 * kMm, 10 * kMm);
    b.add_mesh("line_tool.obj", tool);
    b.add_mesh("step_block.obj", step);

    // The shaft leans 30 deg from vertical with its top toward -X, so the tip leads when moving
    // +X (the only lean for which the shaft can rest on the convex edge while the tip is beyond
    // it); it is rolled 45 deg about its axis so the tip has a single lowest vertex (V-F) and a
    // long edge of the shaft crosses the convex edge (E-E) instead of lying flat along it.
    const Quat q = about(30 * kDeg, Vec3(0, 0, 1)) * about(45 * kDeg, Vec3(0, 1, 0));
    const Vec3 tip_local(0, -15 * kMm, 0);
    const Vec3 tip = q * tip_local;                                   // tip relative to the centre
    const double min_y = -support(tool, q, Vec3(0, -1, 0));          // lowest point rel. centre
    const double max_x = support(tool, q, Vec3(1, 0, 0));            // rightmost point rel. centre
    const Vec3 n_edge(-std::cos(30 * kDeg), -std::sin(30 * kDeg), 0);  // from shaft toward the edge
    const double side = support(tool, q, n_edge);
    // Centre x at which the shaft overlaps the convex edge (0, 0) by `depth` along n_edge.
    auto x_for_edge_depth = [&](double cy, double depth) { return (depth - side - cy * n_edge.y) / n_edge.x; };
    auto edge_depth = [&](const Vec3& c) { return glm::dot(c, n_edge) + side; };
    // Smallest x of the tool's tip face (local y = -15 mm), relative to the centre.
    double tip_face_min_x = 1e300;
    for (const Vec3& v : tool.vertices)
        if (v.y < 0) tip_face_min_x = std::min(tip_face_min_x, (q * v).x);

    const Vec3 k0(-20 * kMm - tip.x, 2 * kMm - min_y, 0);                  // tip 2 mm above the top
    const Vec3 k1(k0.x, -1 * kMm - min_y, 0);                              // V-F: 1 mm into the top
    const Vec3 k2(-1 * kMm - max_x, k1.y, 0);                              // slid to 1 mm before the edge
    const Vec3 k2b(0.5 * kMm - tip_face_min_x, k1.y, 0);                   // tip just past the edge
    const double k3y = -5 * kMm - min_y;                                   // tip halfway down the wall
    const Vec3 k3(x_for_edge_depth(k3y, 1 * kMm), k3y, 0);                 // E-E: shaft 1 mm onto the edge
    // Two regions: 1 mm straight below the pose whose tip rests on the floor while the shaft just
    // touches the edge. That double-touch pose is then the nearest free pose (pushing up clears
    // the floor and the edge by the same amount), so both contacts stay active together.
    const double floor_touch_y = -10 * kMm - min_y;
    const Vec3 k4(x_for_edge_depth(floor_touch_y, 0.0), floor_touch_y - 1 * kMm, 0);
    const Vec3 k5(21 * kMm - max_x, k4.y, 0);                              // tip 1 mm into floor and wall
    const Vec3 k6(19 * kMm - max_x, -9 * kMm - min_y, 0);                  // backed off, free
    const Vec3 k7(k6.x, 12 * kMm - min_y, 0);                              // lifted above everything

    // Each phase really happens: the haptic pose is free, or overlaps, where intended.
    const Pose id_pose;
    auto overlaps = [&](const Vec3& c) { return tool_overlaps_object(step, id_pose, tool, Pose{c, q}, kTouchTolerance_m); };
    check(!overlaps(k0) && overlaps(k1) && overlaps(k2) && overlaps(k3) && overlaps(k4) && overlaps(k5) &&
              !overlaps(k6) && !overlaps(k7),
          "line_tool: a keyframe is not in its intended contact state");
    check(k3.x + tip_face_min_x > 0.2 * kMm && k4.x + tip_face_min_x > 0.2 * kMm,
          "line_tool: the tip must be clear of the wall at x = 0 in the E-E phases");
    check(k2.x + max_x < 0, "line_tool: before the edge the whole tool must be over the top face");
    check(edge_depth(k2b) > 0 && edge_depth(k2b) < 2 * side, "line_tool: past the edge the shaft must overlap it");
    check(k4.x + max_x < 20 * kMm, "line_tool: the two-region pose must not reach the far wall");

    const std::vector<Key> keys{{0.0, k0, q},  {0.3, k0, q},  {0.8, k1, q}, {2.0, k2, q}, {2.4, k2b, q},
                                {2.9, k3, q},  {3.5, k4, q},  {3.8, k4, q}, {4.5, k5, q}, {4.8, k6, q},
                                {5.3, k7, q},  {5.6, k7, q}};
    SceneSpec s;
    s.name = "line_tool";
    s.objects = {{"step_block", "step_block.obj", Pose{}}};
    s.tool_name = "line_tool";
    s.tool_file = "line_tool.obj";
    s.trajectory = sample_keys(keys, 500.0);
    auto tip_at = [&](const Vec3& c) { return "(" + mm_text(c.x + tip.x) + ", " + mm_text(c.y + tip.y) + ")"; };
    s.readme =
        "## line_tool.json — line-shaped tool over convex and concave edges (section V.B, Fig. 12-13)\n\n"
        "Tool: `line_tool.obj`, a 1 x 30 x 1 mm box along its local Y, origin at its centre, tip at local "
        "(0, -15, 0) mm. It is held leaning 30 deg from vertical with its top toward -X (the tip leads when "
        "moving +X: only with this lean can the shaft rest on the convex edge while the tip is beyond it) "
        "and rolled 45 deg about its own axis, so the tip has a single lowest vertex and a long edge of the "
        "shaft crosses the object's edges (generic V-F and E-E contacts rather than face-on-face). The "
        "orientation stays fixed along the whole haptic path.\n\n"
        "Object: `step_block.obj`, the XY profile (-30,-20) (30,-20) (30,10) (20,10) (20,-10) (0,-10) (0,0) "
        "(-30,0) mm extruded from z = -10 to +10 mm: an upper top face y = 0 for x < 0, a convex edge at "
        "(0, 0), a wall down to the floor y = -10 between x = 0 and 20, a concave corner at (20, -10) and a "
        "wall up to y = +10.\n\n"
        "Keyframes (tip point in mm as (x, y); smoothstep between them, rows every 2 ms); the haptic target "
        "lies 1 mm inside the surfaces during contact:\n\n"
        "| time (s) | haptic tip | expected contact |\n|---|---|---|\n"
        "| 0.0-0.3 | " + tip_at(k0) + ", lowest vertex 2 mm above the top | none |\n"
        "| 0.3-0.8 | " + tip_at(k1) + ", lowest vertex 1 mm into the top | V-F (tip vertex on the top face) |\n"
        "| 0.8-2.0 | slides +X to " + tip_at(k2) + " | V-F sliding, no friction |\n"
        "| 2.0-2.4 | " + tip_at(k2b) + ", tip face past x = 0 | tip leaves the top face; the shaft's lower "
        "long edge drops onto the convex edge (haptic overlap " + mm_text(edge_depth(k2b)) + " mm): V-F -> E-E |\n"
        "| 2.4-2.9 | " + tip_at(k3) + " | E-E (shaft on the convex edge, tip free beside the wall) |\n"
        "| 2.9-3.5, hold to 3.8 | " + tip_at(k4) + ", 1 mm straight below the pose whose tip rests on the "
        "floor while the shaft just touches the edge (haptic overlap of the edge " + mm_text(edge_depth(k4)) +
        " mm) | two regions: E-E on the convex edge and V-F of the tip on the floor; pushing up clears both "
        "by the same amount, so both stay active |\n"
        "| 3.8-4.5 | " + tip_at(k5) + ", 1 mm into floor and far wall | shaft leaves the edge; tip in the "
        "concave corner: V-F on the floor plus V-F on the wall |\n"
        "| 4.5-4.8 | " + tip_at(k6) + ", 1 mm clear of floor and wall | none |\n"
        "| 4.8-5.6 | lifted to " + tip_at(k7) + ", hold from 5.3 | none |\n\n";
    return s;
}

// Cube falling onto a 0.05 mm plate (Fig. 5a): without continuous detection it would tunnel.
SceneSpec thin_plate_scene(Bundle& b, const std::string& name, double speed_m_per_s, double turn_rad) {
    const double a = 2.5 * kMm, plate_half_t = 0.025 * kMm;
    b.add_mesh("cube_5mm.obj", make_box(Vec3(a)));
    b.add_mesh("thin_plate.obj", make_box(Vec3(20 * kMm, plate_half_t, 20 * kMm)));
    const Vec3 top(0, plate_half_t + 10 * kMm + a, 0);       // 10 mm above the plate
    const Vec3 bottom(0, -plate_half_t - 10 * kMm - a, 0);   // 10 mm below it
    const double fall_s = (top.y - bottom.y) / speed_m_per_s;
    const Quat q0(1, 0, 0, 0), q1 = about(turn_rad, Vec3(0, 1, 0));
    const double t1 = 0.1, t2 = t1 + fall_s, t3 = t2 + 0.2, t4 = t3 + fall_s, t5 = t4 + 0.1;
    const std::vector<Key> keys{{0.0, top, q0},
                                {t1, top, q0},
                                {t2, bottom, q1, Ease::Linear},
                                {t3, bottom, q1},
                                {t4, top, q0, Ease::Linear},
                                {t5, top, q0}};
    SceneSpec s;
    s.name = name;
    s.objects = {{"thin_plate", "thin_plate.obj", Pose{}}};
    s.tool_name = "cube_5mm";
    s.tool_file = "cube_5mm.obj";
    s.trajectory = sample_keys(keys, 1000.0);
    const double per_tick_mm = speed_m_per_s / s.rate_hz / kMm;
    s.readme = "## " + name + ".json — thin plate, tunnelling test (Fig. 5a)\n\n"
               "Tool: 5 mm cube (`cube_5mm.obj`). Object: `thin_plate.obj`, 40 x 0.05 x 40 mm, thickness along Y, "
               "centred at the origin. The haptic cube starts 10 mm above the plate, rests 0.1 s, moves straight "
               "down at " + num(speed_m_per_s) + " m/s (" + num(per_tick_mm) + " mm per tick at 1 kHz, " +
               num(per_tick_mm / 0.05) + " times the plate thickness) to 10 mm below it" +
               (turn_rad != 0 ? ", turning " + deg_text(turn_rad) + " deg about Y on the way" : "") +
               ", stays 0.2 s, returns up at the same speed" +
               (turn_rad != 0 ? " (turning back)" : "") +
               " and rests 0.1 s. Rows every 1 ms plus the exact corners of the path.\n\n"
               "Expected: the graphic cube stops on top of the plate (bottom face at y = +0.025 mm) and never "
               "passes through it; the force points +Y and grows to about " +
               fixed2(s.haptic.stiffness_N_per_m * (plate_half_t + a - bottom.y)) +
               " N at the lowest haptic pose (1 N/mm); the cube follows the haptic tool back up. "
               "Face-on-face contact (four V-F of the cube's bottom corners on the plate)" +
               (turn_rad != 0 ? ", turning about the plate normal while in contact" : "") + ".\n\n";
    return s;
}

// Cube pushed across a sharp ridge (Fig. 5b): the local solution stays on the near flank.
SceneSpec sharp_corner_scene(Bundle& b) {
    const double a = 2.5 * kMm, half_apex = 15 * kDeg;
    b.add_mesh("cube_5mm.obj", make_box(Vec3(a)));
    b.add_mesh("wedge_30deg.obj", make_wedge(2 * half_apex, 20 * kMm, 20 * kMm));
    const Vec3 n_left(-std::cos(half_apex), std::sin(half_apex), 0), n_right(std::cos(half_apex), std::sin(half_apex), 0);

    const Vec3 k0(-4 * kMm, 6 * kMm, 0);
    // Touching the left flank with the cube's lower right edge (x0 + a, y - a) on x = y tan(15 deg).
    const double corner_x = k0.x + a;
    const Vec3 touch(k0.x, corner_x / std::tan(half_apex) + a, 0);
    const Vec3 k1 = touch - 1 * kMm * n_left;  // 1 mm into the left flank
    const Vec3 k2(3 * kMm, -8 * kMm, 0);       // below and right of the apex

    // 2-D separating-axis check at k2: the shortest way out of the wedge is along the right flank
    // normal (the global solution), not back to the left flank where the local solution stays.
    const std::vector<Vec3> wedge{{-20 * kMm * std::tan(half_apex), -20 * kMm, 0},
                                  {20 * kMm * std::tan(half_apex), -20 * kMm, 0}, {0, 0, 0}};
    auto push_out = [&](const Vec3& c, const Vec3& d) {  // translation along d that frees the cube
        double box_min = 1e300, wedge_max = -1e300;
        for (double sx : {-a, a})
            for (double sy : {-a, a}) box_min = std::min(box_min, glm::dot(c + Vec3(sx, sy, 0), d));
        for (const Vec3& w : wedge) wedge_max = std::max(wedge_max, glm::dot(w, d));
        return wedge_max - box_min;
    };
    const std::vector<Vec3> axes{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, n_left, -n_left, n_right, -n_right};
    size_t best = 0;
    for (size_t i = 1; i < axes.size(); ++i)
        if (push_out(k2, axes[i]) < push_out(k2, axes[best])) best = i;
    check(best == 6 && push_out(k2, n_right) > 0, "sharp_corner: the global exit at k2 must be the right flank");
    const double depth_right = push_out(k2, n_right), depth_left = push_out(k2, n_left);

    const Pose id_pose;
    const TriMesh& cube = b.mesh("cube_5mm.obj");
    const TriMesh& ridge = b.mesh("wedge_30deg.obj");
    check(!tool_overlaps_object(ridge, id_pose, cube, Pose{k0, Quat(1, 0, 0, 0)}, kTouchTolerance_m) &&
              tool_overlaps_object(ridge, id_pose, cube, Pose{k1, Quat(1, 0, 0, 0)}, kTouchTolerance_m),
          "sharp_corner: the start must be free and the first contact pose must press the left flank");

    const Quat id(1, 0, 0, 0);
    const std::vector<Key> keys{{0.0, k0, id}, {0.2, k0, id}, {0.8, k1, id}, {2.0, k2, id},
                                {2.3, k2, id}, {3.1, k1, id}, {3.7, k0, id}, {3.9, k0, id}};
    SceneSpec s;
    s.name = "sharp_corner";
    s.objects = {{"ridge", "wedge_30deg.obj", Pose{}}};
    s.tool_name = "cube_5mm";
    s.tool_file = "cube_5mm.obj";
    s.trajectory = sample_keys(keys, 500.0);
    auto at = [](const Vec3& c) { return "(" + mm_text(c.x) + ", " + mm_text(c.y) + ")"; };
    s.readme =
        "## sharp_corner.json — sharp ridge, local versus global solution (Fig. 5b)\n\n"
        "Tool: 5 mm cube (`cube_5mm.obj`), axis-aligned. Object: `wedge_30deg.obj`, a ridge along Z "
        "(z -20..20 mm) with its apex at the origin, apex angle 30 deg, base at y = -20 mm (flanks 75 deg "
        "from horizontal).\n\n"
        "Haptic path (cube centre, mm; smoothstep between keyframes, rows every 2 ms): rest at " + at(k0) +
        " (above the left flank, free) until 0.2 s; down onto the left flank to " + at(k1) +
        " (its lower right edge 1 mm into the flank) at 0.8 s; on down and right, under the apex, to " + at(k2) +
        " at 2.0 s; hold to 2.3 s; back the same way to " + at(k1) + " at 3.1 s and " + at(k0) +
        " at 3.7 s; rest to 3.9 s.\n\n"
        "At " + at(k2) + " the haptic cube overlaps the right flank by " + mm_text(depth_right) +
        " mm along its normal, while escaping to the left flank would take " + mm_text(depth_left) +
        " mm: the global nearest free pose is on the right flank. Expected: the graphic cube never "
        "crosses the ridge; it stays on the left flank (edge-on-face contact, V-F pairs of the cube's lower "
        "right edge), with the force pointing up-left, growing as the haptic tool moves away, and follows "
        "the haptic tool back up to free space without any jump.\n\n";
    return s;
}

// No object within reach: the graphic tool must equal the haptic tool on every tick.
SceneSpec free_motion_scene(Bundle& b) {
    b.add_mesh("cube_10mm.obj", make_box(Vec3(5 * kMm)));
    b.add_mesh("block_40mm.obj", make_box(Vec3(20 * kMm), Vec3(150 * kMm, 0, 0)));
    const double two_pi = 2 * std::numbers::pi;
    auto pose_at = [&](double t) {
        const Vec3 p(20 * kMm * std::sin(two_pi * 0.4 * t), 15 * kMm * std::sin(two_pi * 0.6 * t),
                     10 * kMm * std::sin(two_pi * 0.5 * t));
        const Quat q = about(0.6 * std::sin(two_pi * 0.3 * t), Vec3(1, 0.4, 0.2)) *
                       about(1.2 * std::sin(two_pi * 0.2 * t), Vec3(0, 1, 0));
        return Pose{p, q};
    };
    SceneSpec s;
    s.name = "free_motion";
    s.objects = {{"block", "block_40mm.obj", Pose{}}};
    s.tool_name = "cube_10mm";
    s.tool_file = "cube_10mm.obj";
    s.trajectory = sample(pose_at, 0.0, 5.0, 500.0, {});
    s.readme =
        "## free_motion.json — free motion, no contact\n\n"
        "Tool: 10 mm cube. Object: `block_40mm.obj`, a 40 mm cube centred at (150, 0, 0) mm, far out of "
        "reach. The haptic cube follows a Lissajous path (x 20 mm at 0.4 Hz, y 15 mm at 0.6 Hz, z 10 mm at "
        "0.5 Hz) while turning (up to 0.6 rad about (1, 0.4, 0.2) at 0.3 Hz after up to 1.2 rad about Y at "
        "0.2 Hz) for 5 s; rows every 2 ms. Expected: no contact on any tick, zero force and torque, and "
        "the graphic pose equal to the haptic pose on every tick.\n\n";
    return s;
}

Bundle build_bundle() {
    Bundle b;
    b.scenes.push_back(cavity_scene(b, "cavity_1mm", 1 * kMm));
    b.scenes.push_back(cavity_scene(b, "cavity_0mm", 0.0));
    b.scenes.push_back(line_tool_scene(b));
    b.scenes.push_back(thin_plate_scene(b, "thin_plate", 1.0, 0.0));
    b.scenes.push_back(sharp_corner_scene(b));
    b.scenes.push_back(thin_plate_scene(b, "thin_plate_fast", 5.0, 90 * kDeg));
    b.scenes.push_back(free_motion_scene(b));
    return b;
}

// ---------------------------------------------------------------------------------------------
// Output

std::string obj_text(const TriMesh& m, const std::string& what) {
    std::string s = "# " + what + "; generated by tools/make_paper_scenes; coordinates in metres\n";
    for (const Vec3& v : m.vertices) s += "v " + num(v.x) + " " + num(v.y) + " " + num(v.z) + "\n";
    for (const auto& t : m.triangles)
        s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
    return s;
}

std::string csv_text(const std::vector<TrajectorySample>& rows) {
    std::string s = "t,x,y,z,qw,qx,qy,qz\n";
    for (const auto& r : rows) {
        const Vec3& p = r.pose.position;
        const Quat& q = r.pose.orientation;
        s += num(r.t) + "," + num(p.x) + "," + num(p.y) + "," + num(p.z) + "," + num(q.w) + "," + num(q.x) + "," +
             num(q.y) + "," + num(q.z) + "\n";
    }
    return s;
}

std::string json_string(const std::string& v) { return "\"" + v + "\""; }  // names are plain ASCII

std::string scene_json(const SceneSpec& s) {
    std::string j = "{\n  \"format\": \"sulcus.scene/1\",\n  \"objects\": [\n";
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const ObjectSpec& o = s.objects[i];
        const Vec3& p = o.pose.position;
        const Quat& q = o.pose.orientation;
        j += "    { \"name\": " + json_string(o.name) + ", \"mesh\": " + json_string(o.mesh_file) +
             ",\n      \"position\": [" + num(p.x) + ", " + num(p.y) + ", " + num(p.z) + "], \"orientation\": [" +
             num(q.w) + ", " + num(q.x) + ", " + num(q.y) + ", " + num(q.z) + "] }" +
             (i + 1 < s.objects.size() ? "," : "") + "\n";
    }
    j += "  ],\n  \"tool\": { \"name\": " + json_string(s.tool_name) + ", \"mesh\": " + json_string(s.tool_file) +
         " },\n  \"haptic\": {\n" + "    \"stiffness_N_per_m\": " + num(s.haptic.stiffness_N_per_m) + ",\n" +
         "    \"rotational_stiffness_Nm_per_rad\": " + num(s.haptic.rotational_stiffness_Nm_per_rad) + ",\n" +
         "    \"weight_translational\": " + num(s.haptic.weight_translational) + ",\n" +
         "    \"weight_rotational\": " + num(s.haptic.weight_rotational) + "\n  },\n" +
         "  \"trajectory\": " + json_string(s.name + ".csv") + ",\n  \"rate_hz\": " + num(s.rate_hz) + "\n}\n";
    return j;
}

std::string readme_text(const Bundle& b) {
    std::string r =
        "# Paper scenes\n\n"
        "Scenes reproducing the experiments of the seed paper (section V: a cube in a narrow cavity, a "
        "line-shaped tool over convex and concave features) and its Fig. 5 (tunnelling through a thin "
        "object, a sharp feature), plus a free-motion check. Each `NAME.json` is a `sulcus.scene/1` file "
        "with its trajectory `NAME.csv` (haptic tool pose over time: seconds, metres, unit quaternion "
        "w, x, y, z) and OBJ meshes in metres. Run one with `sulcus-cli run NAME.json`.\n\n"
        "All scenes use the default haptic settings (1000 N/m, 0.03 N·m/rad, weights 1 and 1e-4) at "
        "1 kHz. Tools are convex with their origin at their centre. The first trajectory pose of every "
        "scene is checked not to penetrate (touching is allowed: `cavity_0mm`).\n\n"
        "These files are generated: edit `content/src/paper_scenes.cpp`, then run "
        "`build/bin/make_paper_scenes content/assets/scenes/paper`.\n\n";
    for (const SceneSpec& s : b.scenes) r += s.readme;
    return r;
}

bool write_whole(const std::filesystem::path& path, const std::string& text, std::string* error) {
    const std::filesystem::path tmp = path.string() + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        f << text;
        f.flush();
        if (!f) {
            if (error) *error = tmp.string() + ": cannot write";
            return false;
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        if (error) *error = path.string() + ": cannot rename from " + tmp.string() + ": " + ec.message();
        return false;
    }
    return true;
}

// Every self-check a generated scene must pass; "" or the first fault.
std::string check_scene(const Bundle& b, const SceneSpec& s) {
    const std::string where = s.name + ".json: ";
    const TriMesh& tool = b.mesh(s.tool_file);
    if (std::string e = check_convex(tool); !e.empty()) return where + "tool " + s.tool_file + ": " + e;
    if (s.trajectory.size() < 2) return where + "trajectory needs at least two rows";
    for (size_t i = 0; i < s.trajectory.size(); ++i) {
        const TrajectorySample& r = s.trajectory[i];
        const Quat& q = r.pose.orientation;
        const bool finite = std::isfinite(r.t) && std::isfinite(r.pose.position.x) && std::isfinite(r.pose.position.y) &&
                            std::isfinite(r.pose.position.z) && std::isfinite(q.w) && std::isfinite(q.x) &&
                            std::isfinite(q.y) && std::isfinite(q.z);
        if (!finite) return where + "trajectory row " + std::to_string(i) + " is not finite";
        if (std::abs(glm::length(q) - 1.0) > 1e-12) return where + "trajectory row " + std::to_string(i) + " quaternion is not unit";
        if (i > 0 && !(r.t > s.trajectory[i - 1].t)) return where + "trajectory time does not increase at row " + std::to_string(i);
    }
    for (const ObjectSpec& o : s.objects)
        if (tool_overlaps_object(b.mesh(o.mesh_file), o.pose, tool, s.trajectory.front().pose, kTouchTolerance_m))
            return where + "the first trajectory pose penetrates object " + o.name;
    return "";
}

}  // namespace

std::vector<std::string> paper_scene_names() {
    return {"cavity_1mm", "cavity_0mm", "line_tool", "thin_plate", "sharp_corner", "thin_plate_fast", "free_motion"};
}

std::string check_closed_outward(const TriMesh& mesh) {
    const size_t nv = mesh.vertices.size();
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& t = mesh.triangles[i];
        for (uint32_t k : t)
            if (k >= nv) return "triangle " + std::to_string(i) + " has a vertex index out of range";
        const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        if (glm::length(glm::cross(b - a, c - a)) == 0.0) return "triangle " + std::to_string(i) + " has zero area";
        for (int e = 0; e < 3; ++e)
            if (++directed[{t[e], t[(e + 1) % 3]}] > 1)
                return "edge " + std::to_string(t[e]) + "-" + std::to_string(t[(e + 1) % 3]) +
                       " is used twice in one direction (not manifold or not consistently oriented)";
    }
    for (const auto& [edge, count] : directed)
        if (directed.find({edge.second, edge.first}) == directed.end())
            return "edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) +
                   " has no opposite (mesh not closed)";
    double six_volume = 0.0;
    for (const auto& t : mesh.triangles)
        six_volume += glm::dot(mesh.vertices[t[0]], glm::cross(mesh.vertices[t[1]], mesh.vertices[t[2]]));
    if (!(six_volume > 0.0)) return "enclosed volume is not positive (faces point inwards)";
    return "";
}

bool tool_overlaps_object(const TriMesh& object, const Pose& object_pose, const TriMesh& convex_tool,
                          const Pose& tool_pose, double tolerance_m) {
    const std::vector<Vec3> ov = placed_vertices(object, object_pose);
    const std::vector<Vec3> tv = placed_vertices(convex_tool, tool_pose);
    for (const Vec3& p : tv)
        if (inside_by_winding(p, ov, object) && point_mesh_distance(p, ov, object) > tolerance_m) return true;
    for (const Vec3& p : ov)
        if (convex_signed_distance(p, tv, convex_tool) < -tolerance_m) return true;
    return edges_cross_faces(tv, convex_tool, ov, object, tolerance_m) ||
           edges_cross_faces(ov, object, tv, convex_tool, tolerance_m);
}

bool write_paper_scenes(const std::string& dir, std::string* error) {
    Bundle b;
    try {
        b = build_bundle();
    } catch (const std::exception& e) {
        if (error) *error = std::string("paper scenes: ") + e.what();
        return false;
    }
    for (const auto& [file, mesh] : b.meshes)
        if (std::string e = check_closed_outward(mesh); !e.empty()) {
            if (error) *error = file + ": " + e;
            return false;
        }
    for (const SceneSpec& s : b.scenes)
        if (std::string e = check_scene(b, s); !e.empty()) {
            if (error) *error = e;
            return false;
        }

    const std::filesystem::path root(dir);
    std::error_code ec;
    std::filesystem::create_directories(root, ec);
    if (ec) {
        if (error) *error = dir + ": cannot create: " + ec.message();
        return false;
    }
    for (const auto& [file, mesh] : b.meshes)
        if (!write_whole(root / file, obj_text(mesh, file), error)) return false;
    for (const SceneSpec& s : b.scenes) {
        if (!write_whole(root / (s.name + ".csv"), csv_text(s.trajectory), error)) return false;
        if (!write_whole(root / (s.name + ".json"), scene_json(s), error)) return false;
    }
    return write_whole(root / "README.md", readme_text(b), error);
}

}  // namespace sulcus
