// Periodontal probes: spec table, centreline and body profile, collision tip, drawable node.
// Geometry notes (profile, rings, hull) are in docs/probes.md.
#include "sulcus/content/probes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

namespace sulcus {
namespace {

constexpr double kMm = 1e-3;
constexpr double kDeg = std::numbers::pi / 180.0;

// Azimuthal resolution: the collision tip's rings have kCollisionSides vertices, the drawn body
// twice as many on the same azimuths, so every collision vertex of a straight probe is a body vertex.
constexpr int kCollisionSides = 12;
constexpr int kBodySides = 48;
constexpr int kGripSides = 16;          // flat facets of the grip
constexpr int kCollisionCapRings = 3;   // tip cap rings of the collision tip (pole excluded)
constexpr int kBodyCapRings = 12;       // twice as many on the body, same angles every other ring
constexpr double kLineWidth_m = 0.15 * kMm;   // width of a thin graduation ring
constexpr double kMarkDepth_m = 0.02 * kMm;   // marks reach this far inside the body (hidden)
constexpr double kArcStep_m = 0.25 * kMm;     // ring spacing along the Nabers arc
constexpr double kBendStep_rad = 5.0 * kDeg;  // ring spacing along shank bends

// Collision pieces beyond the tip follow the drawn body this closely: the polygon of a piece's
// rings (a subset of the body's 48 azimuths) within kPieceRadialTol_m of the circle, and the chord
// of a curved piece within kPieceChordTol_m of the arc on either side.
constexpr double kPieceRadialTol_m = 0.02 * kMm;
constexpr double kPieceChordTol_m = 0.025 * kMm;

// The handle's rings: (distance along the handle axis from the shank's end, radius), mm. The
// ferrule is a smooth cone in two frustums (together not convex: it flares), the grip a faceted
// prism with chamfered ends (convex).
struct HandleRing {
    double a_mm, r_mm;
};
constexpr HandleRing kFerrule[] = {{-1.0, 0.7}, {10.0, 2.4}, {13.0, 3.3}};
constexpr HandleRing kGrip[] = {{12.5, 3.2}, {14.0, 4.0}, {112.0, 4.0}, {113.5, 3.2}};

// The centreline is a chain of pieces in the XY plane, starting at the origin heading +Y.
// Heading psi: tangent = (-sin psi, cos psi, 0); kappa > 0 turns toward -X.
struct Piece {
    double length_m;
    double kappa_per_m;
};

struct Geometry {
    double R = 0;                // tip radius
    double phi_cap = 0;          // angle from the pole where the tip cap ends (tangent or neck)
    double u_cap = 0, r_cap = 0; // end of the cap: distance from the tip end and radius
    double L = 0, r_L = 0;       // top of the working end
    double r_shank_end = 0;      // body radius where the shank enters the handle
    std::vector<Piece> path;
    double path_length = 0;
    double straight_until = 0;   // the centreline is the Y axis up to here
};

ProbeMark line_at(double mm) { return {(mm * kMm) - 0.5 * kLineWidth_m, (mm * kMm) + 0.5 * kLineWidth_m, kProbeMarkBlack}; }
ProbeMark band(double from_mm, double to_mm) { return {from_mm * kMm, to_mm * kMm, kProbeMarkBlack}; }

std::vector<double> mm_list(std::initializer_list<double> mm) {
    std::vector<double> out;
    for (double v : mm) out.push_back(v * kMm);
    return out;
}

std::array<ProbeSpec, 5> build_specs() {
    const std::vector<std::string> general = {"biologyinsights.com \"Periodontal Probe Markings\"",
                                              "ergodenta.dk probe guide", "juniordentist.com"};
    const std::string tip_src = "Carranza's Clinical Periodontology 12th ed. (dentaldevotee.com): 0.5 mm tip";
    std::array<ProbeSpec, 5> s;

    s[0] = {ProbeKind::Williams, "Williams", 0.5 * kMm, false, 12.0 * kMm, mm_list({1, 2, 3, 5, 7, 8, 9, 10}), {},
            0.9 * kMm, 0.5 * kMm, 0.0, 12.0 * kMm, general};
    for (double g : {1, 2, 3, 5, 7, 8, 9, 10}) s[0].marks.push_back(line_at(g));
    s[0].sources.push_back("todaysrdh.com (Williams, 1936)");
    s[0].sources.push_back(tip_src);

    s[1] = {ProbeKind::Unc15, "UNC-15", 0.5 * kMm, false, 16.0 * kMm, {}, {}, 0.9 * kMm, 0.5 * kMm, 0.0, 16.0 * kMm, general};
    for (int g = 1; g <= 15; ++g) s[1].graduations_m.push_back(g * kMm);
    for (double g : {1, 2, 3, 6, 7, 8, 11, 12, 13}) s[1].marks.push_back(line_at(g));
    for (double b : {5, 10, 15}) s[1].marks.push_back(band(b - 1, b));
    std::sort(s[1].marks.begin(), s[1].marks.end(), [](const ProbeMark& a, const ProbeMark& b) { return a.from_m < b.from_m; });
    s[1].sources.push_back(tip_src);

    s[2] = {ProbeKind::Cpi, "WHO / CPI", 0.5 * kMm, true, 13.0 * kMm, mm_list({3.5, 5.5, 8.5, 11.5}),
            {band(3.5, 5.5), line_at(8.5), line_at(11.5)}, 0.8 * kMm, 0.47 * kMm, 0.0, 13.0 * kMm,
            {"WHO Oral Health Surveys - Basic Methods, 4th ed. 1997, CPI (0.5 mm ball, band 3.5-5.5 mm, rings 8.5 and 11.5 mm)",
             "WHO 3rd ed. 1987 CPITN extract", "openaire record on the WHO probe design (20 g)"}};

    s[3] = {ProbeKind::Marquis, "Marquis (CP-12)", 0.5 * kMm, false, 13.5 * kMm, mm_list({3, 6, 9, 12}),
            {band(3, 6), band(9, 12)}, 0.9 * kMm, 0.5 * kMm, 0.0, 13.5 * kMm, {"juniordentist.com", "ergodenta.dk probe guide", tip_src}};

    s[4] = {ProbeKind::Nabers, "Nabers (furcation)", 0.5 * kMm, false, 15.0 * kMm, mm_list({3, 6, 9, 12}),
            {band(3, 6), band(9, 12)}, 1.0 * kMm, 0.5 * kMm, 10.0 * kMm, 3.0 * kMm,
            {"iperiopal.com \"Naber's probe\"", "ergodenta.dk probe guide", "neetmds.com",
             "Carranza 12th ed. ch. 61 caption (trendsperioimplantresourcecenter)"}};
    return s;
}

const std::array<ProbeSpec, 5>& specs() {
    static const std::array<ProbeSpec, 5> table = build_specs();
    return table;
}

// Angle from the pole at which the tangent from the profile point (r, u) touches the tip circle
// (centre on the axis at u = R).
double tangent_angle(double R, double r, double u) {
    const double A = r, B = u - R;
    return std::atan2(B, A) + std::asin(R / std::sqrt(A * A + B * B));
}

double cap_angle(double phi_end, int k, int rings_of_body) { return phi_end * k / rings_of_body; }

// End point and heading of a chain of pieces.
void walk(const std::vector<Piece>& path, double u, Vec3* p_out, double* psi_out) {
    Vec3 p(0.0);
    double psi = 0.0;
    for (size_t i = 0; i < path.size(); ++i) {
        const Piece& piece = path[i];
        const bool last = i + 1 == path.size();
        const double s = last ? u : std::min(u, piece.length_m);
        if (piece.kappa_per_m == 0.0) {
            p += s * Vec3(-std::sin(psi), std::cos(psi), 0.0);
        } else {
            const double psi1 = psi + piece.kappa_per_m * s;
            p += (1.0 / piece.kappa_per_m) * Vec3(std::cos(psi1) - std::cos(psi), std::sin(psi1) - std::sin(psi), 0.0);
            psi = psi1;
        }
        u -= s;
        if (u <= 0.0) break;
    }
    *p_out = p;
    *psi_out = psi;
}

double cross2(const Vec3& a, const Vec3& b) { return a.x * b.y - a.y * b.x; }

Geometry build_geometry(const ProbeSpec& spec) {
    Geometry g;
    g.R = 0.5 * spec.tip_diameter_m;
    g.L = spec.working_length_m;
    g.r_L = 0.5 * spec.shank_diameter_m;
    if (spec.ball_tip) {
        // The ball continues past its equator to the neck, where the shaft starts.
        const double r_neck = 0.5 * spec.neck_diameter_m;
        g.phi_cap = std::numbers::pi - std::asin(r_neck / g.R);
    } else {
        // The taper is tangent to the tip sphere: a smooth rounded end.
        g.phi_cap = tangent_angle(g.R, g.r_L, g.L);
    }
    g.u_cap = g.R * (1.0 - std::cos(g.phi_cap));
    g.r_cap = g.R * std::sin(g.phi_cap);
    g.straight_until = std::max(g.R, g.u_cap);

    const double bend_r = 3.0 * kMm;
    if (spec.curve_radius_m == 0.0) {
        // Two bends in the XY plane (a contra-angle), sized so that the handle's axis passes
        // through the tip: the instrument is balanced.
        const double a1 = 40.0 * kDeg, a2 = -25.0 * kDeg, tail = 3.0 * kMm;
        std::vector<Piece> p0 = {{g.L, 0.0}, {a1 * bend_r, 1.0 / bend_r}, {0.0, 0.0}, {-a2 * bend_r, -1.0 / bend_r}, {tail, 0.0}};
        auto end_of = [&](double mid) {
            std::vector<Piece> p = p0;
            p[2].length_m = mid;
            double len = 0;
            for (const Piece& x : p) len += x.length_m;
            Vec3 e;
            double psi;
            walk(p, len, &e, &psi);
            return e;
        };
        const double psi_mid = a1, psi_h = a1 + a2;
        const Vec3 t_mid(-std::sin(psi_mid), std::cos(psi_mid), 0.0), t_h(-std::sin(psi_h), std::cos(psi_h), 0.0);
        const double mid = -cross2(end_of(0.0), t_h) / cross2(t_mid, t_h);
        if (!(mid > 1.0 * kMm)) throw std::logic_error("probe shank: no room between the bends");
        g.path = p0;
        g.path[2].length_m = mid;
        g.r_shank_end = 0.8 * kMm;
    } else {
        // The working end is an arc toward +X after the straight tip; a short shank then turns the
        // rest of the way to a right angle, so the handle runs along +X: held upright, the tip
        // points sideways into a furcation.
        const double k = -1.0 / spec.curve_radius_m;
        const double turned = (g.L - g.straight_until) / spec.curve_radius_m;
        const double rest = 0.5 * std::numbers::pi - turned;
        if (!(rest > 0.0)) throw std::logic_error("probe curve: turns past a right angle");
        g.path = {{g.straight_until, 0.0}, {g.L - g.straight_until, k}, {4.0 * kMm, 0.0},
                  {rest * bend_r, -1.0 / bend_r}, {3.0 * kMm, 0.0}};
        g.r_shank_end = 0.85 * kMm;
    }
    for (const Piece& x : g.path) g.path_length += x.length_m;
    return g;
}

const Geometry& geometry(ProbeKind kind) {
    static const std::array<Geometry, 5> table = [] {
        std::array<Geometry, 5> t;
        for (size_t i = 0; i < t.size(); ++i) t[i] = build_geometry(specs()[i]);
        return t;
    }();
    return table[size_t(kind)];
}

double radius_at(const Geometry& g, double u) {
    if (u <= g.u_cap) {
        const double d = g.R - u;
        return std::sqrt(std::max(0.0, g.R * g.R - d * d));
    }
    if (u <= g.L) return g.r_cap + (g.r_L - g.r_cap) * (u - g.u_cap) / (g.L - g.u_cap);
    const double f = std::min(1.0, (u - g.L) / (g.path_length - g.L));
    return g.r_L + (g.r_shank_end - g.r_L) * f;
}

Vec3 centre_at(const Geometry& g, double u, Vec3* tangent) {
    Vec3 p;
    double psi;
    walk(g.path, std::max(0.0, u), &p, &psi);
    if (tangent) *tangent = Vec3(-std::sin(psi), std::cos(psi), 0.0);
    return p;
}

// ---- Convex hull (incremental) of a small point set; used for the curved tip ----

// Points closer than `eps` (metres) in front of a face count as on it. Returns a closed, outward
// triangle mesh of the hull's vertices (in input order). Points must not all be coplanar.
TriMesh convex_hull(const std::vector<Vec3>& pts, double eps) {
    struct Face {
        std::array<uint32_t, 3> v;
        Vec3 n;
        double d;
        bool alive;
    };
    std::vector<Face> faces;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_face;  // directed edge -> face
    auto make_face = [&](uint32_t a, uint32_t b, uint32_t c) {
        const Vec3 n = glm::normalize(glm::cross(pts[b] - pts[a], pts[c] - pts[a]));
        faces.push_back({{a, b, c}, n, glm::dot(n, pts[a]), true});
        const auto f = uint32_t(faces.size() - 1);
        edge_face[{a, b}] = f;
        edge_face[{b, c}] = f;
        edge_face[{c, a}] = f;
    };
    auto front = [&](const Face& f, const Vec3& p) { return glm::dot(f.n, p) - f.d; };

    // Initial tetrahedron from extreme points.
    const auto n = uint32_t(pts.size());
    uint32_t i0 = 0, i1 = 0, i2 = 0, i3 = 0;
    for (uint32_t i = 1; i < n; ++i)
        if (pts[i].y < pts[i0].y) i0 = i;
    double best = -1;
    for (uint32_t i = 0; i < n; ++i)
        if (double d = glm::length(pts[i] - pts[i0]); d > best) best = d, i1 = i;
    best = -1;
    for (uint32_t i = 0; i < n; ++i)
        if (double d = glm::length(glm::cross(pts[i] - pts[i0], pts[i1] - pts[i0])); d > best) best = d, i2 = i;
    const Vec3 n012 = glm::cross(pts[i1] - pts[i0], pts[i2] - pts[i0]);
    best = -1;
    for (uint32_t i = 0; i < n; ++i)
        if (double d = std::abs(glm::dot(n012, pts[i] - pts[i0])); d > best) best = d, i3 = i;
    if (glm::dot(n012, pts[i3] - pts[i0]) > 0) std::swap(i1, i2);  // i3 behind face (i0, i1, i2)
    make_face(i0, i1, i2);
    make_face(i0, i3, i1);
    make_face(i1, i3, i2);
    make_face(i2, i3, i0);

    std::vector<uint32_t> visible;
    std::vector<std::pair<uint32_t, uint32_t>> horizon;
    for (uint32_t p = 0; p < n; ++p) {
        if (p == i0 || p == i1 || p == i2 || p == i3) continue;
        visible.clear();
        for (uint32_t f = 0; f < faces.size(); ++f)
            if (faces[f].alive && front(faces[f], pts[p]) > eps) visible.push_back(f);
        if (visible.empty()) continue;
        for (uint32_t f : visible) faces[f].alive = false;
        horizon.clear();
        for (uint32_t f : visible) {
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = faces[f].v[k], b = faces[f].v[(k + 1) % 3];
                if (faces[edge_face.at({b, a})].alive) horizon.push_back({a, b});
            }
        }
        for (uint32_t f : visible)
            for (int k = 0; k < 3; ++k) edge_face.erase({faces[f].v[k], faces[f].v[(k + 1) % 3]});
        for (const auto& [a, b] : horizon) make_face(a, b, p);
    }

