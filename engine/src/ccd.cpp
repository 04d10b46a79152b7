#include "ccd.h"

#include "so3.h"
#include "tool_placement.h"

#include <algorithm>
#include <cmath>

namespace sulcus {

// Each triangle advances on its own, in the frame of the moving tool (the triangle is carried
// into it, three points, rather than the tool into the world): a triangle far from the path
// costs one bound, one near it the advances it needs, and none is tested again for the steps
// another one needed. The search ends at the first contact found so far: no later one matters.
CcdResult conservative_advancement(const Model& model, const Pose& base, const double x[6], double clearance,
                                   const NearTriangle* near, int near_count, int max_iterations, bool first_only) {
    CcdResult r;
    const Vec3 dp(x[0], x[1], x[2]);
    const Vec3 th(x[3], x[4], x[5]);
    const double move = glm::length(dp), turn = glm::length(th);
    const ModelTool& tool = model.tool;
    double limit = 1.0;  // the first contact so far
    for (int i = 0; i < near_count; ++i) {
        const NearTriangle& nt = near[i];
        const ToolPiece& piece = tool.pieces[nt.piece];
        // No point of this piece moves faster than this per unit tau.
        const double speed = move + turn * piece.radius_m;
        // The bound at the start leaves room for the whole motion up to the limit.
        if (nt.lower_m - speed * limit > clearance) continue;
        ConvexView view;
        view.vertices = tool.mesh.vertices.data() + piece.vertex_begin;
        view.vertex_count = int(piece.vertex_count);
        view.capsule = piece.capsule_points.data();
        view.capsule_radii = piece.capsule_radii_m.data();
        view.capsule_count = piece.capsule_count;
        const ModelObject& obj = model.objects[nt.object];
        const auto& t = obj.mesh.triangles[nt.tri];
        const Vec3 world[3] = {obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]]};
        // The triangle in the tool's frame at motion parameter `at`.
        auto carried = [&](double at, Vec3 out[3]) {
            const Quat qi = glm::conjugate(glm::normalize(quat_exp(at * th) * base.orientation));
            const Vec3 p = base.position + at * dp;
            for (int k = 0; k < 3; ++k) out[k] = qi * (world[k] - p);
        };
        double tau = 0.0;
        bool done = false;
        // Each search starts where the last one for this triangle ended (the triangle has moved
        // little along the tool since), the first where detect's did: a few iterations each
        // instead of a search from scratch. Any direction's gap bounds the distance below.
        Vec3 hint(0.0);
        GjkSimplex warm{};
        bool hinted = false;
        if (glm::dot(nt.direction, nt.direction) > 0.0) {
            hint = glm::conjugate(glm::normalize(base.orientation)) * nt.direction;
            hinted = true;
        }
        for (int it = 0; it < max_iterations && !done; ++it) {
            ++r.tests;
            r.iterations = std::max(r.iterations, it + 1);
            Vec3 tri[3];
            carried(tau, tri);
            const Vec3 &a = tri[0], &b = tri[1], &c = tri[2];
            // A distance this large lets the rest of the motion up to the limit go through.
            const double enough = clearance + speed * (limit - tau);
            double d = capsule_lower_bound(view, a, b, c);
            if (d < enough) {
                const DistanceBounds db = convex_triangle_distance(view, a, b, c, enough, 1e-13, 64,
                                                                   hinted ? &hint : nullptr,
                                                                   warm.count > 0 ? &warm : nullptr);
                d = db.lower;
                if (glm::dot(db.direction, db.direction) > 0.0) {
                    hint = db.direction;
                    hinted = true;
                }
                warm = db.simplex;
            }
            if (d >= enough) {
                done = true;
            } else if (d <= clearance) {
                r.hit = true;
                limit = tau;
                if (first_only) {
                    r.toi = limit;
                    return r;
                }
                done = true;
            } else {
                if (first_only && it == 0) {
                    // Only whether there is a contact matters: one at the end of the motion says so
                    // at once, where the advances towards it would take many small steps (a tool
                    // coming down onto a surface at a slant, or sliding into a wedge).
                    ++r.tests;
                    Vec3 e[3];
                    carried(limit, e);
                    double de = capsule_lower_bound(view, e[0], e[1], e[2]);
                    if (de <= clearance) de = convex_triangle_distance(view, e[0], e[1], e[2], clearance).lower;
                    if (de <= clearance) {
                        r.hit = true;
                        r.toi = limit;
                        return r;
                    }
                }
                tau += (d - clearance) / speed;
                done = tau >= limit;
            }
        }
        if (!done) {
            // Out of advances before a verdict: taken as a contact where the search stopped.
            r.hit = true;
            r.exhausted = true;
            limit = tau;
            if (first_only) {
                r.toi = limit;
                return r;
            }
        }
    }
    r.toi = limit;
    return r;
}

}  // namespace sulcus
