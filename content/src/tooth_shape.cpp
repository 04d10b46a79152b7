// The implicit solid of a tooth (docs/anatomy.md describes the construction).
//
// The body (crown, and the root or root trunk) is a stack of horizontal cross-sections: rounded
// superellipses whose half-widths are smooth functions of the height y, passing through the
// table's cervical widths at y = 0 and its crown widths at the heights of contour. The crown is
// capped by an occlusal height field (incisal edge, canine cusp, or cusps and marginal ridges
// around the fossae) and the single root by a rounded apex. Multi-rooted teeth cap the trunk at
// the furcation roof and add separate roots, joined by a smooth union.
//
// Everything inside is in millimetres; field() converts at its boundary.
#include "sulcus/content/polygonize.h"
#include "sulcus/content/tooth.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sulcus {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Smooth maximum with its partial derivatives' weight (d/da = h, d/db = 1 - h).
inline double smax_w(double a, double b, double k, double* h_out) {
    const double h = std::clamp(0.5 + 0.5 * (a - b) / k, 0.0, 1.0);
    *h_out = h;
    return b + (a - b) * h + k * h * (1.0 - h);
}

inline double smax(double a, double b, double k) {
    double h;
    return smax_w(a, b, k, &h);
}

// Approximate signed distance (mm) from (u, v) to the section |u/a|, |v/b| blended between an
// ellipse (w = 0) and a squircle (w = 1); b is b_pos for v >= 0 and b_neg below. The zero set is
// exact; the value is the level minus one over the gradient's length, which is the distance to
// first order. Near the centre the gradient is replaced by a constant so the field stays
// continuous there.
inline double section_distance(double u, double v, double a, double b_pos, double b_neg, double w) {
    const double b = v >= 0.0 ? b_pos : b_neg;
    const double U = u / a, V = v / b;
    const double U2 = U * U, V2 = V * V;
    const double n2 = std::sqrt(U2 + V2);
    const double n4 = std::sqrt(std::sqrt(U2 * U2 + V2 * V2));
    const double N = (1.0 - w) * n2 + w * n4;
    const double g_centre = 2.0 / (a + 0.5 * (b_pos + b_neg));
    double g = g_centre;
    if (n2 > 1e-12) {
        const double n43 = n4 * n4 * n4;
        const double dU = ((1.0 - w) * U / n2 + w * U2 * U / n43) / a;
        const double dV = ((1.0 - w) * V / n2 + w * V2 * V / n43) / b;
        const double beta = std::min(2.0 * N, 1.0);
        g = g_centre + (std::sqrt(dU * dU + dV * dV) - g_centre) * beta;
    }
    return (N - 1.0) / g;
}

// Rounded apex: a paraboloid with radii of curvature (rx, rz) whose lowest point is (x0, y0, z0),
// as a distance-like field of the half-space above it.
inline double apex_cap(double x, double y, double z, double x0, double y0, double z0, double rx, double rz) {
    const double du = x - x0, dv = z - z0;
    const double h = y0 + 0.5 * (du * du / rx + dv * dv / rz);
    const double gx = du / rx, gz = dv / rz;
    return (h - y) / std::sqrt(1.0 + gx * gx + gz * gz);
}

// Rise from v0 at s = 0 to v1 at s = 1 with zero slope at s = 1 (a height of contour).
inline double rise(double v0, double v1, double s) { return v0 + (v1 - v0) * (1.0 - (1.0 - s) * (1.0 - s)); }

constexpr double kCuspTip = 0.5;     // rounding of a cusp tip or ridge crest, mm
constexpr double kApexBlend = 0.3;   // rounding where the apex cap meets the root's side, mm
constexpr double kFloorBlend = 0.6;  // rounding of the trunk's floor (furcation roof) into its side, mm
constexpr double kRootTopBlend = 2.0;  // a separate root fades into the trunk over this height, mm

}  // namespace

