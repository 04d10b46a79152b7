// Building a case from a chart: teeth on the arch, the tables that shape gingiva and bone around
// each tooth, the site frames, and the gingiva and bone meshes (docs/cases.md).
//
// The gingiva of a jaw is an implicit solid: around each tooth a collar (outer surface, margin at
// the charted height, a flat bottom) kept on its side of the planes halfway to the neighbours, the
// collars of a jaw joined with a rounded seam (which fills the embrasures with papillae), then, for
// each tooth, the pocket cut out of it: the space between the tooth's outline and the inner wall of
// the gingiva, from the margin down to the floor: the onset of the site tissue's yielding layer,
// depth_at(0.25 N) above the charted floor (docs/tissue.md). The inner wall stands where a straight
// probe held parallel to the long axis just clears the tooth near the margin, widened at each site
// so the probe clears the whole crown there. Furcations of grade 2 and more open a tunnel between
// the roots.
#include "case_geometry.h"

#include "sulcus/content/polygonize.h"
#include "sulcus/content/tooth_asset.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

namespace sulcus {

namespace cd = case_detail;
using json = nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;

// Shape of the gingiva and bone (metres).
constexpr double kMarginThickness = 0.6e-3;   // gingiva at the margin, beyond the inner wall
constexpr double kThickening = 0.35;          // outer surface leans out this much per metre down
constexpr double kTopRounding = 0.35e-3;      // rounding of the outer edge of the margin
constexpr double kMarginRounding = 0.08e-3;   // rounding of the margin's inner edge
constexpr double kFloorRounding = 0.12e-3;    // fillet where the pocket floor meets the inner wall
constexpr double kUnionRounding = 0.5e-3;     // papillae: seam between neighbouring collars
constexpr double kBelowApex = 1.5e-3;         // the gingiva block ends this far below the longest root
constexpr double kThickeningDepth = 5e-3;     // the outer surface leans out down to this depth
constexpr double kHullInset = 0.05e-3;        // the pocket starts this far inside the tooth outline
constexpr double kCrestBelowFloor = 1.5e-3;   // alveolar crest below the charted pocket floor
constexpr double kBoneInset = 0.8e-3;         // bone surface inside the gingiva's outer surface
constexpr double kLigament = 0.2e-3;          // periodontal ligament space around the root
constexpr double kNearMargin = 0.5e-3;        // the inner wall clears the tooth up to this above the margin
constexpr double kFloorHalfWidth = 0.6e-3;    // largest half-width of a floor layer along the pocket
constexpr double kFloorLayerGap = 0.05e-3;    // kept between a floor layer and the next site's
constexpr double kFloorLayerReach = 0.5e-3;   // how far a layer reaches past the probe into tooth and wall
constexpr double kMinPocket = 0.2e-3;         // the floor stays at least this far below the margin
constexpr double kSiteSearchStep = kPi / 180.0;
constexpr int kSiteSearchSteps = 40;

double wrap_angle(double theta) {
    double t = std::fmod(theta, kTwoPi);
    if (t < 0.0) t += kTwoPi;
    return t;
}

double angle_of(int i) { return kTwoPi * double(i) / double(cd::kAngles); }

// Arch: z = -depth (x / half_width)^2 through the incisal midline (z = 0), metres.
struct Arch {
    double half_width, depth;
    double z(double x) const { return -depth * (x / half_width) * (x / half_width); }
    double dz(double x) const { return -2.0 * depth * x / (half_width * half_width); }
    // x >= 0 at arc length s from the midline.
    double x_at(double s) const {
        double lo = 0.0, hi = s;
        auto arc = [&](double x) {
            // Closed form of the parabola's arc length from 0 to x.
            const double a = 2.0 * depth / (half_width * half_width);
            const double ax = a * x;
            return 0.5 * x * std::sqrt(1.0 + ax * ax) + std::asinh(ax) / (2.0 * a);
        };
        for (int i = 0; i < 100; ++i) {
            const double mid = 0.5 * (lo + hi);
            (arc(mid) < s ? lo : hi) = mid;
        }
        return 0.5 * (lo + hi);
    }
};

constexpr double kContactGap = 0.2e-3;  // between neighbouring crowns on the arch

}  // namespace

Vec3 ToothPlacement::to_case(const Vec3& p) const {
    return position + rotation * (mirror ? Vec3(-p.x, p.y, p.z) : p);
}

Vec3 ToothPlacement::to_case_direction(const Vec3& d) const { return rotation * (mirror ? Vec3(-d.x, d.y, d.z) : d); }

Vec3 ToothPlacement::to_tooth(const Vec3& q) const {
    Vec3 l = glm::conjugate(rotation) * (q - position);
    if (mirror) l.x = -l.x;
    return l;
}

