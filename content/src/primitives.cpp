#include "sulcus/content/primitives.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace sulcus {
namespace {

double cross2(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }

// > 0 when c lies left of the directed line a -> b.
double orient2(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(b - a, c - a); }

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

void require(bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(what);
}

// Closed segments ab and cd share at least one point (touching counts).
bool segments_touch(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
    const double d1 = orient2(c, d, a), d2 = orient2(c, d, b);
    const double d3 = orient2(a, b, c), d4 = orient2(a, b, d);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
    auto on_segment = [](const Vec2& p, const Vec2& q, const Vec2& r) {  // r on pq, given collinear
        return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
               r.y <= std::max(p.y, q.y);
    };
    return (d1 == 0 && on_segment(c, d, a)) || (d2 == 0 && on_segment(c, d, b)) ||
           (d3 == 0 && on_segment(a, b, c)) || (d4 == 0 && on_segment(a, b, d));
}

// p inside or on the boundary of the counter-clockwise triangle abc.
bool in_triangle_closed(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c) {
    return orient2(a, b, p) >= 0 && orient2(b, c, p) >= 0 && orient2(c, a, p) >= 0;
}

void check_simple_ccw(const std::vector<Vec2>& poly) {
    const size_t n = poly.size();
    require(n >= 3, "polygon needs at least 3 vertices");
    for (const Vec2& p : poly) require(std::isfinite(p.x) && std::isfinite(p.y), "polygon vertex not finite");
    for (size_t i = 0; i < n; ++i) {
        const Vec2 &a = poly[i], &b = poly[(i + 1) % n];
        require(a != b, "polygon has a repeated vertex at " + std::to_string(i));
        for (size_t j = i + 1; j < n; ++j) {
            const Vec2 &c = poly[j], &d = poly[(j + 1) % n];
            const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if (adjacent) {
                // Neighbouring edges share one vertex; they must not fold back onto each other.
                const Vec2 shared = j == i + 1 ? b : a;
                const Vec2 other_i = j == i + 1 ? a : b;
                const Vec2 other_j = j == i + 1 ? d : c;
                if (orient2(other_i, shared, other_j) == 0 &&
                    glm::dot(other_i - shared, other_j - shared) > 0)
                    throw std::invalid_argument("polygon folds back at vertex " + std::to_string(j == i + 1 ? j : i));
            } else if (segments_touch(a, b, c, d)) {
                throw std::invalid_argument("polygon edges " + std::to_string(i) + " and " + std::to_string(j) +
                                            " intersect (polygon not simple)");
            }
        }
    }
    require(polygon_signed_area(poly) > 0, "polygon is not counter-clockwise");
}

// Adds the axis-aligned face quad of a box on side `sign` of `axis`, wound counter-clockwise
// seen from outside (or from inside the box when `inward`).
void add_box_face(TriMesh& m, uint32_t base, int axis, int sign, bool inward) {
    // Box corner k has coordinate bit a set when it is on the + side of axis a.
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // u x v = +axis
    auto corner = [&](int su, int sv) {
        uint32_t k = sign > 0 ? (1u << axis) : 0u;
        if (su > 0) k |= 1u << u;
        if (sv > 0) k |= 1u << v;
        return base + k;
    };
    std::array<uint32_t, 4> q{corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)};  // normal +axis
    if ((sign < 0) != inward) std::swap(q[1], q[3]);
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
}

void add_box_shell(TriMesh& m, const Vec3& half, const Vec3& centre, bool inward) {
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    for (uint32_t k = 0; k < 8; ++k)
        m.vertices.push_back(centre + Vec3((k & 1u) ? half.x : -half.x, (k & 2u) ? half.y : -half.y,
                                           (k & 4u) ? half.z : -half.z));
    for (int axis = 0; axis < 3; ++axis)
        for (int sign : {-1, 1}) add_box_face(m, base, axis, sign, inward);
}

bool positive_finite(const Vec3& v) { return positive_finite(v.x) && positive_finite(v.y) && positive_finite(v.z); }

}  // namespace

double polygon_signed_area(const std::vector<Vec2>& polygon) {
    double a2 = 0.0;
    for (size_t i = 0, n = polygon.size(); i < n; ++i) a2 += cross2(polygon[i], polygon[(i + 1) % n]);
    return 0.5 * a2;
}

