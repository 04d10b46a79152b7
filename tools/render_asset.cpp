// Draws a content asset (.glb) to a PNG with a small CPU rasterizer, so that the docs can show
// generated teeth, cases and probes without an outside renderer:
//   render_asset IN.glb OUT.png [--size WxH] [--view front|side|top|iso|lingual] [--yaw DEG]
//       [--pitch DEG] [--roll DEG] [--fit NODE-SUBSTRING]... [--fit-box-mm X0 Y0 Z0 X1 Y1 Z1]
//       [--hide NODE-SUBSTRING]... [--alpha NODE-SUBSTRING=A]... [--ssaa N] [--ortho] [--flat]
//       [--zoom F]
// Views look at the asset frame (+Y up): front from +Z, side from +X, lingual from -Z, top from
// +Y (with -Z up in the picture), iso from yaw 35, pitch 25 degrees. --yaw (about +Y, from +Z
// toward +X) and --pitch (elevation) replace the view's angles; --roll turns the picture.
// The camera frames the visible nodes, or the nodes matching --fit, or the visible geometry inside
// the --fit-box-mm box (asset frame, millimetres). Output is deterministic: same input, same bytes.
#include "sulcus/content/gltf_io.h"

#include <stb/stb_image_write.h>  // implementation in Debian's libstb

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace {

using sulcus::Vec3;

struct Options {
    std::string in, out;
    int width = 900, height = 600;
    double yaw_deg = 35.0, pitch_deg = 25.0, roll_deg = 0.0;
    std::vector<std::string> fit, hide;
    std::vector<std::pair<std::string, double>> alpha;
    bool fit_box = false;
    Vec3 box_lo, box_hi;  // metres
    int ssaa = 2;
    bool ortho = false, flat = false;
    double zoom = 1.0;
};

[[noreturn]] void fail(const std::string& what, int code = 2) {
    std::fprintf(stderr, "render_asset: %s\n", what.c_str());
    std::exit(code);
}

double parse_number(const std::string& flag, const std::string& text) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(v)) fail(flag + ": '" + text + "' is not a number");
    return v;
}

Options parse_args(int argc, char** argv) {
    Options o;
    std::vector<std::string> positional;
    bool yaw_set = false, pitch_set = false;
    double view_yaw = 35.0, view_pitch = 25.0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) fail(a + " needs a value");
            return argv[++i];
        };
        if (a == "--size") {
            const std::string v = value();
            int w = 0, h = 0;
            char tail = 0;
            if (std::sscanf(v.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 ||
                h > 8192)
                fail("--size: '" + v + "' is not WxH with 16..8192 pixels each");
            o.width = w;
            o.height = h;
        } else if (a == "--view") {
            const std::string v = value();
            if (v == "front") view_yaw = 0, view_pitch = 0;
            else if (v == "side") view_yaw = 90, view_pitch = 0;
            else if (v == "lingual") view_yaw = 180, view_pitch = 0;
            else if (v == "top") view_yaw = 0, view_pitch = 90;
            else if (v == "iso") view_yaw = 35, view_pitch = 25;
            else fail("--view: '" + v + "' is not one of front, side, top, iso, lingual");
        } else if (a == "--yaw") {
            o.yaw_deg = parse_number(a, value());
            yaw_set = true;
        } else if (a == "--pitch") {
            o.pitch_deg = parse_number(a, value());
            if (std::abs(o.pitch_deg) > 90.0) fail("--pitch: must be within [-90, 90] degrees");
            pitch_set = true;
        } else if (a == "--roll") {
            o.roll_deg = parse_number(a, value());
        } else if (a == "--fit") {
            o.fit.push_back(value());
        } else if (a == "--hide") {
            o.hide.push_back(value());
        } else if (a == "--alpha") {
            const std::string v = value();
            const auto eq = v.rfind('=');
            if (eq == std::string::npos || eq == 0) fail("--alpha: '" + v + "' is not NODE-SUBSTRING=A");
            const double alpha = parse_number(a, v.substr(eq + 1));
            if (alpha < 0.0 || alpha > 1.0) fail("--alpha: A must be within [0, 1]");
            o.alpha.push_back({v.substr(0, eq), alpha});
        } else if (a == "--fit-box-mm") {
            double c[6];
            for (double& x : c) x = parse_number(a, value()) * 1e-3;
            o.box_lo = Vec3(std::min(c[0], c[3]), std::min(c[1], c[4]), std::min(c[2], c[5]));
            o.box_hi = Vec3(std::max(c[0], c[3]), std::max(c[1], c[4]), std::max(c[2], c[5]));
            o.fit_box = true;
        } else if (a == "--ssaa") {
            const double n = parse_number(a, value());
            if (n != std::floor(n) || n < 1 || n > 8) fail("--ssaa: N must be a whole number 1..8");
            o.ssaa = int(n);
        } else if (a == "--zoom") {
            o.zoom = parse_number(a, value());
            if (o.zoom <= 0.0) fail("--zoom: F must be positive");
        } else if (a == "--ortho") {
            o.ortho = true;
        } else if (a == "--flat") {
            o.flat = true;
        } else if (a.size() > 1 && a[0] == '-') {
            fail("unknown option '" + a + "'");
        } else {
            positional.push_back(a);
        }
    }
    if (positional.size() != 2) fail("usage: render_asset IN.glb OUT.png [options] (see the source's header)");
    o.in = positional[0];
    o.out = positional[1];
    if (!yaw_set) o.yaw_deg = view_yaw;
    if (!pitch_set) o.pitch_deg = view_pitch;
    return o;
}