    TriMesh out;
    std::vector<int64_t> remap(n, -1);
    for (const Face& f : faces)
        if (f.alive)
            for (uint32_t v : f.v) remap[v] = 0;
    for (uint32_t i = 0; i < n; ++i)
        if (remap[i] == 0) {
            remap[i] = int64_t(out.vertices.size());
            out.vertices.push_back(pts[i]);
        }
    for (const Face& f : faces)
        if (f.alive) out.triangles.push_back({uint32_t(remap[f.v[0]]), uint32_t(remap[f.v[1]]), uint32_t(remap[f.v[2]])});
    return out;
}

// ---- Sweeps: rings of `sides` vertices around a centreline, closed by poles or flat caps ----

struct Ring {
    Vec3 centre;
    Vec3 tangent;   // unit, in the XY plane
    double radius;  // 0: a single vertex (pole)
};

Vec3 ring_point(const Ring& r, int j, int sides) {
    const Vec3 n(-r.tangent.y, r.tangent.x, 0.0);  // Z x tangent: (n, Z, tangent) is right-handed
    const double th = 2.0 * std::numbers::pi * j / sides;
    return r.centre + r.radius * (std::cos(th) * n + std::sin(th) * Vec3(0.0, 0.0, 1.0));
}

// Appends one closed tube: first and last rings may be poles (radius 0), else flat caps.
// `inward` flips the winding (the inner wall of a ring mark).
void add_tube(TriMesh& m, const std::vector<Ring>& rings, int sides, bool caps = true, bool inward = false,
              std::vector<uint32_t>* first_ring = nullptr, std::vector<uint32_t>* last_ring = nullptr) {
    std::vector<std::vector<uint32_t>> idx(rings.size());
    for (size_t i = 0; i < rings.size(); ++i) {
        if (rings[i].radius == 0.0) {
            idx[i].assign(size_t(sides), uint32_t(m.vertices.size()));
            m.vertices.push_back(rings[i].centre);
        } else {
            for (int j = 0; j < sides; ++j) {
                idx[i].push_back(uint32_t(m.vertices.size()));
                m.vertices.push_back(ring_point(rings[i], j, sides));
            }
        }
    }
    auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (a == b || b == c || a == c) return;
        if (inward) std::swap(b, c);
        m.triangles.push_back({a, b, c});
    };
    for (size_t i = 0; i + 1 < rings.size(); ++i) {
        for (int j = 0; j < sides; ++j) {
            const int k = (j + 1) % sides;
            tri(idx[i][j], idx[i][k], idx[i + 1][k]);
            tri(idx[i][j], idx[i + 1][k], idx[i + 1][j]);
        }
    }
    if (caps) {
        if (rings.front().radius != 0.0) {
            const auto c = uint32_t(m.vertices.size());
            m.vertices.push_back(rings.front().centre);
            for (int j = 0; j < sides; ++j) tri(c, idx.front()[(j + 1) % sides], idx.front()[j]);
        }
        if (rings.back().radius != 0.0) {
            const auto c = uint32_t(m.vertices.size());
            m.vertices.push_back(rings.back().centre);
            for (int j = 0; j < sides; ++j) tri(c, idx.back()[j], idx.back()[(j + 1) % sides]);
        }
    }
    if (first_ring) *first_ring = idx.front();
    if (last_ring) *last_ring = idx.back();
}