ToothPlacement arch_placement(int fdi) {
    const ToothDimensions& d = tooth_dimensions(fdi);
    const int quadrant = fdi / 10, pos = fdi % 10;
    const bool upper = quadrant == 1 || quadrant == 2;
    const bool left = quadrant == 2 || quadrant == 3;  // patient's left: +x
    const Arch arch = upper ? Arch{0.026, 0.0315} : Arch{0.023, 0.028};
    double s = 0.5 * kContactGap;
    for (int p = 1; p < pos; ++p) s += tooth_dimensions(quadrant * 10 + p).crown_md_mm * 1e-3 + kContactGap;
    s += 0.5 * d.crown_md_mm * 1e-3;
    const double x = (left ? 1.0 : -1.0) * arch.x_at(s);
    const Vec3 distal = glm::normalize(Vec3(left ? 1.0 : -1.0, 0.0, (left ? 1.0 : -1.0) * arch.dz(x)));
    const Vec3 buccal = glm::normalize(Vec3(-arch.dz(x), 0.0, 1.0));
    const Vec3 occlusal(0.0, upper ? -1.0 : 1.0, 0.0);
    glm::dmat3 a(-distal, occlusal, buccal);  // columns: where the tooth's X, Y, Z go
    ToothPlacement pl;
    pl.fdi = fdi;
    pl.position = Vec3(x, upper ? kUpperCejHeight : 0.0, arch.z(x));
    pl.mirror = glm::determinant(a) < 0.0;
    if (pl.mirror) a[0] = -a[0];
    pl.rotation = glm::normalize(glm::quat_cast(a));
    return pl;
}

namespace case_detail {

double AngleTable::at(double theta) const {
    const double u = wrap_angle(theta) / kTwoPi * double(kAngles);
    const int i0 = std::min(int(u), kAngles - 1);
    const double f = u - double(i0);
    return v[size_t(i0)] * (1.0 - f) + v[size_t((i0 + 1) % kAngles)] * f;
}

double ToothTables::hull_at(double theta, double y) const {
    const double r = (y - hull_y0) / hull_dy;
    if (r < 0.0 || r > double(hull_rows - 1)) return 0.0;
    const int j0 = std::min(int(r), hull_rows - 2);
    const double g = r - double(j0);
    const double u = wrap_angle(theta) / kTwoPi * double(kAngles);
    const int i0 = std::min(int(u), kAngles - 1), i1 = (i0 + 1) % kAngles;
    const double f = u - double(i0);
    auto h = [&](int j, int i) { return double(hull[size_t(j) * kAngles + size_t(i)]); };
    const double a = h(j0, i0) * (1.0 - f) + h(j0, i1) * f;
    const double b = h(j0 + 1, i0) * (1.0 - f) + h(j0 + 1, i1) * f;
    return a * (1.0 - g) + b * g;
}

double Tunnel::field(const Vec3& p) const {
    const Vec3 q = p - entrance;
    const double d = q.x * inward.x + q.z * inward.z;
    const double l = q.x * across.x + q.z * across.z;
    return std::max({d - depth, -outer - d, std::abs(l) - half_width, p.y - y_high, y_low - p.y});
}

double site_interpolate(const std::array<double, 6>& site_theta_in, const std::array<double, 6>& values, double theta) {
    // Sites in increasing angle; between two consecutive ones a smoothstep, flat at both.
    std::array<double, 6> site_theta;
    for (size_t i = 0; i < 6; ++i) site_theta[i] = wrap_angle(site_theta_in[i]);
    std::array<int, 6> order{0, 1, 2, 3, 4, 5};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return site_theta[size_t(a)] < site_theta[size_t(b)]; });
    const double t = wrap_angle(theta);
    for (int k = 0; k < 6; ++k) {
        const int a = order[size_t(k)], b = order[size_t((k + 1) % 6)];
        const double ta = site_theta[size_t(a)];
        double span = site_theta[size_t(b)] - ta;
        if (span <= 0.0) span += kTwoPi;
        double off = t - ta;
        if (off < 0.0) off += kTwoPi;
        if (off <= span) {
            const double u = off / span;
            const double w = u * u * (3.0 - 2.0 * u);
            return values[size_t(a)] + (values[size_t(b)] - values[size_t(a)]) * w;
        }
    }
    return values[size_t(order[0])];
}

namespace {

struct Local {
    Vec3 p;       // tooth frame
    double r, theta;
};

Local local_of(const ToothTables& t, const Vec3& p) {
    Local l;
    l.p = t.placement.to_tooth(p);
    l.r = std::sqrt(l.p.x * l.p.x + l.p.z * l.p.z);
    l.theta = std::atan2(l.p.z, l.p.x);
    return l;
}

double collar(const ToothTables& t, const Local& l, const Vec3& p, double inset) {
    const double ym = t.margin.at(l.theta);
    const double rout = t.outer.at(l.theta) - inset + kThickening * std::clamp(ym - l.p.y, 0.0, kThickeningDepth);
    double f = smooth_max(l.r - rout, l.p.y - ym, kTopRounding);
    f = std::max(f, t.bottom + inset - l.p.y);
    for (const auto& [point, normal] : t.cuts) f = std::max(f, glm::dot(p - point, normal));
    return f;
}

// Negative inside the pocket of this tooth.
double pocket(const ToothTables& t, const Local& l) {
    const double yf = t.floor.at(l.theta);
    const double wall = l.r - t.slot.at(l.theta);
    const double floor = yf - l.p.y;
    const double inner = (t.hull_at(l.theta, l.p.y) - kHullInset) - l.r;
    return std::max(smooth_max(wall, floor, kFloorRounding), inner);
}

}  // namespace

double gum_field(const std::vector<ToothTables>& jaw, const Vec3& p) {
    double f = 1.0;  // far outside (finite: the smooth union mixes it)
    for (const ToothTables& t : jaw) {
        const Local l = local_of(t, p);
        if (l.r > t.reach) {
            f = std::min(f, l.r - t.reach + 1e-3);
            continue;
        }
        f = smooth_min(f, collar(t, l, p, 0.0), kUnionRounding);
    }
    for (const ToothTables& t : jaw) {
        const Local l = local_of(t, p);
        if (l.r > t.reach) continue;
        f = smooth_max(f, -pocket(t, l), kMarginRounding);
        for (const Tunnel& tn : t.tunnels) f = std::max(f, -tn.field(l.p));
    }
    return f;
}