bool matches_any(const std::string& name, const std::vector<std::string>& subs) {
    for (const std::string& s : subs)
        if (name.find(s) != std::string::npos) return true;
    return false;
}

// A triangle ready to draw: asset-frame corners, per-corner normals, colour and opacity.
struct Triangle {
    Vec3 p[3];
    Vec3 n[3];
    const sulcus::Material* material;
    double alpha;
};

// Per-corner normals: the area-weighted average of the faces around the vertex whose normals lie
// within the crease angle of this face, so that smooth surfaces shade smoothly and sharp edges
// (a tip's rim, a band's edge) stay sharp.
void corner_normals(const sulcus::TriMesh& m, std::vector<std::array<Vec3, 3>>& out, bool flat) {
    const size_t nt = m.triangles.size();
    std::vector<Vec3> area_normal(nt), unit(nt);
    for (size_t t = 0; t < nt; ++t) {
        const auto& tri = m.triangles[t];
        const Vec3 c = glm::cross(m.vertices[tri[1]] - m.vertices[tri[0]], m.vertices[tri[2]] - m.vertices[tri[0]]);
        area_normal[t] = c;
        const double len = glm::length(c);
        unit[t] = len > 0.0 ? c / len : Vec3(0.0);
    }
    out.assign(nt, {});
    if (flat) {
        for (size_t t = 0; t < nt; ++t) out[t] = {unit[t], unit[t], unit[t]};
        return;
    }
    // Faces around each vertex (CSR).
    std::vector<uint32_t> offset(m.vertices.size() + 1, 0), faces(3 * nt);
    for (const auto& tri : m.triangles)
        for (uint32_t v : tri) ++offset[v + 1];
    for (size_t v = 0; v < m.vertices.size(); ++v) offset[v + 1] += offset[v];
    std::vector<uint32_t> fill(offset.begin(), offset.end() - 1);
    for (size_t t = 0; t < nt; ++t)
        for (uint32_t v : m.triangles[t]) faces[fill[v]++] = uint32_t(t);
    const double crease_cos = std::cos(50.0 * std::numbers::pi / 180.0);
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.triangles[t][k];
            Vec3 sum(0.0);
            for (uint32_t i = offset[v]; i < offset[v + 1]; ++i)
                if (glm::dot(unit[faces[i]], unit[t]) >= crease_cos) sum += area_normal[faces[i]];
            const double len = glm::length(sum);
            out[t][k] = len > 0.0 ? sum / len : unit[t];
        }
}

