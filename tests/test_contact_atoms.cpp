// Each constraint atom's value and gradient against finite differences, and the rotation maps.
#include "contact_atoms.h"
#include "scene_helpers.h"
#include "so3.h"

#include <random>

using namespace sulcus;
using namespace sulcus::test;

namespace {

Vec3 random_vec(std::mt19937_64& rng, double scale) {
    std::uniform_real_distribution<double> u(-scale, scale);
    return Vec3(u(rng), u(rng), u(rng));
}

Quat random_quat(std::mt19937_64& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    return glm::normalize(Quat(n(rng), n(rng), n(rng), n(rng)));
}

// A tool and an object with convex edges and vertices (a wedge), and one atom of each kind.
struct Fixture {
    std::unique_ptr<Model> model;
    std::vector<Atom> atoms;

    Fixture() {
        const TriMesh tool = make_box(Vec3(2 * mm, 3 * mm, 1.5 * mm));
        const TriMesh wedge = make_wedge(0.6, 10 * mm, 8 * mm);
        model = model_of(tool, {object("wedge", wedge)});
        const MeshTopology& topo = model->objects[0].topology;
        for (uint32_t tv = 0; tv < 8; tv += 3) {
            Atom a;
            a.kind = AtomKind::VertexFace;
            a.tool_vertex = tv;
            a.object_triangle = tv % model->objects[0].mesh.triangles.size();
            a.sign = tv % 2 ? -1.0 : 1.0;
            atoms.push_back(a);
        }
        for (uint32_t f = 0; f < model->tool.face_normals.size(); f += 2) {
            Atom a;
            a.kind = AtomKind::FaceVertex;
            a.tool_face = f;
            a.object_vertex = f % model->objects[0].mesh.vertices.size();
            atoms.push_back(a);
        }
        for (uint32_t e = 0; e < topo.edges.size(); ++e) {
            if (topo.edges[e].convexity != Convexity::Convex) continue;
            for (uint32_t te = 0; te < model->tool.edges.size(); te += 5) {
                Atom a;
                a.kind = AtomKind::EdgeEdge;
                a.object_edge = e;
                a.tool_edge = te;
                a.sign = (e + te) % 2 ? 1.0 : -1.0;
                atoms.push_back(a);
            }
        }
        Atom fa;
        fa.kind = AtomKind::FixedAxis;
        fa.tool_vertex = 5;
        fa.object_vertex = 2;
        fa.axis = glm::normalize(Vec3(0.3, 1.0, -0.2));
        atoms.push_back(fa);
    }
};

}  // namespace

TEST(Rotation, ExpLogRoundTrip) {
    std::mt19937_64 rng(7);
    for (int i = 0; i < 1000; ++i) {
        Vec3 v = random_vec(rng, 3.0);
        if (glm::length(v) >= 3.14) continue;
        const Vec3 back = quat_log(quat_exp(v));
        EXPECT_NEAR(glm::length(back - v), 0.0, 1e-12);
    }
    EXPECT_NEAR(glm::length(quat_log(quat_exp(Vec3(1e-12, 0, 0))) - Vec3(1e-12, 0, 0)), 0.0, 1e-24);
}

TEST(Rotation, LeftJacobianMatchesExponential) {
    std::mt19937_64 rng(8);
    for (int i = 0; i < 500; ++i) {
        const Vec3 phi = random_vec(rng, 2.0);
        const Vec3 d = random_vec(rng, 1e-6);
        const Quat lhs = quat_exp(phi + d);
        const Quat rhs = quat_exp(left_jacobian(phi) * d) * quat_exp(phi);
        const Vec3 err = quat_log(lhs * glm::conjugate(rhs));
        EXPECT_LT(glm::length(err), 1e-11) << "phi " << phi.x << " " << phi.y << " " << phi.z;
    }
}

TEST(ContactAtoms, GradientsMatchFiniteDifferences) {
    Fixture fx;
    ASSERT_TRUE(fx.model);
    std::mt19937_64 rng(42);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Pose base{random_vec(rng, 8 * mm), random_quat(rng)};
        double x[6];
        const Vec3 dp = random_vec(rng, 2 * mm);
        const Vec3 dt = random_vec(rng, trial % 4 == 0 ? 1.0 : 0.05);
        x[0] = dp.x; x[1] = dp.y; x[2] = dp.z; x[3] = dt.x; x[4] = dt.y; x[5] = dt.z;
        const ToolPoseAt at = tool_pose_at(base, x);
        for (const Atom& atom : fx.atoms) {
            double grad[6];
            evaluate_atom(*fx.model, atom, at, grad);
            for (int j = 0; j < 6; ++j) {
                const double h = j < 3 ? 1e-7 : 1e-6;
                double xp[6], xm[6];
                for (int k = 0; k < 6; ++k) xp[k] = xm[k] = x[k];
                xp[j] += h;
                xm[j] -= h;
                const double gp = evaluate_atom(*fx.model, atom, tool_pose_at(base, xp), nullptr);
                const double gm = evaluate_atom(*fx.model, atom, tool_pose_at(base, xm), nullptr);
                const double fd = (gp - gm) / (2 * h);
                const double scale = j < 3 ? 1.0 : 0.02;  // rotational gradients are ~ lever arm (m)
                EXPECT_NEAR(grad[j], fd, 2e-6 * scale + 1e-5 * std::abs(fd))
                    << "atom kind " << int(atom.kind) << " var " << j << " trial " << trial;
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 1000);
}

TEST(ContactAtoms, VertexFaceValueIsSignedPlaneDistance) {
    Fixture fx;
    ASSERT_TRUE(fx.model);
    const Model& m = *fx.model;
    Atom a;
    a.kind = AtomKind::VertexFace;
    a.tool_vertex = 0;
    a.object_triangle = 0;
    const Pose base{Vec3(0.01, 0.02, -0.003), axis_angle(Vec3(1, 2, 3), 0.4)};
    const double x[6] = {0, 0, 0, 0, 0, 0};
    const double g = evaluate_atom(m, a, tool_pose_at(base, x), nullptr);
    const Vec3 w = base.apply(m.tool.mesh.vertices[0]);
    const auto& tri = m.objects[0].mesh.triangles[0];
    const Vec3 n = glm::normalize(glm::cross(m.objects[0].mesh.vertices[tri[1]] - m.objects[0].mesh.vertices[tri[0]],
                                             m.objects[0].mesh.vertices[tri[2]] - m.objects[0].mesh.vertices[tri[0]]));
    EXPECT_NEAR(g, glm::dot(n, w - m.objects[0].mesh.vertices[tri[0]]), 1e-15);
}