ToothShape::ToothShape(int fdi) : dims_(tooth_dimensions(fdi)) {
    const ToothDimensions& d = dims_;
    const double L = d.crown_length_mm, R = d.root_length_mm;
    const double A = 0.5 * d.crown_md_mm, a0 = 0.5 * d.cervix_md_mm;
    const double B = 0.5 * d.crown_bl_mm, b0 = 0.5 * d.cervix_bl_mm;
    const bool up = d.upper;

    apex_half_md_ = std::max(0.25 * a0, 0.6);
    apex_half_bl_ = std::max(0.25 * b0, 0.6);
    root_taper_length_ = d.roots > 1 ? 2.0 * R : R;
    switch (d.cls) {
        case ToothClass::CentralIncisor:
        case ToothClass::LateralIncisor: {
            const bool central = d.cls == ToothClass::CentralIncisor;
            occlusal_kind_ = Occlusal::Edge;
            contact_y_ = (central ? 0.8 : 0.75) * L;  // contact areas in the incisal third
            facial_contour_y_ = 0.2 * L;                // labial contour and cingulum: cervical third
            lingual_contour_y_ = 0.2 * L;
            top_half_md_ = 0.97 * A;
            top_half_facial_ = top_half_lingual_ = up ? 0.5 : 0.4;  // the incisal edge
            squareness_cervix_ = 0.2;
            squareness_crown_ = 0.35;
            // The mesio-incisal angle is sharper than the disto-incisal one.
            if (up) {
                edge_drop_mesial_ = central ? 0.4 : 0.6;
                edge_drop_distal_ = central ? 1.0 : 1.2;
            } else {
                edge_drop_mesial_ = central ? 0.25 : 0.3;
                edge_drop_distal_ = central ? 0.35 : 0.6;
            }
            apex_curve_ = up && !central ? 0.8 : 0.3;  // upper laterals bend distally most
            blend_top_ = 0.3;
            break;
        }
        case ToothClass::Canine:
            occlusal_kind_ = Occlusal::Cusp;
            contact_y_ = 0.65 * L;
            facial_contour_y_ = 0.25 * L;
            lingual_contour_y_ = 0.25 * L;
            top_half_md_ = 0.85 * A;
            top_half_facial_ = top_half_lingual_ = 1.0;
            squareness_cervix_ = 0.2;
            squareness_crown_ = 0.3;
            // The cusp tip lies slightly mesial: the mesial cusp ridge is the shorter one.
            cusps_[0] = Cusp{0.25, 0.0, L, 0.45, 0.45};
            n_cusps_ = 1;
            apex_curve_ = 0.6;
            blend_top_ = 0.4;
            break;
        case ToothClass::FirstPremolar:
        case ToothClass::SecondPremolar: {
            const bool first = d.cls == ToothClass::FirstPremolar;
            occlusal_kind_ = Occlusal::Table;
            contact_y_ = 0.62 * L;
            facial_contour_y_ = 0.3 * L;
            lingual_contour_y_ = (up ? 0.45 : 0.4) * L;
            top_half_md_ = 0.85 * A;
            top_half_facial_ = 0.75 * B;
            top_half_lingual_ = 0.7 * B;
            squareness_cervix_ = 0.3;
            squareness_crown_ = 0.45;
            // The lingual cusp is shorter than the buccal one: a little on upper premolars, a lot on
            // the lower first premolar (a small, non-functional lingual cusp).
            const double lingual_h = up ? (first ? L - 1.0 : L - 0.4) : (first ? L - 2.2 : L - 0.8);
            const double ridge_h = lingual_h - 0.5;
            const double xr = 0.8 * top_half_md_;
            cusps_[0] = Cusp{first && up ? -0.2 : 0.0, 0.45 * B, L, 0.75, 1.1};
            cusps_[1] = Cusp{first && up ? 0.3 : 0.0, -0.45 * B, lingual_h, 0.75, 1.1};
            cusps_[2] = Cusp{xr, 0.0, ridge_h, 0.8, 0.0};
            cusps_[3] = Cusp{-xr, 0.0, ridge_h - 0.2, 0.8, 0.0};
            n_cusps_ = 4;
            apex_curve_ = 0.5;
            blend_top_ = 0.5;
            break;
        }
        case ToothClass::FirstMolar:
        case ToothClass::SecondMolar: {
            const bool first = d.cls == ToothClass::FirstMolar;
            occlusal_kind_ = Occlusal::Table;
            contact_y_ = 0.6 * L;
            facial_contour_y_ = 0.3 * L;
            lingual_contour_y_ = 0.45 * L;
            top_half_md_ = 0.85 * A;
            top_half_facial_ = 0.8 * B;
            top_half_lingual_ = 0.8 * B;
            squareness_cervix_ = 0.45;
            squareness_crown_ = 0.65;
            const double sx = 0.8, sz = 0.9;
            const double zb = 0.5 * B, zl = -0.5 * B;
            int n = 0;
            if (up) {
                // MB, DB, ML (the largest), DL (small, smaller still on the second molar).
                cusps_[n++] = Cusp{0.45 * A, zb, L, sx, sz};
                cusps_[n++] = Cusp{-0.45 * A, zb, L - 0.3, sx, sz};
                cusps_[n++] = Cusp{0.3 * A, zl, L - 0.2, sx, sz};
                cusps_[n++] = Cusp{-0.55 * A, zl, L - (first ? 0.9 : 1.3), sx, sz};
            } else if (first) {
                // MB, DB, D on the buccal side; ML, DL on the lingual.
                cusps_[n++] = Cusp{0.55 * A, zb, L, sx, sz};
                cusps_[n++] = Cusp{-0.05 * A, 0.55 * B, L - 0.3, sx, sz};
                cusps_[n++] = Cusp{-0.65 * A, 0.3 * B, L - 0.7, sx, sz};
                cusps_[n++] = Cusp{0.5 * A, zl, L, sx, sz};
                cusps_[n++] = Cusp{-0.4 * A, zl, L - 0.2, sx, sz};
            } else {
                cusps_[n++] = Cusp{0.45 * A, zb, L, sx, sz};
                cusps_[n++] = Cusp{-0.45 * A, zb, L - 0.3, sx, sz};
                cusps_[n++] = Cusp{0.45 * A, zl, L, sx, sz};
                cusps_[n++] = Cusp{-0.45 * A, zl, L - 0.2, sx, sz};
            }
            const double xr = 0.78 * top_half_md_;
            cusps_[n++] = Cusp{xr, 0.0, L - 1.3, 0.8, 0.0};
            cusps_[n++] = Cusp{-xr, 0.0, L - 1.5, 0.8, 0.0};
            n_cusps_ = n;
            blend_top_ = 0.5;
            break;
        }
    }
    blend_cusps_ = 0.6;
    blend_roots_ = 0.4;

    // Separate roots of multi-rooted teeth (tooth frame, mm). Each starts halfway down the trunk,
    // inside it, narrows to a rounded apex and bows outward just enough that its outer face is
    // flush with the trunk's side at the furcation roof (the bend is solved for below), so the
    // roots continue the trunk's outline and part only where the floor of the trunk shows.
    const double T = d.trunk_length_mm;
    auto add_root = [&](double tx, double tz, double ax, double az, double len, double md, double bl,
                        double md_apex, double bl_apex, double ox, double oz) {
        Root r;
        r.top_y = -0.5 * T;
        r.apex_y = -len;
        r.top_x = tx;
        r.top_z = tz;
        r.apex_x = ax;
        r.apex_z = az;
        r.half_md_top = md;
        r.half_bl_top = bl;
        r.half_md_apex = md_apex;
        r.half_bl_apex = bl_apex;
        const double ol = std::hypot(ox, oz);
        ox /= ol;
        oz /= ol;
        // Outermost point of the root's section in direction o at height y, for a bend beta.
        const double y = -T - 0.2;
        const double t = (r.top_y - y) / (r.top_y - r.apex_y);
        const double f = 1.0 - t * std::sqrt(t);
        const double a = md_apex + (md - md_apex) * f, b = bl_apex + (bl - bl_apex) * f;
        const double sup = std::sqrt(a * a * ox * ox + b * b * oz * oz);
        const Section sec = section(y);
        auto outside = [&](double beta) {
            const double cx = tx + (ax - tx) * t + beta * ox * 4.0 * t * (1.0 - t);
            const double cz = tz + (az - tz) * t + beta * oz * 4.0 * t * (1.0 - t);
            const double px = cx + a * a * ox / sup, pz = cz + b * b * oz / sup;
            return section_distance(px - sec.cx, pz, sec.half_md, sec.half_facial, sec.half_lingual,
                                    sec.squareness);
        };
        double lo = -4.0, hi = 4.0;
        for (int it = 0; it < 50; ++it) {
            const double m = 0.5 * (lo + hi);
            (outside(m) < 0.0 ? lo : hi) = m;
        }
        r.bend_x = 0.5 * (lo + hi) * ox;
        r.bend_z = 0.5 * (lo + hi) * oz;
        roots_[size_t(n_roots_++)] = r;
    };
    if (d.roots == 2 && up) {
        // Upper first premolar: buccal and palatal roots, parting in the apical part.
        add_root(0.0, 1.9, 0.0, 2.4, R, 2.1, 1.7, 0.7, 0.7, 0, 1);
        add_root(0.0, -1.9, 0.0, -2.6, R - 1.0, 2.0, 1.7, 0.7, 0.7, 0, -1);
    } else if (d.roots == 2) {
        // Lower molars: mesial and distal roots, broad bucco-lingually; the mesial root curves
        // distally toward its apex, the distal one points distally.
        if (d.cls == ToothClass::FirstMolar) {
            add_root(1.8, 0.0, 1.9, 0.0, R, 2.2, 4.5, 0.8, 1.2, 1, 0);
            add_root(-1.8, 0.0, -2.8, 0.0, R - 1.0, 2.1, 4.4, 0.8, 1.1, -1, 0);
        } else {
            add_root(1.6, 0.0, 1.2, 0.0, R, 2.0, 4.5, 0.8, 1.2, 1, 0);
            add_root(-1.6, 0.0, -2.0, 0.0, R - 1.0, 1.9, 4.4, 0.8, 1.1, -1, 0);
        }
    } else if (d.roots == 3) {
        // Upper molars: mesiobuccal (broad bucco-lingually), distobuccal, palatal (the longest,
        // diverging palatally).
        if (d.cls == ToothClass::FirstMolar) {
            add_root(2.1, 2.5, 2.5, 3.1, R - 1.0, 1.7, 2.1, 0.7, 0.9, 1, 1.2);
            add_root(-2.1, 2.6, -2.9, 3.1, R - 1.5, 1.6, 1.9, 0.7, 0.8, -1, 1.2);
            add_root(0.0, -2.5, 0.0, -4.0, R, 2.6, 2.2, 0.9, 0.8, 0, -1);
        } else {
            add_root(1.8, 2.5, 2.0, 2.9, R - 1.0, 1.5, 2.1, 0.7, 0.9, 1, 1.2);
            add_root(-1.8, 2.6, -2.3, 2.9, R - 1.5, 1.4, 1.9, 0.7, 0.8, -1, 1.2);
            add_root(0.0, -2.5, 0.0, -3.4, R, 2.3, 2.2, 0.9, 0.8, 0, -1);
        }
    }
    find_furcations();
}