// Camera: orthonormal basis (right, up, back toward the viewer), eye position, and the image
// mapping screen = scale * projected + offset (projected = x/depth, y/depth or x, y when ortho).
struct Camera {
    Vec3 right, up, back, eye;
    bool ortho = false;
    double near = 0.0;
    double scale = 1.0, off_x = 0.0, off_y = 0.0;

    Vec3 to_camera(const Vec3& p) const {
        const Vec3 d = p - eye;
        return Vec3(glm::dot(d, right), glm::dot(d, up), glm::dot(d, back));
    }
    Vec3 dir_to_camera(const Vec3& n) const { return Vec3(glm::dot(n, right), glm::dot(n, up), glm::dot(n, back)); }
    // Projected (x, y) of a camera-space point in front of the eye.
    void project(const Vec3& c, double* x, double* y) const {
        if (ortho) {
            *x = c.x;
            *y = c.y;
        } else {
            *x = c.x / -c.z;
            *y = c.y / -c.z;
        }
    }
};

Camera make_camera(const Options& o, const std::vector<Vec3>& fit_points, int w, int h) {
    const double deg = std::numbers::pi / 180.0;
    const double yaw = o.yaw_deg * deg, pitch = o.pitch_deg * deg, roll = o.roll_deg * deg;
    Camera cam;
    cam.ortho = o.ortho;
    cam.back = Vec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
    const Vec3 r0(std::cos(yaw), 0.0, -std::sin(yaw));  // horizontal right; defined even looking straight down
    const Vec3 u0 = glm::cross(cam.back, r0);
    cam.right = std::cos(roll) * r0 + std::sin(roll) * u0;
    cam.up = -std::sin(roll) * r0 + std::cos(roll) * u0;

    sulcus::Aabb box;
    for (const Vec3& p : fit_points) box.grow(p);
    const Vec3 centre = box.center();
    double radius = 0.0;
    for (const Vec3& p : fit_points) radius = std::max(radius, glm::length(p - centre));
    radius = std::max(radius, 1e-6);
    // A 25-degree field of view around the bounding sphere: mild perspective.
    const double distance = radius / std::tan(12.5 * deg);
    cam.eye = centre + distance * cam.back;
    cam.near = 0.02 * distance;

    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const Vec3& p : fit_points) {
        double x, y;
        cam.project(cam.to_camera(p), &x, &y);
        x0 = std::min(x0, x), x1 = std::max(x1, x);
        y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    const double margin = 0.06;
    const double sx = (1.0 - 2.0 * margin) * w / std::max(x1 - x0, 1e-12);
    const double sy = (1.0 - 2.0 * margin) * h / std::max(y1 - y0, 1e-12);
    cam.scale = std::min(sx, sy) * o.zoom;
    // Screen y grows downward.
    cam.off_x = 0.5 * w - cam.scale * 0.5 * (x0 + x1);
    cam.off_y = 0.5 * h + cam.scale * 0.5 * (y0 + y1);
    return cam;
}

// A clipped, camera-space vertex.
struct CamVertex {
    Vec3 c;  // camera-space position
    Vec3 n;  // camera-space normal
};

struct Framebuffer {
    int w, h;
    std::vector<Vec3> colour;  // linear RGB
    std::vector<double> depth;
};