double bone_field(const std::vector<ToothTables>& jaw, const Vec3& p) {
    double f = 1.0;  // far outside (finite: the smooth union mixes it)
    for (const ToothTables& t : jaw) {
        const Local l = local_of(t, p);
        if (l.r > t.reach) {
            f = std::min(f, l.r - t.reach + 1e-3);
            continue;
        }
        double c = collar(t, l, p, kBoneInset);
        c = std::max(c, l.p.y - (t.charted_floor.at(l.theta) - kCrestBelowFloor));
        f = smooth_min(f, c, kUnionRounding);
    }
    for (const ToothTables& t : jaw) {
        const Local l = local_of(t, p);
        if (l.r > t.reach) continue;
        f = std::max(f, kLigament - t.shape->field(l.p));
        for (const Tunnel& tn : t.tunnels) f = std::max(f, -tn.field(l.p));
    }
    return f;
}

}  // namespace case_detail

namespace {

using cd::ToothTables;

// The 2D convex hull (x, z) of points, counter-clockwise (monotone chain).
std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> pts) {
    std::sort(pts.begin(), pts.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
        return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    if (pts.size() < 3) return pts;
    std::vector<glm::dvec2> h(2 * pts.size());
    size_t k = 0;
    auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
        return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    };
    for (size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0.0) --k;
        h[k++] = pts[i];
    }
    for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0.0) --k;
        h[k++] = pts[i];
    }
    h.resize(k - 1);
    return h;
}

// Largest distance from the origin along direction (cos t, sin t) to the hull boundary (0 if missed).
double hull_radius(const std::vector<glm::dvec2>& hull, double theta) {
    const glm::dvec2 d(std::cos(theta), std::sin(theta));
    double best = 0.0;
    for (size_t i = 0; i < hull.size(); ++i) {
        const glm::dvec2 a = hull[i], b = hull[(i + 1) % hull.size()];
        const glm::dvec2 e = b - a;
        const double den = d.x * e.y - d.y * e.x;
        if (std::abs(den) < 1e-18) continue;
        const double s = (a.x * e.y - a.y * e.x) / den;     // along the ray
        const double u = (a.x * d.y - a.y * d.x) / den;     // along the edge
        if (s > 0.0 && u >= -1e-12 && u <= 1.0 + 1e-12) best = std::max(best, s);
    }
    return best;
}

void fill_hull(ToothTables& t, const TriMesh& mesh) {
    double ylo = 1e9, yhi = -1e9;
    for (const Vec3& v : mesh.vertices) {
        ylo = std::min(ylo, v.y);
        yhi = std::max(yhi, v.y);
    }
    t.hull_dy = 1e-4;
    t.hull_y0 = ylo;
    t.hull_rows = int(std::ceil((yhi - ylo) / t.hull_dy)) + 1;
    t.hull.assign(size_t(t.hull_rows) * cd::kAngles, 0.0f);
    // Bucket triangles by the rows they span.
    std::vector<std::vector<uint32_t>> rows(size_t(t.hull_rows));
    for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& tri = mesh.triangles[i];
        double a = 1e9, b = -1e9;
        for (uint32_t v : tri) {
            a = std::min(a, mesh.vertices[v].y);
            b = std::max(b, mesh.vertices[v].y);
        }
        const int j0 = std::max(0, int(std::ceil((a - t.hull_y0) / t.hull_dy)));
        const int j1 = std::min(t.hull_rows - 1, int(std::floor((b - t.hull_y0) / t.hull_dy)));
        for (int j = j0; j <= j1; ++j) rows[size_t(j)].push_back(i);
    }
    std::vector<glm::dvec2> pts;
    for (int j = 0; j < t.hull_rows; ++j) {
        const double y = t.hull_y0 + t.hull_dy * j;
        pts.clear();
        for (uint32_t i : rows[size_t(j)]) {
            const auto& tri = mesh.triangles[i];
            for (int k = 0; k < 3; ++k) {
                const Vec3& a = mesh.vertices[tri[size_t(k)]];
                const Vec3& b = mesh.vertices[tri[size_t((k + 1) % 3)]];
                if ((a.y - y) * (b.y - y) > 0.0 || a.y == b.y) continue;
                const double s = (y - a.y) / (b.y - a.y);
                pts.emplace_back(a.x + (b.x - a.x) * s, a.z + (b.z - a.z) * s);
            }
        }
        if (pts.size() < 3) continue;
        const auto hull = convex_hull(pts);
        for (int i = 0; i < cd::kAngles; ++i)
            t.hull[size_t(j) * cd::kAngles + size_t(i)] = float(hull_radius(hull, angle_of(i)));
    }
}

// The probe's radius at a height above its tip end plus a clearance.
struct ProbeClearance {
    const std::vector<double>* profile;
    double step, radius, clearance;
    double at(double height) const {
        if (profile->empty()) return radius + clearance;
        // The sample at or above the height: the profile never decreases.
        const double u = std::max(0.0, height) / step;
        const size_t i = std::min(size_t(std::ceil(u)), profile->size() - 1);
        return (*profile)[i] + clearance;
    }
};