ToothShape::Section ToothShape::section(double y) const {
    const ToothDimensions& d = dims_;
    const double L = d.crown_length_mm;
    const double A = 0.5 * d.crown_md_mm, a0 = 0.5 * d.cervix_md_mm;
    const double B = 0.5 * d.crown_bl_mm, b0 = 0.5 * d.cervix_bl_mm;
    Section s{};
    if (y >= 0.0) {
        const double yy = std::min(y, L);
        // Mesio-distal: widest at the contact areas, narrowing a little toward the occlusal.
        if (yy < contact_y_) {
            s.half_md = rise(a0, A, yy / contact_y_);
        } else {
            const double t = (yy - contact_y_) / (L - contact_y_);
            s.half_md = A - (A - top_half_md_) * t * t;
        }
        // Facial: the height of contour in the cervical third, converging toward the edge/cusps.
        if (yy < facial_contour_y_) {
            s.half_facial = rise(b0, B, yy / facial_contour_y_);
        } else {
            const double t = (yy - facial_contour_y_) / (L - facial_contour_y_);
            s.half_facial = B - (B - top_half_facial_) * t * t;
        }
        // Lingual: the cingulum of anterior teeth, then a concave fossa to the edge (S-shaped
        // profile); the lingual contour of posterior teeth in the middle third.
        if (yy < lingual_contour_y_) {
            s.half_lingual = rise(b0, B, yy / lingual_contour_y_);
        } else {
            const double t = (yy - lingual_contour_y_) / (L - lingual_contour_y_);
            const double prof = occlusal_kind_ == Occlusal::Table ? t * t : t * t * (3.0 - 2.0 * t);
            s.half_lingual = B - (B - top_half_lingual_) * prof;
        }
        s.squareness = squareness_cervix_ + (squareness_crown_ - squareness_cervix_) * std::min(yy / contact_y_, 1.0);
        s.cx = 0.0;
    } else {
        // Root (or root trunk): narrowing slowly near the cervix, faster toward the apex.
        const double t = std::min(-y / root_taper_length_, 1.0);
        const double f = 1.0 - t * std::sqrt(t);
        s.half_md = apex_half_md_ + (a0 - apex_half_md_) * f;
        s.half_facial = s.half_lingual = apex_half_bl_ + (b0 - apex_half_bl_) * f;
        s.squareness = squareness_cervix_ * (1.0 - t);
        const double q = std::max(0.0, (t - 0.6) / 0.4);
        s.cx = -apex_curve_ * q * q;  // the apical third bends distally
    }
    return s;
}

