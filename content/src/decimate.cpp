// Edge-collapse decimation through OpenMesh's decimater. Compiled with NDEBUG (CMakeLists): the
// library's internal asserts cost it a factor of two to three, and only this file instantiates it.
#include "sulcus/content/polygonize.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Core/Geometry/QuadricT.hh>
#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

#include <cmath>
#include <stdexcept>

namespace sulcus {

namespace {

struct OmTraits : public OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec3d Point;
    typedef OpenMesh::Vec3d Normal;
    VertexAttributes(OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Status | OpenMesh::Attributes::Normal);
    EdgeAttributes(OpenMesh::Attributes::Status);
    HalfedgeAttributes(OpenMesh::Attributes::Status);
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

// Quadric error without area weights: the error of a vertex is the sum of its squared distances to
// the planes of all original triangles merged into it, so an error below tol^2 keeps the vertex
// within tol of every one of those planes. (OpenMesh's ModQuadricT weights each plane by its
// triangle's area, which makes its bound a function of the mesh's scale and density.)
class ModPlaneDistance : public OpenMesh::Decimater::ModBaseT<OmMesh> {
public:
    using Self = ModPlaneDistance;
    using Handle = OpenMesh::Decimater::ModHandleT<Self>;
    using Base = OpenMesh::Decimater::ModBaseT<OmMesh>;
    using Mesh = Base::Mesh;
    using CollapseInfo = Base::CollapseInfo;
    DECIMATER_MODNAME(PlaneDistance)
    explicit ModPlaneDistance(OmMesh& mesh) : Base(mesh, false) { mesh.add_property(quadrics_); }
    ~ModPlaneDistance() override { Base::mesh().remove_property(quadrics_); }

    void set_max_distance(double d) { max_err_ = d * d; }

    void initialize() override {
        OmMesh& m = Base::mesh();
        for (const auto& v : m.vertices()) m.property(quadrics_, v).clear();
        for (const auto& f : m.faces()) {
            auto fv = m.cfv_iter(f);
            const OmMesh::Point p0 = m.point(*fv), p1 = m.point(*++fv), p2 = m.point(*++fv);
            OmMesh::Point n = (p1 - p0) % (p2 - p0);
            const double len = n.norm();
            if (!(len > 0.0)) continue;
            n /= len;
            const Quadric q(n[0], n[1], n[2], -(n | p0));
            for (const auto& v : m.fv_range(f)) m.property(quadrics_, v) += q;
        }
    }

    float collapse_priority(const CollapseInfo& ci) override {
        Quadric q = Base::mesh().property(quadrics_, ci.v0);
        q += Base::mesh().property(quadrics_, ci.v1);
        const double err = q(ci.p1);
        return err < max_err_ ? float(err / max_err_) : float(Base::ILLEGAL_COLLAPSE);
    }

    void postprocess_collapse(const CollapseInfo& ci) override {
        Base::mesh().property(quadrics_, ci.v1) += Base::mesh().property(quadrics_, ci.v0);
    }

private:
    using Quadric = OpenMesh::Geometry::QuadricT<double>;
    OpenMesh::VPropHandleT<Quadric> quadrics_;
    double max_err_ = 0.0;
};

}  // namespace

TriMesh decimate(const TriMesh& mesh, const DecimateSettings& settings) {
    OmMesh om;
    std::vector<OmMesh::VertexHandle> vh;
    vh.reserve(mesh.vertices.size());
    for (const Vec3& v : mesh.vertices) vh.push_back(om.add_vertex(OmMesh::Point(v.x, v.y, v.z)));
    for (const auto& t : mesh.triangles) {
        const OmMesh::FaceHandle f = om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
        if (!f.is_valid()) throw std::invalid_argument("decimate: the mesh is not manifold");
    }
    om.update_face_normals();

    using Decimater = OpenMesh::Decimater::DecimaterT<OmMesh>;
    Decimater dec(om);
    ModPlaneDistance::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<OmMesh>::Handle aspect;
    dec.add(quadric);
    dec.add(flipping);
    dec.module(quadric).set_max_distance(settings.max_error_m);
    dec.module(flipping).set_max_normal_deviation(settings.max_normal_change_rad * 180.0 / M_PI);
    // No collapse may leave a sliver worse than this (length over height), unless it improves one.
    dec.add(aspect);
    dec.module(aspect).set_aspect_ratio(settings.max_aspect > 0.0 ? settings.max_aspect : 20.0);
    dec.module(aspect).set_binary(true);
    if (!dec.initialize()) throw std::invalid_argument("decimate: could not set up the decimater");
    if (settings.target_triangles > 0)
        dec.decimate_to_faces(0, settings.target_triangles);
    else
        dec.decimate();
    om.garbage_collection();

    TriMesh out;
    out.vertices.reserve(om.n_vertices());
    for (const auto& v : om.vertices()) {
        const auto& p = om.point(v);
        out.vertices.emplace_back(p[0], p[1], p[2]);
    }
    out.triangles.reserve(om.n_faces());
    for (const auto& f : om.faces()) {
        std::array<uint32_t, 3> t{};
        int k = 0;
        for (const auto& v : om.fv_range(f)) t[size_t(k++)] = uint32_t(v.idx());
        out.triangles.push_back(t);
    }
    return out;
}

}  // namespace sulcus