// Smallest radius along theta at which a vertical probe with its tip end at height `tip_y` keeps
// its clearance from every point of `pts` (tooth frame) with y in [tip_y - radius, yhi].
double line_clearance(const std::vector<Vec3>& pts, double theta, double tip_y, double yhi, const ProbeClearance& pc) {
    const double c = std::cos(theta), s = std::sin(theta);
    double r = 0.0;
    for (const Vec3& p : pts) {
        if (p.y < tip_y - pc.radius || p.y > yhi) continue;
        const double clear = pc.at(p.y - tip_y);
        const double along = p.x * c + p.z * s;
        const double side = -p.x * s + p.z * c;
        if (std::abs(side) >= clear) continue;
        r = std::max(r, along + std::sqrt(clear * clear - side * side));
    }
    return r;
}

// Whether the vertical probe at (r, theta) with its tip end at tip_y keeps its clearance from
// every point with y above its tip.
bool line_clear_of(const std::vector<Vec3>& pts, double r, double theta, double tip_y, const ProbeClearance& pc) {
    const double lx = r * std::cos(theta), lz = r * std::sin(theta);
    for (const Vec3& p : pts)
        if (p.y >= tip_y - pc.radius && std::hypot(p.x - lx, p.z - lz) < pc.at(p.y - tip_y)) return false;
    return true;
}

double site_target_angle(Site s) {
    return (s == Site::MB || s == Site::B || s == Site::DB) ? 0.5 * kPi : -0.5 * kPi;
}

struct Built {
    ToothTables tables;
    std::unique_ptr<ToothShape> shape;
    TriMesh fine;   // polygonized tooth, tooth frame
    TriMesh mesh;   // decimated
    std::array<double, 6> theta{}, probe_r{};
    // Heights (tooth frame) at each site: margin, onset of the yielding floor (the gingiva's
    // floor), charted floor (tip at 0.25 N) and the tip at 0.5 N.
    std::array<double, 6> margin{}, floor{}, rest{}, deep{};
    std::array<Tissue, 6> tissue{};
};

// Each site's floor layer: a box under the probe's line with its flat top at the onset, reaching
// past the probe into the tooth and the pocket wall (objects may overlap; the probe is never
// there), along the pocket up to half way to the next site, and down past the gingiva's own floor.
// Outward triangles in the case frame (mirrored placements too).
void add_floor_layers(PatientCase& c, double probe_radius_m) {
    for (SiteFrame& f : c.sites) {
        double nearest = 1.0;
        for (const SiteFrame& o : c.sites) {
            if (&o == &f || (o.fdi / 10 <= 2) != (f.fdi / 10 <= 2)) continue;
            nearest = std::min(nearest, glm::length(o.onset_point - f.onset_point));
        }
        f.floor_half_width_m = std::max(probe_radius_m + 0.05e-3, std::min(kFloorHalfWidth, 0.5 * nearest - kFloorLayerGap));
        const Vec3 u = f.outward, y = f.axis, v = glm::normalize(glm::cross(y, u));
        const double ru = probe_radius_m + kFloorLayerReach, rv = f.floor_half_width_m;
        const double down = kFloorLayerDepth + 0.3e-3;
        TriMesh box;
        for (int k = 0; k < 8; ++k)
            box.vertices.push_back(f.onset_point + ((k & 1) ? ru : -ru) * u + ((k & 2) ? rv : -rv) * v +
                                   ((k & 4) ? 0.0 : -down) * y);
        // Quads of the cube on corner bits (x = bit 0, y = bit 1, z = bit 2), outward for a
        // right-handed (u, v, y).
        const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
        for (const auto& q : quads) {
            box.triangles.push_back({uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])});
            box.triangles.push_back({uint32_t(q[0]), uint32_t(q[2]), uint32_t(q[3])});
        }
        if (mesh_volume(box) < 0.0)
            for (auto& t : box.triangles) std::swap(t[1], t[2]);
        c.solids.push_back({"floor_" + std::to_string(f.fdi) + "_" + site_name(f.site), box});
    }
}

json tissue_json(const Tissue& t) {
    if (t.is_preset) return tissue_preset_name(t.preset);
    json pts = json::array();
    for (const auto& [force, depth] : t.custom.points_N_mm) pts.push_back({force, depth});
    return {{"yield_curve_N_mm", pts}};
}

json site_json(const SiteFrame& f) {
    auto v = [](const Vec3& x) { return json::array({x.x, x.y, x.z}); };
    return {{"fdi", f.fdi}, {"site", site_name(f.site)}, {"theta_rad", f.theta_rad},
            {"margin_point", v(f.margin_point)}, {"floor_point", v(f.floor_point)}, {"axis", v(f.axis)},
            {"outward", v(f.outward)}, {"pd_mm", f.pd_m * 1e3}, {"gm_mm", f.gm_m * 1e3},
            {"tissue", tissue_json(f.tissue)}, {"onset_point", v(f.onset_point)},
            {"floor_half_width_m", f.floor_half_width_m},
            // Margin to tip along the axis at 0.25 N, and how much further it goes at 0.5 N.
            {"depth_at_0_25_N_mm", f.rest_depth_m * 1e3},
            {"extra_depth_at_0_5_N_mm",
             f.tissue.curve().depth_mm_at(kFirmProbeForce_N) - f.tissue.curve().depth_mm_at(kRestingProbeForce_N)}};
}