void ToothShape::occlusal(double x, double z, double* h, double* gx, double* gz) const {
    const double L = dims_.crown_length_mm, A = 0.5 * dims_.crown_md_mm;
    if (occlusal_kind_ == Occlusal::Edge) {
        // A straight incisal edge at y = L, rounded down into the mesial and distal corners.
        double v = L, g = 0.0;
        const double xm = 0.5 * A, xd = 0.4 * A;
        if (x > xm) {
            const double s = (x - xm) / (A - xm);
            v -= edge_drop_mesial_ * s * s;
            g = -2.0 * edge_drop_mesial_ * s / (A - xm);
        } else if (x < -xd) {
            const double s = (-x - xd) / (A - xd);
            v -= edge_drop_distal_ * s * s;
            g = 2.0 * edge_drop_distal_ * s / (A - xd);
        }
        *h = v;
        *gx = g;
        *gz = 0.0;
        return;
    }
    // Cusps (and marginal ridges) as cones with rounded tips, joined by a smooth maximum whose
    // creases are the grooves and fossae.
    double v = 0, vx = 0, vz = 0;
    for (int i = 0; i < n_cusps_; ++i) {
        const Cusp& c = cusps_[size_t(i)];
        const double dx = (x - c.x) * c.slope_x, dz = (z - c.z) * c.slope_z;
        const double r = std::sqrt(dx * dx + dz * dz + kCuspTip * kCuspTip);
        const double ci = c.height - (r - kCuspTip);
        const double cx = -dx * c.slope_x / r, cz = -dz * c.slope_z / r;
        if (i == 0) {
            v = ci;
            vx = cx;
            vz = cz;
        } else {
            double w;
            v = smax_w(v, ci, blend_cusps_, &w);
            vx = w * vx + (1.0 - w) * cx;
            vz = w * vz + (1.0 - w) * cz;
        }
    }
    *h = v;
    *gx = vx;
    *gz = vz;
}

