// Tooth meshes: the implicit tooth polygonized on a grid, then coarsened where it is flat.
#include "sulcus/content/polygonize.h"
#include "sulcus/content/tooth.h"

namespace sulcus {

// Visual: a 0.15 mm grid decimated to about 12k triangles (inside the 5k-20k budget), with the
// surface kept within 0.05 mm.
ToothMeshSettings tooth_visual_settings() { return ToothMeshSettings{1.5e-4, 5e-5, 12000}; }

// Collision: a 0.1 mm grid (vertices on the zero set), decimated only as far as the surface stays
// within 0.02 mm of it.
ToothMeshSettings tooth_collision_settings() { return ToothMeshSettings{1e-4, 2e-5, 0}; }

TriMesh make_tooth_mesh(int fdi, const ToothMeshSettings& settings) {
    const ToothShape shape(fdi);
    PolygonizeSettings ps;
    ps.cell_m = settings.cell_m;
    TriMesh mesh = polygonize([&shape](const Vec3& p) { return shape.field(p); }, shape.bounds(), ps);
    if (settings.max_error_m <= 0.0 && settings.target_triangles == 0) return mesh;
    DecimateSettings ds;
    // With only a triangle target, the error bound must not stop the decimation first.
    ds.max_error_m = settings.max_error_m > 0.0 ? settings.max_error_m : 1.0;
    ds.target_triangles = settings.target_triangles;
    return decimate(mesh, ds);
}

}  // namespace sulcus