// A closed ring mark: outer wall `proud` outside the body, inner wall `depth` inside, annular ends.
void add_mark(TriMesh& m, const std::vector<Ring>& body_rings, double proud, double depth, int sides) {
    std::vector<Ring> outer = body_rings, inner = body_rings;
    for (Ring& r : outer) r.radius += proud;
    for (Ring& r : inner) r.radius -= depth;
    std::vector<uint32_t> o0, o1, i0, i1;
    add_tube(m, outer, sides, false, false, &o0, &o1);
    add_tube(m, inner, sides, false, true, &i0, &i1);
    for (int j = 0; j < sides; ++j) {
        const int k = (j + 1) % sides;
        // Start end faces -tangent, far end +tangent.
        m.triangles.push_back({o0[j], i0[j], i0[k]});
        m.triangles.push_back({o0[j], i0[k], o0[k]});
        m.triangles.push_back({o1[j], o1[k], i1[k]});
        m.triangles.push_back({o1[j], i1[k], i1[j]});
    }
}

Ring ring_at(const Geometry& g, double u) {
    Ring r;
    r.centre = centre_at(g, u, &r.tangent);
    r.radius = radius_at(g, u);
    return r;
}

// Tip-cap rings from the pole (inclusive) to the end of the cap, `rings` steps of equal angle
// ending at phi_end; every other body ring is a collision ring (same angle bits: k*phi/n).
std::vector<Ring> cap_rings(const Geometry& g, double phi_end, int rings, int step) {
    std::vector<Ring> out;
    out.push_back({Vec3(0.0), Vec3(0, 1, 0), 0.0});
    for (int k = step; k <= rings; k += step) {
        const double phi = cap_angle(phi_end, k, rings);
        out.push_back({Vec3(0.0, g.R * (1.0 - std::cos(phi)), 0.0), Vec3(0, 1, 0), g.R * std::sin(phi)});
    }
    return out;
}