double ToothShape::body(double x, double y, double z) const {
    const Section s = section(y);
    const double side = section_distance(x - s.cx, z, s.half_md, s.half_facial, s.half_lingual, s.squareness);
    double h, gx, gz;
    occlusal(x, z, &h, &gx, &gz);
    const double top = (y - h) / std::sqrt(1.0 + gx * gx + gz * gz);
    const double f = smax(side, top, blend_top_);
    if (n_roots_ == 0)
        return smax(f, apex_cap(x, y, z, -apex_curve_, -dims_.root_length_mm, 0.0, apex_half_md_, apex_half_bl_),
                    kApexBlend);
    return smax(f, -(y + dims_.trunk_length_mm), kFloorBlend);
}

double ToothShape::root(const Root& r, double x, double y, double z) const {
    const double t = std::clamp((r.top_y - y) / (r.top_y - r.apex_y), 0.0, 1.0);
    const double bend = 4.0 * t * (1.0 - t);
    const double cx = r.top_x + (r.apex_x - r.top_x) * t + r.bend_x * bend;
    const double cz = r.top_z + (r.apex_z - r.top_z) * t + r.bend_z * bend;
    const double f = 1.0 - t * std::sqrt(t);
    const double a = r.half_md_apex + (r.half_md_top - r.half_md_apex) * f;
    const double b = r.half_bl_apex + (r.half_bl_top - r.half_bl_apex) * f;
    const double side = section_distance(x - cx, z - cz, a, b, b, 0.0);
    const double cap = apex_cap(x, y, z, r.apex_x, r.apex_y, r.apex_z, r.half_md_apex, r.half_bl_apex);
    // Ends (rounded) at the cervix, inside the trunk.
    return smax(smax(side, cap, kApexBlend), y - r.top_y, kRootTopBlend);
}

