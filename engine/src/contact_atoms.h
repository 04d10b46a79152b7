// Exact evaluation of principal-contact atoms and their gradients (seed paper eq. 6 and 7).
//
// The variables are x = [dp, theta]: the graphic tool's pose is p = p0 + dp, R = Exp(theta) R0,
// about the previous graphic pose (p0, R0). A tool point a (local) is at w = p + R a. For a
// perturbation d of theta the world rotation is omega = J_l(theta) d, so
//     dw = d_dp + omega x r,   r = R a,
// and a gradient with respect to omega maps to theta by J_l^T.
#pragma once

#include "sulcus/engine/renderer.h"
#include "so3.h"

namespace sulcus {

// The tool pose at a point x of the variables, with what the gradients need.
struct ToolPoseAt {
    Vec3 p;
    Quat q;
    Mat3 R;
    Mat3 Jl;  // left Jacobian at theta
};

inline ToolPoseAt tool_pose_at(const Pose& base, const double x[6]) {
    ToolPoseAt t;
    const Vec3 theta(x[3], x[4], x[5]);
    t.p = base.position + Vec3(x[0], x[1], x[2]);
    t.q = glm::normalize(quat_exp(theta) * base.orientation);
    t.R = glm::mat3_cast(t.q);
    t.Jl = left_jacobian(theta);
    return t;
}

// Writes [grad_p, J_l^T grad_omega] into grad.
inline void pack_gradient(const ToolPoseAt& t, const Vec3& gp, const Vec3& gw, double grad[6]) {
    const Vec3 gt = glm::transpose(t.Jl) * gw;
    grad[0] = gp.x; grad[1] = gp.y; grad[2] = gp.z;
    grad[3] = gt.x; grad[4] = gt.y; grad[5] = gt.z;
}

// Value of the atom (metres; >= 0 means not penetrating) and, when grad != nullptr, its gradient
// with respect to x.
inline double evaluate_atom(const Model& model, const Atom& atom, const ToolPoseAt& t, double* grad) {
    const ModelTool& tool = model.tool;
    const ModelObject& obj = model.objects[atom.object];
    switch (atom.kind) {
        case AtomKind::VertexFace: {
            // eq. 6: g = n_o . (p_t - p_o), n_o fixed in the world.
            const auto& tri = obj.mesh.triangles[atom.object_triangle];
            const Vec3 n = atom.sign * obj.topology.triangle_normals[atom.object_triangle];
            const Vec3 r = t.R * tool.mesh.vertices[atom.tool_vertex];
            const Vec3 w = t.p + r;
            if (grad) pack_gradient(t, n, glm::cross(r, n), grad);
            return glm::dot(n, w - obj.mesh.vertices[tri[0]]);
        }
        case AtomKind::FaceVertex: {
            // eq. 6 with the roles swapped: the plane moves with the tool.
            // g = m . (v - p) - d, m = R m_local.
            const Vec3 m = t.R * tool.face_normals[atom.tool_face];
            const Vec3& v = obj.mesh.vertices[atom.object_vertex];
            const Vec3 d = v - t.p;
            if (grad) pack_gradient(t, -m, glm::cross(m, d), grad);
            return glm::dot(m, d) - tool.face_offsets[atom.tool_face];
        }
        case AtomKind::EdgeEdge: {
            // eq. 7: the dynamic plane through both edges, n = s (E_o x E_t)/|E_o x E_t|,
            // g = n . (a - v) with a on the tool edge and v on the object edge.
            const auto& te = tool.edges[atom.tool_edge];
            const auto& oe = obj.topology.edges[atom.object_edge];
            const Vec3 r = t.R * tool.mesh.vertices[te[0]];
            const Vec3 a = t.p + r;
            const Vec3 Et = t.R * (tool.mesh.vertices[te[1]] - tool.mesh.vertices[te[0]]);
            const Vec3& v = obj.mesh.vertices[oe.v[0]];
            const Vec3 Eo = obj.mesh.vertices[oe.v[1]] - v;
            const Vec3 u = glm::cross(Eo, Et);
            const double ul = glm::length(u);
            const Vec3 nh = u / ul;
            const Vec3 n = atom.sign * nh;
            const Vec3 d = a - v;
            if (grad) {
                // dn = s (I - nh nh^T) [(Eo.Et) I - Et Eo^T] omega / |u|
                const Vec3 dp = d - glm::dot(d, nh) * nh;
                const Vec3 gn = (atom.sign / ul) * (glm::dot(Eo, Et) * dp - glm::dot(dp, Et) * Eo);
                pack_gradient(t, n, glm::cross(r, n) + gn, grad);
            }
            return glm::dot(n, d);
        }
        case AtomKind::FixedAxis: {
            const Vec3& n = atom.axis;
            const Vec3 r = t.R * tool.mesh.vertices[atom.tool_vertex];
            if (grad) pack_gradient(t, n, glm::cross(r, n), grad);
            return glm::dot(n, t.p + r - obj.mesh.vertices[atom.object_vertex]);
        }
    }
    return 0.0;
}

}  // namespace sulcus