TriMesh make_box(const Vec3& half_extents, const Vec3& centre) {
    require(positive_finite(half_extents), "box half extents must be positive");
    TriMesh m;
    add_box_shell(m, half_extents, centre, false);
    return m;
}

TriMesh make_box_with_cavity(const Vec3& outer_half_extents, const Vec3& cavity_half_extents,
                             const Vec3& cavity_centre) {
    require(positive_finite(outer_half_extents) && positive_finite(cavity_half_extents),
            "box and cavity half extents must be positive");
    const Vec3 lo = cavity_centre - cavity_half_extents, hi = cavity_centre + cavity_half_extents;
    for (int a = 0; a < 3; ++a)
        require(lo[a] > -outer_half_extents[a] && hi[a] < outer_half_extents[a],
                "cavity must lie strictly inside the outer box");
    TriMesh m;
    add_box_shell(m, outer_half_extents, Vec3(0.0), false);
    add_box_shell(m, cavity_half_extents, cavity_centre, true);
    return m;
}

std::vector<std::array<uint32_t, 3>> triangulate_polygon(const std::vector<Vec2>& polygon) {
    check_simple_ccw(polygon);
    std::vector<uint32_t> ring(polygon.size());
    for (uint32_t i = 0; i < ring.size(); ++i) ring[i] = i;
    std::vector<std::array<uint32_t, 3>> tris;
    // Clip the first ear found, scanning from the start of the ring: deterministic, and O(n^3)
    // in the worst case, which is nothing for authored outlines of a few dozen vertices.
    while (ring.size() > 3) {
        const size_t m = ring.size();
        bool clipped = false;
        for (size_t k = 0; k < m && !clipped; ++k) {
            const uint32_t ip = ring[(k + m - 1) % m], ic = ring[k], in = ring[(k + 1) % m];
            const Vec2 &a = polygon[ip], &b = polygon[ic], &c = polygon[in];
            if (orient2(a, b, c) <= 0) continue;  // reflex or straight: not an ear
            bool empty = true;
            for (uint32_t j : ring) {
                if (j == ip || j == ic || j == in) continue;
                if (in_triangle_closed(polygon[j], a, b, c)) {
                    empty = false;
                    break;
                }
            }
            if (!empty) continue;
            tris.push_back({ip, ic, in});
            ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
            clipped = true;
        }
        require(clipped, "polygon could not be triangulated (no ear found)");
    }
    require(orient2(polygon[ring[0]], polygon[ring[1]], polygon[ring[2]]) > 0,
            "polygon triangulation left a degenerate triangle");
    tris.push_back({ring[0], ring[1], ring[2]});
    return tris;
}

TriMesh make_extruded_polygon(const std::vector<Vec2>& polygon, double z0, double z1) {
    require(std::isfinite(z0) && std::isfinite(z1) && z1 > z0, "extrusion needs z1 > z0");
    const auto cap = triangulate_polygon(polygon);
    const uint32_t n = static_cast<uint32_t>(polygon.size());
    TriMesh m;
    // Vertex i at z0, vertex n + i at z1.
    for (const Vec2& p : polygon) m.vertices.emplace_back(p.x, p.y, z0);
    for (const Vec2& p : polygon) m.vertices.emplace_back(p.x, p.y, z1);
    for (const auto& t : cap) m.triangles.push_back({n + t[0], n + t[1], n + t[2]});  // top, faces +Z
    for (const auto& t : cap) m.triangles.push_back({t[0], t[2], t[1]});              // bottom, faces -Z
    // Walls: walking counter-clockwise, the outside is on the right of each edge.
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t j = (i + 1) % n;
        m.triangles.push_back({i, j, n + j});
        m.triangles.push_back({i, n + j, n + i});
    }
    return m;
}

TriMesh make_wedge(double apex_angle_rad, double height, double half_length, const Vec3& apex) {
    require(std::isfinite(apex_angle_rad) && apex_angle_rad > 0 && apex_angle_rad < std::numbers::pi,
            "wedge apex angle must be in (0, pi)");
    require(positive_finite(height) && positive_finite(half_length), "wedge height and length must be positive");
    const double half_width = height * std::tan(0.5 * apex_angle_rad);
    const std::vector<Vec2> section{{apex.x - half_width, apex.y - height},
                                    {apex.x + half_width, apex.y - height},
                                    {apex.x, apex.y}};
    return make_extruded_polygon(section, apex.z - half_length, apex.z + half_length);
}

}  // namespace sulcus