// Distances from the tip end at which the body has rings beyond the cap.
std::vector<double> body_ring_u(const Geometry& g) {
    std::vector<double> u;
    double at = 0.0;
    for (const Piece& p : g.path) {
        const double end = at + p.length_m;
        if (p.kappa_per_m != 0.0) {
            const double step = std::min(kArcStep_m, kBendStep_rad / std::abs(p.kappa_per_m));
            const int n = std::max(1, int(std::ceil(p.length_m / step - 1e-9)));
            for (int i = 0; i <= n; ++i) u.push_back(at + p.length_m * i / n);
        } else {
            u.push_back(at);
            u.push_back(end);
        }
        at = end;
    }
    u.push_back(g.L);
    std::sort(u.begin(), u.end());
    std::vector<double> out;
    for (double v : u)
        if (v > g.u_cap + 1e-9 && (out.empty() || v - out.back() > 1e-9)) out.push_back(v);
    return out;
}

nlohmann::json mesh_json(const TriMesh& m) {
    nlohmann::json v = nlohmann::json::array(), t = nlohmann::json::array();
    for (const Vec3& p : m.vertices) v.push_back({p.x, p.y, p.z});
    for (const auto& tr : m.triangles) t.push_back({tr[0], tr[1], tr[2]});
    return {{"vertices_m", v}, {"triangles", t}};
}