// The visual asset: each tooth as enamel and root surfaces (split at the CEJ), gingiva and bone.
void fill_case_asset(PatientCase& c, const std::vector<Built>& built) {
    Asset& a = c.asset;
    a.materials = case_materials();
    a.extras = {{"format", "sulcus.case/1"}, {"chart", chart_to_json(c.chart)}, {"sites", json::array()}};
    for (const SiteFrame& f : c.sites) a.extras["sites"].push_back(site_json(f));
    for (const Built& b : built) {
        const ToothPlacement& pl = b.tables.placement;
        AssetNode node;
        node.name = "tooth " + std::to_string(pl.fdi);
        const auto parts = tooth_parts(b.mesh, *b.shape, &pl);
        node.parts.assign(parts.begin(), parts.end());
        node.extras = {{"fdi", pl.fdi},
                       {"universal", universal_number(pl.fdi)},
                       {"tooth_frame",
                        {{"position", {pl.position.x, pl.position.y, pl.position.z}},
                         {"orientation", {pl.rotation.w, pl.rotation.x, pl.rotation.y, pl.rotation.z}},
                         {"mirror", pl.mirror}}},
                       {"sites", json::array()}};
        for (const SiteFrame& f : c.sites)
            if (f.fdi == pl.fdi) node.extras["sites"].push_back(site_json(f));
        a.nodes.push_back(node);
    }
    for (const auto& [name, mesh] : c.solids) {
        if (name.rfind("tooth_", 0) == 0) continue;
        AssetNode node;
        node.name = name;
        std::replace(node.name.begin(), node.name.end(), '_', ' ');
        if (name.rfind("floor_", 0) == 0) {
            // A site's yielding floor layer: "floor_<fdi>_<site>".
            const int fdi = std::stoi(name.substr(6, 2));
            node.parts.push_back(MeshPart{mesh, kMaterialGingiva});
            node.extras = {{"tissue", "floor"}, {"fdi", fdi}, {"site", name.substr(9)}};
        } else {
            const bool gum = name.rfind("gingiva_", 0) == 0;
            node.parts.push_back(MeshPart{mesh, gum ? kMaterialGingiva : kMaterialBone});
            node.extras = {{"tissue", gum ? "gingiva" : "bone"}, {"jaw", name.substr(name.find('_') + 1)}};
        }
        a.nodes.push_back(node);
    }
}

}  // namespace

const std::vector<Material>& case_materials() {
    static const std::vector<Material> m = {
        Material{"enamel", {0.93, 0.91, 0.84, 1.0}, 0.0, 0.35},
        Material{"root", {0.86, 0.78, 0.60, 1.0}, 0.0, 0.6},
        Material{"gingiva", {0.86, 0.44, 0.47, 1.0}, 0.0, 0.45},
        Material{"bone", {0.90, 0.86, 0.76, 1.0}, 0.0, 0.8},
    };
    return m;
}

