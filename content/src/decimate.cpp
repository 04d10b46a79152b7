// Edge-collapse decimation through OpenMesh's decimater. Compiled with NDEBUG (CMakeLists): the
// library's internal asserts cost it a factor of two to three, and only this file instantiates it.
#include "sulcus/content/polygonize.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

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
    OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<OmMesh>::Handle aspect;
    dec.add(quadric);
    dec.add(flipping);
    // The quadric error of a collapse is the sum of squared distances of the new vertex to the
    // planes of the original triangles around it: bounding it bounds how far the surface moves.
    dec.module(quadric).set_max_err(settings.max_error_m * settings.max_error_m, false);
    dec.module(flipping).set_max_normal_deviation(settings.max_normal_change_rad * 180.0 / M_PI);
    if (settings.min_aspect > 0.0) {
        dec.add(aspect);
        dec.module(aspect).set_aspect_ratio(settings.min_aspect);
        dec.module(aspect).set_binary(true);
    }
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