double srgb_to_linear(double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); }
double linear_to_srgb(double l) {
    l = std::clamp(l, 0.0, 1.0);
    return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

// Lambert + Blinn-Phong from a key and a fill light plus ambient, lights fixed to the camera.
Vec3 shade(const sulcus::Material& m, Vec3 n, const Vec3& pos, bool ortho) {
    const Vec3 view = ortho ? Vec3(0.0, 0.0, 1.0) : glm::normalize(-pos);
    n = glm::normalize(n);
    if (glm::dot(n, view) < 0.0) n = -n;  // two-sided: open parts and inner walls show their back
    const Vec3 base(m.base_color[0], m.base_color[1], m.base_color[2]);
    const double metal = std::clamp(m.metallic, 0.0, 1.0);
    const double rough = std::clamp(m.roughness, 0.04, 1.0);
    // Blinn-Phong exponent from the glTF roughness (alpha = roughness^2).
    const double a2 = rough * rough * rough * rough;
    const double shininess = std::clamp(2.0 / a2 - 2.0, 2.0, 4096.0);
    const Vec3 diffuse = base * (1.0 - 0.45 * metal);
    const Vec3 spec_colour = glm::mix(Vec3(0.5), base + Vec3(0.3), metal) * (1.0 - 0.75 * rough);
    struct Light {
        Vec3 dir;
        double power;
    };
    static const Light lights[] = {{glm::normalize(Vec3(-0.45, 0.65, 0.62)), 0.8},
                                   {glm::normalize(Vec3(0.7, -0.15, 0.45)), 0.3}};
    // Hemispherical ambient: more from above than from below, which keeps the form readable.
    Vec3 out = diffuse * (0.08 + 0.12 * (0.5 + 0.5 * n.y));
    for (const Light& l : lights) {
        const double nl = std::max(0.0, glm::dot(n, l.dir));
        const Vec3 half = glm::normalize(l.dir + view);
        const double nh = std::max(0.0, glm::dot(n, half));
        // Normalised so that rough surfaces get a broad dim highlight and smooth ones a sharp one.
        const double spec = nl > 0.0 ? std::pow(nh, shininess) * (shininess + 8.0) / (8.0 * 16.0) : 0.0;
        out += l.power * (diffuse * nl + spec_colour * std::min(spec, 4.0));
    }
    return out;
}

// Rasterizes one camera-space triangle (all corners at depth >= near).
void raster(Framebuffer& fb, const Camera& cam, const CamVertex v[3], const sulcus::Material& m, double alpha,
            bool transparent) {
    double sx[3], sy[3], depth[3];
    for (int k = 0; k < 3; ++k) {
        double x, y;
        cam.project(v[k].c, &x, &y);
        sx[k] = cam.scale * x + cam.off_x;
        sy[k] = -cam.scale * y + cam.off_y;
        depth[k] = -v[k].c.z;
    }
    const double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sy[1] - sy[0]) * (sx[2] - sx[0]);
    if (!(std::abs(area) > 0.0)) return;
    const int xa = std::max(0, int(std::floor(std::min({sx[0], sx[1], sx[2]}))));
    const int xb = std::min(fb.w - 1, int(std::ceil(std::max({sx[0], sx[1], sx[2]}))));
    const int ya = std::max(0, int(std::floor(std::min({sy[0], sy[1], sy[2]}))));
    const int yb = std::min(fb.h - 1, int(std::ceil(std::max({sy[0], sy[1], sy[2]}))));
    if (xa > xb || ya > yb) return;
    // Edge k runs between the corners other than k. Each edge is evaluated from its
    // lexicographically smaller end, so a shared edge gives exactly opposite values in its two
    // triangles; a sample exactly on it belongs to the triangle where the sign is +1.
    struct Edge {
        double ax, ay, bx, by, sign;
    };
    Edge e[3];
    for (int k = 0; k < 3; ++k) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        double s = area > 0.0 ? 1.0 : -1.0;
        if (sx[j] < sx[i] || (sx[j] == sx[i] && sy[j] < sy[i])) {
            std::swap(i, j);
            s = -s;
        }
        e[k] = {sx[i], sy[i], sx[j], sy[j], s};
    }
    const double inv_area = 1.0 / std::abs(area);
    for (int y = ya; y <= yb; ++y) {
        const double py = y + 0.5;
        for (int x = xa; x <= xb; ++x) {
            const double px = x + 0.5;
            double b[3];
            bool inside = true;
            for (int k = 0; k < 3 && inside; ++k) {
                const double f = ((e[k].bx - e[k].ax) * (py - e[k].ay) - (e[k].by - e[k].ay) * (px - e[k].ax)) * e[k].sign;
                if (f < 0.0 || (f == 0.0 && e[k].sign < 0.0)) inside = false;
                b[k] = f * inv_area;
            }
            if (!inside) continue;
            // Perspective-correct weights.
            double w[3];
            if (cam.ortho) {
                for (int k = 0; k < 3; ++k) w[k] = b[k];
            } else {
                double sum = 0.0;
                for (int k = 0; k < 3; ++k) sum += (w[k] = b[k] / depth[k]);
                for (int k = 0; k < 3; ++k) w[k] /= sum;
            }
            const double z = w[0] * depth[0] + w[1] * depth[1] + w[2] * depth[2];
            const size_t idx = size_t(y) * fb.w + x;
            if (!(z < fb.depth[idx])) continue;
            const Vec3 pos = w[0] * v[0].c + w[1] * v[1].c + w[2] * v[2].c;
            const Vec3 n = w[0] * v[0].n + w[1] * v[1].n + w[2] * v[2].n;
            const Vec3 c = shade(m, n, pos, cam.ortho);
            if (transparent) {
                fb.colour[idx] = alpha * c + (1.0 - alpha) * fb.colour[idx];
            } else {
                fb.colour[idx] = c;
                fb.depth[idx] = z;
            }
        }
    }
}