PatientCase build_case(const Chart& chart, const CaseSettings& cs) {
    {
        std::vector<std::string> errors;
        check_chart_for_case(chart, "chart", errors);
        if (!errors.empty()) throw std::invalid_argument(errors.front());
    }
    PatientCase out;
    out.chart = chart;
    const double r = cs.probe_radius_m;

    std::vector<Built> built;
    built.reserve(chart.teeth.size());
    for (const auto& [fdi, rec] : chart.teeth) {
        Built b;
        b.shape = std::make_unique<ToothShape>(fdi);
        b.tables.placement = arch_placement(fdi);
        b.tables.shape = b.shape.get();
        const ToothShape* shape = b.shape.get();
        b.fine = polygonize([shape](const Vec3& p) { return shape->field(p); }, shape->bounds(),
                            PolygonizeSettings{cs.tooth_cell_m, 24});
        b.mesh = cs.tooth_max_error_m > 0.0 ? decimate(b.fine, DecimateSettings{cs.tooth_max_error_m, 0, 0.5, 20.0})
                                            : b.fine;
        built.push_back(std::move(b));
    }

    // Vertices of every tooth in every other tooth's frame, for the neighbour check of the sites.
    auto others_in = [&](size_t self) {
        std::vector<Vec3> pts;
        const ToothPlacement& me = built[self].tables.placement;
        const bool upper = me.fdi / 10 <= 2;
        for (size_t k = 0; k < built.size(); ++k) {
            if (k == self) continue;
            const ToothPlacement& o = built[k].tables.placement;
            if ((o.fdi / 10 <= 2) != upper) continue;
            if (glm::length(o.position - me.position) > 0.02) continue;
            for (const Vec3& v : built[k].fine.vertices) pts.push_back(me.to_tooth(o.to_case(v)));
        }
        return pts;
    };

    for (size_t k = 0; k < built.size(); ++k) {
        Built& b = built[k];
        ToothTables& t = b.tables;
        const ToothShape& shape = *b.shape;
        const ToothRecord& rec = chart.teeth.at(t.placement.fdi);
        // One flat bottom per jaw, below the longest root of the jaw's charted teeth.
        t.bottom = 0.0;
        for (const auto& [other, r2] : chart.teeth)
            if ((other / 10 <= 2) == (t.placement.fdi / 10 <= 2))
                t.bottom = std::min(t.bottom, -tooth_dimensions(other).root_length_mm * 1e-3 - kBelowApex);
        const std::vector<Vec3> neighbours = others_in(k);
        // The pocket's inner side is the tooth's convex outline (concavities stay filled with
        // tissue), so the probe's line must clear that outline, not only the surface.
        fill_hull(t, b.fine);
        std::vector<Vec3> outline = b.fine.vertices;
        for (int j = 0; j < t.hull_rows; ++j)
            for (int i = 0; i < cd::kAngles; ++i) {
                const double rad = t.hull[size_t(j) * cd::kAngles + size_t(i)];
                if (rad <= 0.0) continue;
                const double th = angle_of(i);
                outline.emplace_back(rad * std::cos(th), t.hull_y0 + t.hull_dy * j, rad * std::sin(th));
            }
        const ProbeClearance probe_clear{&cs.probe_profile_m, cs.probe_profile_step_m, r, cs.tooth_clearance_m};

        // Site angles: at the shape's site angles, turned toward the facial or lingual middle
        // where a neighbouring tooth is in the probe's way.
        std::array<double, 6> gm{}, pd{};
        for (Site s : kAllSites) {
            const size_t i = size_t(s);
            gm[i] = rec.sites[i]->gm_mm * 1e-3;
            pd[i] = rec.sites[i]->pd_mm * 1e-3;
            b.tissue[i] = site_tissue(*rec.sites[i]);
            // The gingiva's floor is where the yielding layer starts: the tip sinks depth_at(0.25 N)
            // into it to rest at the charted depth, and depth_at(0.5 N) at a firm push.
            const YieldCurve& curve = b.tissue[i].curve();
            const double onset_depth = std::max(pd[i] - curve.depth_m_at(kRestingProbeForce_N), kMinPocket);
            const double rest_depth = onset_depth + curve.depth_m_at(kRestingProbeForce_N);
            const double deep_depth = onset_depth + curve.depth_m_at(kFirmProbeForce_N);
            double theta = shape.site_angle(s);
            const double target = site_target_angle(s);
            bool clear = false;
            for (int step = 0; step <= kSiteSearchSteps; ++step) {
                const double ym = shape.cej_height(theta) + gm[i];
                // The probe's line clears the tooth and its neighbours down to the firm push.
                const double yd = ym - deep_depth;
                const double rp = line_clearance(outline, theta, yd, 1.0, probe_clear);
                if (line_clear_of(neighbours, rp, theta, yd, probe_clear)) {
                    b.theta[i] = theta;
                    b.probe_r[i] = rp;
                    b.margin[i] = ym;
                    b.floor[i] = ym - onset_depth;
                    b.rest[i] = ym - rest_depth;
                    b.deep[i] = yd;
                    clear = true;
                    break;
                }
                double diff = std::remainder(target - theta, kTwoPi);
                if (std::abs(diff) < kSiteSearchStep) break;
                theta += diff > 0.0 ? kSiteSearchStep : -kSiteSearchStep;
            }
            if (!clear)
                throw std::invalid_argument("tooth " + std::to_string(t.placement.fdi) + " site " + site_name(s) +
                                            ": no straight probe path clears the neighbouring teeth");
        }

        // Margin around the tooth: the CEJ's scallop plus the charted margin. The floor is
        // interpolated between the sites' floor heights, so it is flat around every site (the CEJ
        // curve slopes at the line angles; a floor following it would let the tip slide off the
        // site), never less than kMinPocket below the margin.
        for (int i = 0; i < cd::kAngles; ++i) {
            const double th = angle_of(i);
            const double ym = shape.cej_height(th) + cd::site_interpolate(b.theta, gm, th);
            t.margin.v[size_t(i)] = ym;
            // The gingiva's own floor lies under the sites' yielding layers (add_floor_layers).
            const double onset = std::min(cd::site_interpolate(b.theta, b.floor, th), ym - kMinPocket);
            t.floor.v[size_t(i)] = onset - kFloorLayerDepth;
            t.charted_floor.v[size_t(i)] = std::min(cd::site_interpolate(b.theta, b.rest, th), onset);
        }

        // Inner wall: clear of the tooth near the margin everywhere, and of the whole crown at the
        // sites (a disc of the probe's radius plus clearance around each site's line).
        // The probe widens up its working end: the wall clears it at its widest within the pocket
        // (around as well as outward), the tip therefore with a little more room at depth.
        double deepest = 0.0;
        for (size_t i = 0; i < 6; ++i) deepest = std::max(deepest, b.margin[i] - b.deep[i]);
        const double wall_clear = probe_clear.at(deepest + kNearMargin) - cs.tooth_clearance_m + cs.wall_clearance_m;
        for (int i = 0; i < cd::kAngles; ++i) {
            const double th = angle_of(i);
            const double yf = t.floor.v[size_t(i)], ym = t.margin.v[size_t(i)];
            double wall = line_clearance(outline, th, yf, ym + kNearMargin, probe_clear) + wall_clear;
            for (double y = yf; y <= ym; y += t.hull_dy)
                wall = std::max(wall, t.hull_at(th, y) + 2.0 * r + cs.tooth_clearance_m + cs.wall_clearance_m);
            for (size_t s = 0; s < 6; ++s) {
                const double delta = std::remainder(th - b.theta[s], kTwoPi);
                const double side = b.probe_r[s] * std::sin(delta);
                if (std::abs(side) >= wall_clear || std::cos(delta) <= 0.0) continue;
                wall = std::max(wall, b.probe_r[s] * std::cos(delta) + std::sqrt(wall_clear * wall_clear - side * side));
            }
            t.slot.v[size_t(i)] = wall;
        }
        // Outer surface: the inner wall's running maximum over +-12 degrees, averaged, plus the
        // margin's thickness: a smooth outline that hugs the pocket without its site bumps.
        {
            const int w = cd::kAngles / 30;
            std::array<double, cd::kAngles> mx{};
            for (int i = 0; i < cd::kAngles; ++i) {
                double m = 0.0;
                for (int d = -w; d <= w; ++d) m = std::max(m, t.slot.v[size_t((i + d + cd::kAngles) % cd::kAngles)]);
                mx[size_t(i)] = m;
            }
            double reach = 0.0;
            for (int i = 0; i < cd::kAngles; ++i) {
                double sum = 0.0;
                for (int d = -w; d <= w; ++d) sum += mx[size_t((i + d + cd::kAngles) % cd::kAngles)];
                t.outer.v[size_t(i)] = std::max(sum / double(2 * w + 1), t.slot.v[size_t(i)]) + kMarginThickness;
                const double depth = std::min(t.margin.v[size_t(i)] - t.bottom, kThickeningDepth);
                reach = std::max(reach, t.outer.v[size_t(i)] + kThickening * depth);
            }
            t.reach = reach + 2e-3;
        }

        // Furcations opened by the chart.
        for (const ToothShape::Furcation& f : shape.furcations()) {
            const auto it = rec.furcation.find(f.side);
            if (it == rec.furcation.end() || it->second < 2) continue;
            cd::Tunnel tn;
            tn.entrance = f.entrance;
            tn.inward = glm::normalize(Vec3(f.inward.x, 0.0, f.inward.z));
            tn.across = Vec3(-tn.inward.z, 0.0, tn.inward.x);
            tn.depth = it->second >= 3 ? 0.05 : 3.5e-3;
            const double theta_e = std::atan2(f.entrance.z, f.entrance.x);
            tn.outer = std::max(0.0, t.slot.at(theta_e) - std::hypot(f.entrance.x, f.entrance.z) - 0.05e-3);
            tn.half_width = 0.5 * f.width + 0.2e-3;
            tn.y_high = f.roof_height + 0.3e-3;
            tn.y_low = f.roof_height - 1.5e-3;
            t.tunnels.push_back(tn);
        }
    }

    // Planes halfway to the neighbours of the same jaw.
    for (size_t a = 0; a < built.size(); ++a)
        for (size_t b = 0; b < built.size(); ++b) {
            if (a == b) continue;
            const ToothPlacement& pa = built[a].tables.placement;
            const ToothPlacement& pb = built[b].tables.placement;
            if ((pa.fdi / 10 <= 2) != (pb.fdi / 10 <= 2)) continue;
            Vec3 d = pb.position - pa.position;
            d.y = 0.0;
            if (glm::length(d) > 0.016) continue;
            built[a].tables.cuts.push_back({0.5 * (pa.position + pb.position), glm::normalize(d)});
        }

    // Teeth into the case.
    for (Built& b : built) {
        const ToothPlacement& pl = b.tables.placement;
        out.teeth.push_back(pl);
        for (Site s : kAllSites) {
            const size_t i = size_t(s);
            SiteFrame f;
            f.fdi = pl.fdi;
            f.site = s;
            f.theta_rad = b.theta[i];
            const Vec3 radial(std::cos(b.theta[i]), 0.0, std::sin(b.theta[i]));
            f.margin_point = pl.to_case(radial * b.probe_r[i] + Vec3(0.0, b.margin[i], 0.0));
            f.floor_point = pl.to_case(radial * b.probe_r[i] + Vec3(0.0, b.margin[i] - chart.teeth.at(pl.fdi).sites[i]->pd_mm * 1e-3, 0.0));
            f.onset_point = pl.to_case(radial * b.probe_r[i] + Vec3(0.0, b.floor[i], 0.0));
            f.rest_depth_m = b.margin[i] - b.rest[i];
            f.tissue = b.tissue[i];
            f.axis = pl.to_case_direction(Vec3(0.0, 1.0, 0.0));
            f.outward = pl.to_case_direction(radial);
            f.pd_m = chart.teeth.at(pl.fdi).sites[i]->pd_mm * 1e-3;
            f.gm_m = chart.teeth.at(pl.fdi).sites[i]->gm_mm * 1e-3;
            out.sites.push_back(f);
        }
        TriMesh placed = b.mesh;
        for (Vec3& v : placed.vertices) v = pl.to_case(v);
        if (pl.mirror)
            for (auto& tri : placed.triangles) std::swap(tri[1], tri[2]);
        out.solids.push_back({"tooth_" + std::to_string(pl.fdi), placed});
    }

    // Gingiva and bone per jaw.
    for (int jaw = 0; jaw < 2; ++jaw) {
        std::vector<ToothTables> tables;
        Aabb box{Vec3(std::numeric_limits<double>::infinity()), Vec3(-std::numeric_limits<double>::infinity())};
        for (const Built& b : built) {
            const bool upper = b.tables.placement.fdi / 10 <= 2;
            if (upper != (jaw == 1)) continue;
            tables.push_back(b.tables);
            const double rr = b.tables.reach;
            double ytop = -1.0;
            for (double v : b.tables.margin.v) ytop = std::max(ytop, v);
            for (int c = 0; c < 8; ++c) {
                const Vec3 corner((c & 1) ? rr : -rr, (c & 2) ? ytop + 1e-3 : b.tables.bottom - 1e-3, (c & 4) ? rr : -rr);
                const Vec3 q = b.tables.placement.to_case(corner);
                box.lo = glm::min(box.lo, q);
                box.hi = glm::max(box.hi, q);
            }
        }
        if (tables.empty()) continue;
        const std::string name = jaw == 1 ? "upper" : "lower";
        TriMesh gum = polygonize([&](const Vec3& p) { return cd::gum_field(tables, p); }, box,
                                 PolygonizeSettings{cs.gum_cell_m, 24});
        if (cs.gum_max_error_m > 0.0) gum = decimate(gum, DecimateSettings{cs.gum_max_error_m, 0, 0.5, 20.0});
        out.solids.push_back({"gingiva_" + name, gum});
        if (cs.bone) {
            TriMesh bone = polygonize([&](const Vec3& p) { return cd::bone_field(tables, p); }, box,
                                      PolygonizeSettings{cs.gum_cell_m * 2.0, 24});
            if (cs.gum_max_error_m > 0.0) bone = decimate(bone, DecimateSettings{cs.gum_max_error_m * 3.0, 0, 0.5, 20.0});
            out.solids.push_back({"bone_" + name, bone});
        }
    }
    add_floor_layers(out, cs.probe_radius_m);
    fill_case_asset(out, built);
    return out;
}