int add_material(Asset& asset, const Material& mat) {
    for (size_t i = 0; i < asset.materials.size(); ++i)
        if (asset.materials[i] == mat) return int(i);
    asset.materials.push_back(mat);
    return int(asset.materials.size() - 1);
}

}  // namespace

bool parse_probe_kind(const std::string& name, ProbeKind* out) {
    for (ProbeKind k : kAllProbeKinds) {
        if (name == probe_kind_name(k)) {
            if (out) *out = k;
            return true;
        }
    }
    return false;
}

const char* probe_kind_name(ProbeKind kind) {
    switch (kind) {
        case ProbeKind::Williams: return "williams";
        case ProbeKind::Unc15: return "unc15";
        case ProbeKind::Cpi: return "cpi";
        case ProbeKind::Marquis: return "marquis";
        case ProbeKind::Nabers: return "nabers";
    }
    return "unknown";
}

const std::vector<Material>& probe_materials() {
    static const std::vector<Material> m = {
        {"probe steel", {0.78, 0.78, 0.80, 1.0}, 1.0, 0.25},
        {"probe handle", {0.70, 0.71, 0.73, 1.0}, 1.0, 0.55},
        {"probe mark black", {0.02, 0.02, 0.02, 1.0}, 0.0, 0.4},
    };
    return m;
}