// Clips a triangle against the near plane (depth >= near) and draws the pieces.
void draw(Framebuffer& fb, const Camera& cam, const Triangle& t, bool transparent) {
    CamVertex in[3];
    for (int k = 0; k < 3; ++k) in[k] = {cam.to_camera(t.p[k]), cam.dir_to_camera(t.n[k])};
    auto depth = [](const CamVertex& v) { return -v.c.z; };
    CamVertex poly[4];
    int count = 0;
    for (int k = 0; k < 3; ++k) {
        const CamVertex& a = in[k];
        const CamVertex& b = in[(k + 1) % 3];
        const bool ina = depth(a) >= cam.near, inb = depth(b) >= cam.near;
        if (ina) poly[count++] = a;
        if (ina != inb) {
            const double s = (cam.near - depth(a)) / (depth(b) - depth(a));
            poly[count++] = {a.c + s * (b.c - a.c), a.n + s * (b.n - a.n)};
        }
    }
    if (count < 3) return;
    const CamVertex first[3] = {poly[0], poly[1], poly[2]};
    raster(fb, cam, first, *t.material, t.alpha, transparent);
    if (count == 4) {
        const CamVertex second[3] = {poly[0], poly[2], poly[3]};
        raster(fb, cam, second, *t.material, t.alpha, transparent);
    }
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse_args(argc, argv);
    const sulcus::AssetLoad load = sulcus::read_glb(o.in);
    if (!load.ok()) fail(load.error);
    const sulcus::Asset& asset = load.asset;
    static const sulcus::Material default_material;

    // Triangles of the visible nodes in the asset frame; fit points collected on the way.
    std::vector<Triangle> opaque, clear;
    std::vector<Vec3> fit_points, visible_points;
    for (const sulcus::AssetNode& node : asset.nodes) {
        if (matches_any(node.name, o.hide)) continue;
        double node_alpha = 1.0;
        for (const auto& [sub, a] : o.alpha)
            if (node.name.find(sub) != std::string::npos) node_alpha = a;
        if (node_alpha <= 0.0) continue;
        const bool fit_node = !o.fit.empty() && matches_any(node.name, o.fit);
        for (const sulcus::MeshPart& part : node.parts) {
            const sulcus::Material* mat = &default_material;
            if (part.material >= 0 && size_t(part.material) < asset.materials.size()) mat = &asset.materials[part.material];
            const double alpha = node_alpha * std::clamp(mat->base_color[3], 0.0, 1.0);
            std::vector<std::array<Vec3, 3>> normals;
            corner_normals(part.mesh, normals, o.flat);
            std::vector<Vec3> placed(part.mesh.vertices.size());
            for (size_t i = 0; i < placed.size(); ++i) {
                placed[i] = node.pose.apply(part.mesh.vertices[i]);
                visible_points.push_back(placed[i]);
                if (fit_node) fit_points.push_back(placed[i]);
                if (o.fit_box && glm::all(glm::greaterThanEqual(placed[i], o.box_lo)) &&
                    glm::all(glm::lessThanEqual(placed[i], o.box_hi)))
                    fit_points.push_back(placed[i]);
            }
            for (size_t t = 0; t < part.mesh.triangles.size(); ++t) {
                Triangle tri;
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = part.mesh.triangles[t][k];
                    if (v >= placed.size()) fail(o.in + ": node '" + node.name + "': vertex index out of range");
                    tri.p[k] = placed[v];
                    tri.n[k] = node.pose.rotate(normals[t][k]);
                }
                tri.material = mat;
                tri.alpha = alpha;
                (alpha < 1.0 ? clear : opaque).push_back(tri);
            }
        }
    }
    if (opaque.empty() && clear.empty()) fail(o.in + ": nothing to draw (no visible triangles)");
    if (o.fit_box && fit_points.empty()) {
        // Nothing inside the box: frame the box itself.
        for (int c = 0; c < 8; ++c)
            fit_points.push_back(Vec3(c & 1 ? o.box_hi.x : o.box_lo.x, c & 2 ? o.box_hi.y : o.box_lo.y,
                                      c & 4 ? o.box_hi.z : o.box_lo.z));
    }
    if (!o.fit.empty() && !o.fit_box && fit_points.empty()) fail("--fit: no visible node matches");
    if (fit_points.empty()) fit_points = std::move(visible_points);

    const int w = o.width * o.ssaa, h = o.height * o.ssaa;
    const Camera cam = make_camera(o, fit_points, w, h);
    Framebuffer fb{w, h, std::vector<Vec3>(size_t(w) * h), std::vector<double>(size_t(w) * h, 1e300)};
    // Background: white at the top to light grey at the bottom.
    for (int y = 0; y < h; ++y) {
        const double g = srgb_to_linear(1.0 - 0.16 * y / (h - 1));
        for (int x = 0; x < w; ++x) fb.colour[size_t(y) * w + x] = Vec3(g);
    }
    for (const Triangle& t : opaque) draw(fb, cam, t, false);
    // Transparent triangles back to front (by centroid depth; ties keep file order).
    std::vector<std::pair<double, size_t>> order(clear.size());
    for (size_t i = 0; i < clear.size(); ++i)
        order[i] = {-cam.to_camera((clear[i].p[0] + clear[i].p[1] + clear[i].p[2]) / 3.0).z, i};
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (const auto& [d, i] : order) draw(fb, cam, clear[i], true);

    // Box-filter the supersamples in linear light, then encode as sRGB.
    std::vector<unsigned char> pixels(size_t(o.width) * o.height * 3);
    const double inv = 1.0 / (o.ssaa * o.ssaa);
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
            Vec3 sum(0.0);
            for (int j = 0; j < o.ssaa; ++j)
                for (int i = 0; i < o.ssaa; ++i) sum += fb.colour[size_t(y * o.ssaa + j) * w + (x * o.ssaa + i)];
            for (int c = 0; c < 3; ++c)
                pixels[(size_t(y) * o.width + x) * 3 + c] =
                    (unsigned char)std::lround(255.0 * linear_to_srgb(sum[c] * inv));
        }
    stbi_write_png_compression_level = 9;
    if (!stbi_write_png(o.out.c_str(), o.width, o.height, 3, pixels.data(), o.width * 3))
        fail(o.out + ": cannot write the PNG", 1);
    return 0;
}