std::vector<double> probe_radius_profile(const TriMesh& tip, double step) {
    std::vector<double> prof;
    auto put = [&](double y, double radius) {
        if (y < 0.0) return;
        const size_t i = size_t(std::llround(y / step));
        if (prof.size() <= i) prof.resize(i + 1, 0.0);
        prof[i] = std::max(prof[i], radius);
    };
    // The surface's radius at every sample height, from the vertices and along the edges.
    for (const auto& tri : tip.triangles)
        for (int k = 0; k < 3; ++k) {
            const Vec3& a = tip.vertices[tri[size_t(k)]];
            const Vec3& b = tip.vertices[tri[size_t((k + 1) % 3)]];
            put(a.y, std::hypot(a.x, a.z));
            const double lo = std::min(a.y, b.y), hi = std::max(a.y, b.y);
            for (double y = std::ceil(lo / step) * step; y < hi; y += step) {
                const Vec3 p = a + (b - a) * ((y - a.y) / (b.y - a.y));
                put(y, std::hypot(p.x, p.z));
            }
        }
    for (size_t i = 1; i < prof.size(); ++i) prof[i] = std::max(prof[i], prof[i - 1]);
    return prof;
}

namespace {

constexpr double kTransferSpeed = 0.04;   // m/s, probe moving between sites above the crowns
constexpr double kLiftAboveCrowns = 3e-3; // how far above the highest crown of the jaw it travels
constexpr double kEntryAboveMargin = 1e-3;
constexpr double kHoldSeconds = 0.1;
constexpr std::array<Site, 6> kWalkingOrder{Site::MB, Site::B, Site::DB, Site::DL, Site::L, Site::ML};

Quat probe_orientation(const SiteFrame& s) {
    const Vec3 y = glm::normalize(s.axis);
    const Vec3 z = glm::normalize(s.outward - y * glm::dot(s.outward, y));
    const Vec3 x = glm::cross(y, z);
    return glm::normalize(glm::quat_cast(glm::dmat3(x, y, z)));
}

}  // namespace