double ToothShape::field(const Vec3& p) const {
    const double x = p.x * 1e3, y = p.y * 1e3, z = p.z * 1e3;
    double f = body(x, y, z);
    for (int i = 0; i < n_roots_; ++i) f = smooth_min(f, root(roots_[size_t(i)], x, y, z), blend_roots_);
    return f * 1e-3;
}

Aabb ToothShape::bounds() const {
    const ToothDimensions& d = dims_;
    double xm = 0.5 * std::max(d.crown_md_mm, d.cervix_md_mm) + apex_curve_;
    double zm = 0.5 * std::max(d.crown_bl_mm, d.cervix_bl_mm);
    for (int i = 0; i < n_roots_; ++i) {
        const Root& r = roots_[size_t(i)];
        xm = std::max(xm, std::max(std::abs(r.top_x), std::abs(r.apex_x)) + std::abs(r.bend_x) + r.half_md_top);
        zm = std::max(zm, std::max(std::abs(r.top_z), std::abs(r.apex_z)) + std::abs(r.bend_z) + r.half_bl_top);
    }
    const double margin = 1.0;
    Aabb box;
    box.lo = 1e-3 * Vec3(-xm - margin, -d.root_length_mm - margin, -zm - margin);
    box.hi = 1e-3 * Vec3(xm + margin, d.crown_length_mm + margin, zm + margin);
    return box;
}

double ToothShape::cej_height(double theta_rad) const {
    const double c = std::cos(theta_rad);
    return 1e-3 * c * c * (c > 0.0 ? dims_.cej_curve_mesial_mm : dims_.cej_curve_distal_mm);
}

double ToothShape::site_angle(Site s) const {
    if (s == Site::B) return 0.5 * kPi;
    if (s == Site::L) return -0.5 * kPi;
    // The line angle: the point of the cervical outline whose outward normal bisects the mesial
    // (or distal) and the facial (or lingual) directions.
    const Section c = section(0.0);
    const bool facial = s == Site::MB || s == Site::DB;
    const double a = c.half_md, b = facial ? c.half_facial : c.half_lingual, w = c.squareness;
    double lo = 0.0, hi = 0.5 * kPi;
    for (int it = 0; it < 60; ++it) {
        const double phi = 0.5 * (lo + hi);
        const double U = std::cos(phi) / a, V = std::sin(phi) / b;
        const double n2 = std::sqrt(U * U + V * V), n4 = std::sqrt(std::sqrt(U * U * U * U + V * V * V * V));
        const double dU = ((1.0 - w) * U / n2 + w * U * U * U / (n4 * n4 * n4)) / a;
        const double dV = ((1.0 - w) * V / n2 + w * V * V * V / (n4 * n4 * n4)) / b;
        (dU > dV ? lo : hi) = phi;
    }
    const double phi = 0.5 * (lo + hi);
    switch (s) {
        case Site::MB: return phi;
        case Site::DB: return kPi - phi;
        case Site::ML: return -phi;
        case Site::DL: return -(kPi - phi);
        default: return 0.0;
    }
}