const ProbeSpec& probe_spec(ProbeKind kind) { return specs()[size_t(kind)]; }

Vec3 probe_centreline(const ProbeSpec& spec, double u_m, Vec3* tangent) {
    return centre_at(geometry(spec.kind), u_m, tangent);
}

double probe_body_radius(const ProbeSpec& spec, double u_m) { return radius_at(geometry(spec.kind), u_m); }

namespace {

// Fewest sides, a divisor of the body's 48 (same azimuths), whose polygon stays within
// kPieceRadialTol_m of a circle of radius r.
int piece_sides(double r) {
    for (int n : {12, 16, 24}) {
        if (r * (1.0 - std::cos(std::numbers::pi / n)) <= kPieceRadialTol_m) return n;
    }
    return kBodySides;
}

// A convex piece: the hull of some rings, each with `sides` vertices on the body's azimuths.
TriMesh ring_hull(const std::vector<Ring>& rings, int sides) {
    std::vector<Vec3> pts;
    for (const Ring& r : rings)
        for (int j = 0; j < sides; ++j) pts.push_back(ring_point(r, j, sides));
    return convex_hull(pts, 1e-14);
}

// Handle rings in the probe frame, around the axis leaving the shank's end.
std::vector<Ring> handle_rings(const Geometry& g, const HandleRing* from, const HandleRing* to) {
    Vec3 t_h;
    const Vec3 e = centre_at(g, g.path_length, &t_h);
    std::vector<Ring> out;
    for (const HandleRing* h = from; h != to; ++h) out.push_back({e + (h->a_mm * kMm) * t_h, t_h, h->r_mm * kMm});
    return out;
}

}  // namespace