Trajectory probing_trajectory(const PatientCase& c, double insert_speed, double stiffness, double force) {
    Trajectory tr;
    double t = 0.0;
    Pose last;
    bool started = false;
    auto go = [&](const Pose& p, double speed) {
        if (!started) {
            tr.samples.push_back({0.0, p});
            started = true;
        } else {
            const double d = glm::length(p.position - last.position);
            t += std::max(d / speed, 0.05);
            tr.samples.push_back({t, p});
        }
        last = p;
    };
    for (const ToothPlacement& pl : c.teeth) {
        double crown_top = 0.0;
        for (const ToothPlacement& o : c.teeth)
            if ((o.fdi / 10 <= 2) == (pl.fdi / 10 <= 2))
                crown_top = std::max(crown_top, tooth_dimensions(o.fdi).crown_length_mm * 1e-3);
        for (Site s : kWalkingOrder) {
            const auto it = std::find_if(c.sites.begin(), c.sites.end(),
                                         [&](const SiteFrame& f) { return f.fdi == pl.fdi && f.site == s; });
            if (it == c.sites.end()) continue;
            const SiteFrame& f = *it;
            const Quat q = probe_orientation(f);
            const double margin_y = pl.to_tooth(f.margin_point).y;
            const Vec3 top = f.margin_point + f.axis * (crown_top + kLiftAboveCrowns - margin_y);
            const Vec3 entry = f.margin_point + f.axis * kEntryAboveMargin;
            // Where the graphic tip rests at `force` (the onset plus the tissue's depth), plus the
            // coupling's stretch force / K and a margin: the force would just pass `force` there.
            const double rest = glm::dot(f.margin_point - f.onset_point, f.axis) + f.tissue.curve().depth_m_at(force);
            const double past = rest + force / stiffness + kProbeOvershootMargin_m - f.pd_m;
            const Vec3 bottom = f.floor_point - f.axis * past;
            go(Pose{top, q}, kTransferSpeed);
            go(Pose{entry, q}, kTransferSpeed);
            ProbingPass pass{pl.fdi, s, t, 0.0, 0.0, past};
            go(Pose{bottom, q}, insert_speed);
            pass.t_floor = t - past / insert_speed;
            tr.samples.push_back({t + kHoldSeconds, Pose{bottom, q}});
            t += kHoldSeconds;
            go(Pose{entry, q}, kTransferSpeed);
            pass.t_end = t;
            go(Pose{top, q}, kTransferSpeed);
            tr.passes.push_back(pass);
        }
    }
    return tr;
}

}  // namespace sulcus