std::vector<ToothShape::Furcation> ToothShape::furcations() const { return furcations_; }

void ToothShape::find_furcations() {
    furcations_.clear();
    if (n_roots_ < 2) return;
    struct Spec {
        FurcationSide side;
        int i, j;
        double ox, oz;  // the side the entrance faces
    };
    std::vector<Spec> specs;
    if (n_roots_ == 2 && dims_.upper) {
        specs = {{FurcationSide::M, 0, 1, 1, 0}, {FurcationSide::D, 0, 1, -1, 0}};
    } else if (n_roots_ == 2) {
        specs = {{FurcationSide::B, 0, 1, 0, 1}, {FurcationSide::L, 0, 1, 0, -1}};
    } else {
        specs = {{FurcationSide::B, 0, 1, 0, 1}, {FurcationSide::M, 0, 2, 1, 0}, {FurcationSide::D, 1, 2, -1, 0}};
    }
    auto f = [&](double x, double y, double z) { return field(Vec3(x, y, z) * 1e-3); };
    const double T = dims_.trunk_length_mm;
    for (const Spec& sp : specs) {
        const Root &ri = roots_[size_t(sp.i)], &rj = roots_[size_t(sp.j)];
        const double mx = 0.5 * (ri.top_x + rj.top_x), mz = 0.5 * (ri.top_z + rj.top_z);
        double tx = rj.top_x - ri.top_x, tz = rj.top_z - ri.top_z;
        const double tl = std::hypot(tx, tz);
        tx /= tl;
        tz /= tl;
        double ox = -tz, oz = tx;
        if (ox * sp.ox + oz * sp.oz < 0.0) {
            ox = -ox;
            oz = -oz;
        }
        // Outline of the trunk just above its floor, along the outward direction.
        const double y_out = -T + 0.3;
        double s_in = 0.0, s_out = 0.0;
        while (f(mx + s_out * ox, y_out, mz + s_out * oz) < 0.0 && s_out < 20.0) s_out += 0.1;
        s_in = s_out - 0.1;
        for (int it = 0; it < 40; ++it) {
            const double s = 0.5 * (s_in + s_out);
            (f(mx + s * ox, y_out, mz + s * oz) < 0.0 ? s_in : s_out) = s;
        }
        // Roof: going up between the roots half a millimetre inside the outline.
        const double qx = mx + (s_out - 0.5) * ox, qz = mz + (s_out - 0.5) * oz;
        double y_lo = -T - 3.0, y_hi = -T + 1.0;
        for (int it = 0; it < 50; ++it) {
            const double y = 0.5 * (y_lo + y_hi);
            (f(qx, y, qz) > 0.0 ? y_lo : y_hi) = y;
        }
        const double roof = 0.5 * (y_lo + y_hi);
        // Width between the roots one millimetre below the roof: the narrowest free span across
        // the gap, along the line from the roots' midpoint out to the entrance.
        const double yw = roof - 1.0;
        double width = 0.0;
        for (double s = 0.0; s <= s_out; s += 0.1) {
            const double px = mx + s * ox, pz = mz + s * oz;
            if (f(px, yw, pz) <= 0.0) continue;
            double span = 0.0;
            bool closed = true;
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double u = 0.0;
                while (f(px + sgn * u * tx, yw, pz + sgn * u * tz) > 0.0 && u < 8.0) u += 0.01;
                closed = closed && u < 8.0;
                span += u;
            }
            if (closed && (width == 0.0 || span < width)) width = span;
        }
        Furcation fu;
        fu.side = sp.side;
        fu.entrance = 1e-3 * Vec3(mx + s_out * ox, roof, mz + s_out * oz);
        fu.inward = Vec3(-ox, 0.0, -oz);
        fu.roof_height = 1e-3 * roof;
        fu.width = 1e-3 * width;
        furcations_.push_back(fu);
    }
}

}  // namespace sulcus