TriMesh make_probe_tip_collision(ProbeKind kind) {
    const ProbeSpec& spec = probe_spec(kind);
    const Geometry& g = geometry(kind);
    const double Lc = spec.collision_length_m;
    TriMesh m;
    if (spec.curve_radius_m == 0.0) {
        // Cap up to where the tangent from the top ring touches the tip sphere, then the frustum.
        // For tapered tips this is the body's own profile; for the ball it bridges the neck.
        const double r_top = radius_at(g, Lc);
        const double phi = spec.ball_tip ? tangent_angle(g.R, r_top, Lc) : g.phi_cap;
        std::vector<Ring> rings = cap_rings(g, phi, kBodyCapRings, kBodyCapRings / kCollisionCapRings);
        rings.push_back({Vec3(0.0, Lc, 0.0), Vec3(0, 1, 0), r_top});
        add_tube(m, rings, kCollisionSides);
        return m;
    }
    // Curved: convex hull of the cap and of body rings (every other one) along the distal piece.
    std::vector<Vec3> pts;
    for (const Ring& r : cap_rings(g, g.phi_cap, kBodyCapRings, kBodyCapRings / kCollisionCapRings)) {
        if (r.radius == 0.0) pts.push_back(r.centre);
        else
            for (int j = 0; j < kCollisionSides; ++j) pts.push_back(ring_point(r, j, kCollisionSides));
    }
    // Body ring distances past the straight tip, every third one (0.75 mm), and the far end.
    std::vector<double> chosen;
    int count = 0;
    for (double u : body_ring_u(g))
        if (u > g.straight_until + 1e-9 && u < Lc - 1e-9 && ++count % 3 == 0) chosen.push_back(u);
    chosen.push_back(Lc);
    for (double u : chosen) {
        const Ring r = ring_at(g, u);
        for (int j = 0; j < kCollisionSides; ++j) pts.push_back(ring_point(r, j, kCollisionSides));
    }
    return convex_hull(pts, 1e-14);
}

std::vector<TriMesh> make_probe_collision_pieces(ProbeKind kind) {
    const ProbeSpec& spec = probe_spec(kind);
    const Geometry& g = geometry(kind);
    std::vector<TriMesh> pieces = {make_probe_tip_collision(kind)};
    // The rest of the working end and the shank, path piece by path piece from the tip piece's end:
    // a frustum per straight run; a curve cut into pieces short enough that the chord between two
    // rings stays within kPieceChordTol_m of the arc on its outer (and inner) side.
    double at = 0.0;
    for (const Piece& p : g.path) {
        const double lo = std::max(at, spec.collision_length_m), hi = at + p.length_m;
        at = hi;
        if (hi <= lo + 1e-12) continue;
        const double r_max = std::max(radius_at(g, lo), radius_at(g, hi));
        int n = 1;
        if (p.kappa_per_m != 0.0) {
            const double bend_r = 1.0 / std::abs(p.kappa_per_m);
            const double half = std::acos(1.0 - kPieceChordTol_m / (bend_r + r_max));
            n = std::max(1, int(std::ceil((hi - lo) * std::abs(p.kappa_per_m) / (2.0 * half) - 1e-9)));
        }
        const int sides = piece_sides(r_max);
        for (int k = 0; k < n; ++k)
            pieces.push_back(ring_hull({ring_at(g, lo + (hi - lo) * k / n), ring_at(g, lo + (hi - lo) * (k + 1) / n)}, sides));
    }
    // The handle: the ferrule's two frustums and the grip on the drawn grip's own facets.
    for (int k = 0; k + 1 < int(std::size(kFerrule)); ++k) {
        const std::vector<Ring> rings = handle_rings(g, &kFerrule[k], &kFerrule[k + 2]);
        pieces.push_back(ring_hull(rings, piece_sides(std::max(rings[0].radius, rings[1].radius))));
    }
    pieces.push_back(ring_hull(handle_rings(g, std::begin(kGrip), std::end(kGrip)), kGripSides));
    return pieces;
}

