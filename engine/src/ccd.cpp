#include "ccd.h"

#include "so3.h"
#include "tool_placement.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

CcdResult conservative_advancement(const Model& model, const Pose& base, const double x[6], double clearance,
                                   const NearTriangle* near, int near_count, int max_iterations,
                                   const CcdScratch& scratch) {
    CcdResult r;
    const Vec3 dp(x[0], x[1], x[2]);
    const Vec3 th(x[3], x[4], x[5]);
    const double speed = glm::length(dp) + glm::length(th) * model.tool.radius_m;
    const ModelTool& tool = model.tool;
    double tau = 0.0;
    for (int it = 0; it < max_iterations; ++it) {
        r.iterations = it + 1;
        const Quat q = glm::normalize(quat_exp(tau * th) * base.orientation);
        const Vec3 p = base.position + tau * dp;
        place_tool_vertices(tool, q, p, scratch.vertices);
        place_tool_planes(tool, q, p, scratch.normals, scratch.offsets);
        *scratch.rotation = q;
        place_tool_capsule(tool, q, p, scratch.capsule);
        double d = 1e300;
        // A distance this large lets the rest of the motion go through in one advance, so any
        // lower bound that reaches it is as good as the exact distance.
        const double enough = clearance + speed * (1.0 - tau);
        for (int i = 0; i < near_count; ++i) {
            // The triangle's distance bound at the start, less how far any point has moved since:
            // when that already reaches what this advance needs, the exact distance is not.
            const double bound = near[i].lower_m - speed * tau;
            if (bound >= std::min(d, enough)) {
                d = std::min(d, bound);
                continue;
            }
            ++r.tests;
            const ModelObject& obj = model.objects[near[i].object];
            const auto& t = obj.mesh.triangles[near[i].tri];
            const size_t k = near[i].piece;
            const ConvexView view = tool_convex_view(tool, k, scratch.vertices, scratch.normals, scratch.offsets,
                                                     scratch.rotation, scratch.capsule);
            d = std::min(d, distance_convex_triangle(view, piece_triangles(tool, k), int(tool.pieces[k].triangle_count),
                                                     obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]],
                                                     obj.mesh.vertices[t[2]], std::min(d, enough)));
            if (d <= clearance) {
                r.hit = true;
                r.toi = tau;
                return r;
            }
        }
        if (tau >= 1.0 || speed <= 0.0) {
            r.toi = 1.0;
            return r;
        }
        tau = std::min(1.0, tau + (d - clearance) / speed);
    }
    r.hit = true;
    r.exhausted = true;
    r.toi = tau;
    return r;
}

}  // namespace sulcus
