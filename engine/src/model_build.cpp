// Builds the immutable model of the renderer: the convex tool's features and each object's
// world-placed mesh, adjacency and BVH.
#include "sulcus/engine/renderer.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace sulcus {

namespace {

// Largest coordinate magnitude of a mesh, for scale-aware tolerances.
double mesh_scale(const TriMesh& m) {
    double s = 0.0;
    for (const Vec3& v : m.vertices) s = std::max(s, std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))));
    return std::max(s, 1e-9);
}

// The capsule around the principal axis of the vertices (power iteration on their covariance).
void set_bounding_capsule(ModelTool& tool) {
    const auto& vs = tool.mesh.vertices;
    Vec3 c(0.0);
    for (const Vec3& v : vs) c += v;
    c /= double(vs.size());
    glm::dmat3 cov(0.0);
    for (const Vec3& v : vs) cov += glm::outerProduct(v - c, v - c);
    Vec3 axis(1.0, 0.7, 0.3);
    for (int it = 0; it < 64; ++it) {
        const Vec3 next = cov * axis;
        const double len = glm::length(next);
        if (!(len > 0.0)) break;
        axis = next / len;
    }
    axis = glm::normalize(axis);
    double lo = 1e300, hi = -1e300;
    for (const Vec3& v : vs) {
        lo = std::min(lo, glm::dot(v - c, axis));
        hi = std::max(hi, glm::dot(v - c, axis));
    }
    constexpr int K = kToolCapsules;
    for (int k = 0; k <= K; ++k) tool.capsule_points[size_t(k)] = c + (lo + (hi - lo) * k / K) * axis;
    // The tool between two cut planes is the hull of its vertices there and of its edges' crossings
    // of the planes; the largest distance to the axis is at one of those points.
    auto radial = [&](const Vec3& x) { return glm::length((x - c) - glm::dot(x - c, axis) * axis); };
    auto slab_of = [&](double s) { return std::clamp(int(std::floor((s - lo) / (hi - lo) * K)), 0, K - 1); };
    std::array<double, K> r{};
    for (const Vec3& v : vs) {
        const double s = glm::dot(v - c, axis);
        r[size_t(slab_of(s))] = std::max(r[size_t(slab_of(s))], radial(v));
        // A vertex on a cut belongs to both slabs.
        const double u = (s - lo) / (hi - lo) * K;
        const int near = int(std::lround(u));
        if (std::abs(u - near) < 1e-9 && near > 0 && near < K) {
            r[size_t(near - 1)] = std::max(r[size_t(near - 1)], radial(v));
            r[size_t(near)] = std::max(r[size_t(near)], radial(v));
        }
    }
    for (const auto& tri : tool.mesh.triangles)
        for (int e = 0; e < 3; ++e) {
            const Vec3& a = vs[tri[size_t(e)]];
            const Vec3& b = vs[tri[size_t((e + 1) % 3)]];
            const double sa = glm::dot(a - c, axis), sb = glm::dot(b - c, axis);
            for (int k = 1; k < K; ++k) {
                const double cut = lo + (hi - lo) * k / K;
                if ((sa - cut) * (sb - cut) >= 0.0) continue;
                const double rr = radial(a + (b - a) * ((cut - sa) / (sb - sa)));
                r[size_t(k - 1)] = std::max(r[size_t(k - 1)], rr);
                r[size_t(k)] = std::max(r[size_t(k)], rr);
            }
        }
    // A hair over, so rounding never puts a point outside.
    for (int k = 0; k < K; ++k) tool.capsule_radii_m[size_t(k)] = r[size_t(k)] * (1.0 + 1e-9) + 1e-12;
    const double widest = *std::max_element(tool.capsule_radii_m.begin(), tool.capsule_radii_m.end());
    tool.capsule_count = (hi - lo) > 4.0 * widest ? K : 0;
}

std::string build_tool(const TriMesh& mesh, ModelTool& tool) {
    tool.mesh = mesh;
    tool.topology = build_topology(mesh);
    const double tol = 1e-9 * mesh_scale(mesh);
    // Distinct face planes: coplanar triangles share one plane.
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3& n = tool.topology.triangle_normals[t];
        const double d = glm::dot(n, mesh.vertices[mesh.triangles[t][0]]);
        bool found = false;
        for (size_t f = 0; f < tool.face_normals.size(); ++f) {
            if (glm::length(tool.face_normals[f] - n) < 1e-9 && std::abs(tool.face_offsets[f] - d) <= tol) {
                found = true;
                break;
            }
        }
        if (!found) {
            tool.face_normals.push_back(n);
            tool.face_offsets.push_back(d);
        }
    }
    // Convexity: every vertex on the inner side of every face plane.
    for (size_t f = 0; f < tool.face_normals.size(); ++f) {
        for (size_t v = 0; v < mesh.vertices.size(); ++v) {
            const double s = glm::dot(tool.face_normals[f], mesh.vertices[v]) - tool.face_offsets[f];
            if (s > tol)
                return "tool mesh is not convex: vertex " + std::to_string(v) + " lies " + std::to_string(s) +
                       " m outside face plane " + std::to_string(f);
        }
    }
    for (size_t f = 0; f < tool.face_normals.size(); ++f) {
        double lo = tool.face_offsets[f];
        for (const Vec3& v : mesh.vertices) lo = std::min(lo, glm::dot(tool.face_normals[f], v));
        tool.face_depths.push_back(tool.face_offsets[f] - lo);
    }
    for (const MeshEdge& e : tool.topology.edges)
        if (e.convexity != Convexity::Flat) {
            tool.edges.push_back({e.v[0], e.v[1]});
            tool.edge_normals.push_back({tool.topology.triangle_normals[e.tri[0]], tool.topology.triangle_normals[e.tri[1]]});
        }
    for (const Vec3& v : mesh.vertices) tool.radius_m = std::max(tool.radius_m, glm::length(v));
    set_bounding_capsule(tool);
    return "";
}

}  // namespace

ModelBuild build_model(const TriMesh& tool_mesh, const std::vector<SceneObject>& objects,
                       const RendererSettings& settings) {
    ModelBuild out;
    if (std::string err = validate_mesh(tool_mesh); !err.empty()) {
        out.error = "tool: " + err;
        return out;
    }
    auto model = std::make_unique<Model>();
    model->settings = settings;
    if (std::string err = build_tool(tool_mesh, model->tool); !err.empty()) {
        out.error = "tool: " + err;
        return out;
    }
    if (objects.size() > 65535) {
        out.error = "too many objects (at most 65535)";
        return out;
    }
    for (const SceneObject& so : objects) {
        if (std::string err = validate_mesh(so.mesh); !err.empty()) {
            out.error = so.name + ": " + err;
            return out;
        }
        ModelObject o;
        o.name = so.name;
        o.pose = so.pose;
        o.mesh = so.mesh;
        for (Vec3& v : o.mesh.vertices) v = so.pose.apply(v);
        o.topology = build_topology(o.mesh);
        o.bvh = Bvh(o.mesh);
        model->objects.push_back(std::move(o));
    }
    out.model = std::move(model);
    return out;
}

}  // namespace sulcus