TriMesh make_probe_collision(ProbeKind kind) {
    TriMesh all;
    for (const TriMesh& piece : make_probe_collision_pieces(kind)) {
        const auto base = uint32_t(all.vertices.size());
        all.vertices.insert(all.vertices.end(), piece.vertices.begin(), piece.vertices.end());
        for (const auto& t : piece.triangles) all.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    return all;
}

AssetNode make_probe_node(ProbeKind kind, Asset& asset) {
    const ProbeSpec& spec = probe_spec(kind);
    const Geometry& g = geometry(kind);
    AssetNode node;
    node.name = std::string("probe ") + probe_kind_name(kind);
    const std::vector<Material>& mats = probe_materials();

    // Body: tip cap, working end and shank as one sweep.
    std::vector<Ring> rings = cap_rings(g, g.phi_cap, kBodyCapRings, 1);
    const std::vector<double> us = body_ring_u(g);
    for (double u : us) rings.push_back(ring_at(g, u));
    MeshPart body;
    add_tube(body.mesh, rings, kBodySides);
    body.material = add_material(asset, mats[kProbeSteel]);
    node.parts.push_back(std::move(body));

    // Handle along the shank's final direction: a smooth ferrule cone, then a faceted grip.
    MeshPart handle;
    add_tube(handle.mesh, handle_rings(g, std::begin(kFerrule), std::end(kFerrule)), kBodySides);
    add_tube(handle.mesh, handle_rings(g, std::begin(kGrip), std::end(kGrip)), kGripSides);
    handle.material = add_material(asset, mats[kProbeHandle]);
    node.parts.push_back(std::move(handle));

    // Marks, one part per colour: rings that follow the body (and the Nabers curve).
    std::vector<int> colours;
    for (const ProbeMark& mk : spec.marks)
        if (std::find(colours.begin(), colours.end(), mk.material) == colours.end()) colours.push_back(mk.material);
    nlohmann::json bands = nlohmann::json::array();
    for (int colour : colours) {
        MeshPart part;
        for (const ProbeMark& mk : spec.marks) {
            if (mk.material != colour) continue;
            std::vector<Ring> mr = {ring_at(g, mk.from_m)};
            for (double u : us)
                if (u > mk.from_m + 1e-6 && u < mk.to_m - 1e-6) mr.push_back(ring_at(g, u));
            mr.push_back(ring_at(g, mk.to_m));
            add_mark(part.mesh, mr, kProbeMarkProud_m, kMarkDepth_m, kBodySides);
        }
        part.material = add_material(asset, mats[size_t(colour)]);
        node.parts.push_back(std::move(part));
    }
    for (const ProbeMark& mk : spec.marks) bands.push_back({mk.from_m / kMm, mk.to_m / kMm});

    nlohmann::json marks_mm = nlohmann::json::array();
    for (double v : spec.graduations_m) marks_mm.push_back(v / kMm);
    const std::vector<TriMesh> pieces = make_probe_collision_pieces(kind);
    nlohmann::json coll = mesh_json(make_probe_collision(kind));
    coll["shape"] = "convex pieces (connected components): the working tip, the rest of the working end, the shank "
                    "and the handle";
    coll["pieces"] = pieces.size();
    coll["tip"] = spec.curve_radius_m == 0.0 ? "tip sphere cap and tangent frustum"
                                              : "convex hull of the distal curved working end";
    coll["length_m"] = spec.collision_length_m;
    node.extras = {{"probe", probe_kind_name(kind)},
                   {"display_name", spec.display_name},
                   {"tip_diameter_m", spec.tip_diameter_m},
                   {"ball_tip", spec.ball_tip},
                   {"working_length_m", spec.working_length_m},
                   {"marks_mm", marks_mm},
                   {"bands_mm", bands},
                   {"frame", "origin at the tip end, +Y along the working end toward the handle, bends in XY"},
                   {"collision", coll}};
    return node;
}

}  // namespace sulcus
