// Edge-collapse decimation through OpenMesh's decimater. Compiled with NDEBUG (CMakeLists): the
// library's internal asserts cost it a factor of two to three, and only this file instantiates it.
#include "sulcus/content/polygonize.h"
#include "decimate_detail.h"

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
using OmBase = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

// The mesh the decimater works on. It answers the decimater's topology check itself, with the same
// tests as OpenMesh's TriConnectivity::is_collapse_ok, in this file: the packaged library is built
// with its asserts on, which there check every property access by comparing type names as strings
// (two allocations and a compare each), and that check was half of a case build's time. The
// decimater is a template over the mesh type, so it calls this one.
class OmMesh : public OmBase {
public:
    bool is_collapse_ok(OpenMesh::HalfedgeHandle v0v1) {
        if (status(edge_handle(v0v1)).deleted()) return false;
        const OpenMesh::HalfedgeHandle v1v0 = opposite_halfedge_handle(v0v1);
        const OpenMesh::VertexHandle v0 = to_vertex_handle(v1v0);
        const OpenMesh::VertexHandle v1 = to_vertex_handle(v0v1);
        if (status(v0).deleted() || status(v1).deleted()) return false;

        // The far vertex of the triangle on halfedge h's side (none on the boundary); false where
        // that triangle's two other edges are both on the boundary.
        auto far_vertex = [&](OpenMesh::HalfedgeHandle h, OpenMesh::VertexHandle& far) {
            if (is_boundary(h)) return true;
            const OpenMesh::HalfedgeHandle h1 = next_halfedge_handle(h);
            const OpenMesh::HalfedgeHandle h2 = next_halfedge_handle(h1);
            far = to_vertex_handle(h1);
            return !(is_boundary(opposite_halfedge_handle(h1)) && is_boundary(opposite_halfedge_handle(h2)));
        };
        OpenMesh::VertexHandle vl, vr;
        if (!far_vertex(v0v1, vl) || !far_vertex(v1v0, vr) || vl == vr) return false;

        // The two one-rings may share only vl and vr (tag bits, as the library does).
        for (auto it = vv_iter(v0); it.is_valid(); ++it) status(*it).set_tagged(false);
        for (auto it = vv_iter(v1); it.is_valid(); ++it) status(*it).set_tagged(true);
        for (auto it = vv_iter(v0); it.is_valid(); ++it)
            if (status(*it).tagged() && *it != vl && *it != vr) return false;

        // An edge between two boundary vertices must itself be on the boundary.
        if (is_boundary(v0) && is_boundary(v1) && !is_boundary(v0v1) && !is_boundary(v1v0)) return false;
        return true;
    }

    // The halfedge from a to b, if any (the decimater asks it of a collapse's two far vertices);
    // the library's own is slowed by the same asserts.
    OpenMesh::SmartHalfedgeHandle find_halfedge(OpenMesh::VertexHandle a, OpenMesh::VertexHandle b) const {
        for (auto it = cvoh_iter(a); it.is_valid(); ++it)
            if (to_vertex_handle(*it) == b) return OpenMesh::make_smart(OpenMesh::HalfedgeHandle(*it), this);
        return OpenMesh::make_smart(OpenMesh::HalfedgeHandle(), this);
    }

    // The library's own answers, for the test that they agree.
    bool library_is_collapse_ok(OpenMesh::HalfedgeHandle h) { return OmBase::is_collapse_ok(h); }
    OpenMesh::HalfedgeHandle library_find_halfedge(OpenMesh::VertexHandle a, OpenMesh::VertexHandle b) const {
        return OmBase::find_halfedge(a, b);
    }
};

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

namespace {

void load(const TriMesh& mesh, OmMesh& om) {
    std::vector<OmMesh::VertexHandle> vh;
    vh.reserve(mesh.vertices.size());
    for (const Vec3& v : mesh.vertices) vh.push_back(om.add_vertex(OmMesh::Point(v.x, v.y, v.z)));
    for (const auto& t : mesh.triangles) {
        const OmMesh::FaceHandle f = om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
        if (!f.is_valid()) throw std::invalid_argument("decimate: the mesh is not manifold");
    }
}

}  // namespace

namespace decimate_detail {

CollapseCheckCount compare_collapse_checks(const TriMesh& mesh, size_t collapses) {
    OmMesh om;
    load(mesh, om);
    CollapseCheckCount count;
    const size_t n = om.n_halfedges();
    size_t next = 0;
    for (size_t round = 0; round <= collapses; ++round) {
        for (size_t i = 0; i < n; ++i) {
            const OpenMesh::HalfedgeHandle h{int(i)};
            const bool ours = om.is_collapse_ok(h);
            const bool theirs = om.library_is_collapse_ok(h);
            ++count.compared;
            count.allowed += ours ? 1 : 0;
            count.disagreed += ours != theirs ? 1 : 0;
            // The halfedge between the two far vertices of the edge's triangles, as the decimater
            // asks it, and between its own ends.
            const OpenMesh::HalfedgeHandle o = om.opposite_halfedge_handle(h);
            const OpenMesh::VertexHandle vl = om.to_vertex_handle(om.next_halfedge_handle(h));
            const OpenMesh::VertexHandle vr = om.to_vertex_handle(om.next_halfedge_handle(o));
            for (const auto& [a, b] : {std::pair{vl, vr}, std::pair{om.to_vertex_handle(o), om.to_vertex_handle(h)}}) {
                if (!a.is_valid() || !b.is_valid() || om.status(a).deleted()) continue;
                const OpenMesh::HalfedgeHandle mine = om.find_halfedge(a, b);
                ++count.found_compared;
                count.found += mine.is_valid() ? 1 : 0;
                count.disagreed += mine != om.library_find_halfedge(a, b) ? 1 : 0;
            }
        }
        if (round == collapses) break;
        // Collapse the first allowed halfedge from a point that strides through the mesh.
        for (size_t k = 0; k < n; ++k) {
            const OpenMesh::HalfedgeHandle h{int((next + k) % n)};
            if (om.is_collapse_ok(h)) {
                om.collapse(h);
                next = (next + k + 7919) % n;
                break;
            }
        }
    }
    return count;
}

}  // namespace decimate_detail

TriMesh decimate(const TriMesh& mesh, const DecimateSettings& settings) {
    OmMesh om;
    load(mesh, om);
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
