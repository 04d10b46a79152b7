// Our proximity queries timed against FCL's on the same meshes and poses (peer_fcl.h).
#include "cli/peer_fcl.h"

#include "sulcus/engine/proximity.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#ifdef SULCUS_HAVE_FCL
#include <fcl/fcl.h>

#include <memory>
#endif

namespace sulcus::cli {

#ifndef SULCUS_HAVE_FCL

bool fcl_available() { return false; }

PeerComparison compare_with_fcl(const Model&, const std::vector<Pose>&) {
    PeerComparison out;
    out.error = "sulcus-cli was built without FCL (Debian libfcl-dev)";
    return out;
}

#else

namespace {

// One repetition batch must take at least this long for the clock to resolve it well.
constexpr double kMinBatchUs = 2.0;
constexpr long kMaxRepetitions = 1L << 20;

// Mean time of one call of f in microseconds: repeats f, doubling the count, until a batch takes
// kMinBatchUs. The shorter batches before it warm the caches.
template <class F>
double time_one_us(F&& f) {
    using Clock = std::chrono::steady_clock;
    for (long reps = 1;; reps *= 2) {
        const auto t0 = Clock::now();
        for (long i = 0; i < reps; ++i) f();
        const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
        if (us >= kMinBatchUs || reps >= kMaxRepetitions) return us / static_cast<double>(reps);
    }
}

std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> fcl_mesh(const TriMesh& mesh) {
    std::vector<fcl::Vector3d> points;
    points.reserve(mesh.vertices.size());
    for (const Vec3& v : mesh.vertices) points.emplace_back(v.x, v.y, v.z);
    std::vector<fcl::Triangle> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    model->beginModel(int(triangles.size()), int(points.size()));
    model->addSubModel(points, triangles);
    model->endModel();
    return model;
}

fcl::Transform3d fcl_transform(const Pose& pose) {
    const Quat q = glm::normalize(pose.orientation);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.linear() = fcl::Quaterniond(q.w, q.x, q.y, q.z).toRotationMatrix();
    tf.translation() = fcl::Vector3d(pose.position.x, pose.position.y, pose.position.z);
    return tf;
}

// FCL's side: the tool and the objects as collision objects.
struct FclScene {
    std::unique_ptr<fcl::CollisionObjectd> tool;
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;

    explicit FclScene(const Model& model) {
        tool = std::make_unique<fcl::CollisionObjectd>(fcl_mesh(model.tool.mesh), fcl::Transform3d::Identity());
        for (const ModelObject& obj : model.objects) {
            // Object meshes are already placed in the world.
            objects.push_back(
                std::make_unique<fcl::CollisionObjectd>(fcl_mesh(obj.mesh), fcl::Transform3d::Identity()));
            objects.back()->computeAABB();
        }
    }

    void place(const fcl::Transform3d& tf) {
        tool->setTransform(tf);
        tool->computeAABB();
    }

    // Least distance over the objects, one fcl::distance call each (no broadphase manager).
    double distance(const fcl::Transform3d& tf) {
        place(tf);
        const fcl::DistanceRequestd request;
        double best = std::numeric_limits<double>::infinity();
        for (const auto& obj : objects) {
            fcl::DistanceResultd result;
            fcl::distance(tool.get(), obj.get(), request, result);
            best = std::min(best, result.min_distance);
        }
        return best;
    }

    bool collides(const fcl::Transform3d& tf) {
        place(tf);
        const fcl::CollisionRequestd request;  // one contact, no contact details
        for (const auto& obj : objects) {
            fcl::CollisionResultd result;
            if (fcl::collide(tool.get(), obj.get(), request, result) > 0) return true;
        }
        return false;
    }
};

}  // namespace

bool fcl_available() { return true; }

PeerComparison compare_with_fcl(const Model& model, const std::vector<Pose>& poses) {
    PeerComparison out;
    if (model.tool.mesh.triangles.empty() || model.objects.empty()) {
        out.error = "the model has no tool mesh or no objects to compare";
        return out;
    }
    if (poses.empty()) {
        out.error = "no poses to compare at";
        return out;
    }
    FclScene peer(model);
    // Closer than this (m) the tool touches: its verdicts may differ by rounding.
    constexpr double kTouch = 1e-9;
    const double no_cap = std::numeric_limits<double>::infinity();

    PeerQueryTiming dist;
    dist.query = "distance";
    PeerQueryTiming coll;
    coll.query = "collision";
    std::vector<double> ours_d, peer_d, ours_c, peer_c;
    for (const Pose& pose : poses) {
        const fcl::Transform3d tf = fcl_transform(pose);

        const double ours = tool_distance(model, pose, no_cap);
        const double theirs = peer.distance(tf);
        // The poses are where the tool really went: many touch, and at a touch (distance 0 to
        // rounding) either verdict is right. A disagreement is one where the distances differ
        // by more than kTouch across it.
        const bool ours_apart = ours > kTouch, theirs_apart = theirs > kTouch;
        if (ours_apart != theirs_apart && std::abs(ours - theirs) > kTouch) ++dist.disagreements;
        if (ours > 0.0 && theirs > 0.0) dist.max_difference_m = std::max(dist.max_difference_m, std::abs(ours - theirs));
        volatile double sink = 0.0;
        ours_d.push_back(time_one_us([&] { sink = tool_distance(model, pose, no_cap); }));
        peer_d.push_back(time_one_us([&] { sink = peer.distance(tf); }));

        if (tool_collides(model, pose) != peer.collides(tf) && std::min(ours, theirs) > kTouch) ++coll.disagreements;
        volatile bool hit = false;
        ours_c.push_back(time_one_us([&] { hit = tool_collides(model, pose); }));
        peer_c.push_back(time_one_us([&] { hit = peer.collides(tf); }));
        (void)sink;
        (void)hit;
    }
    auto finish = [](PeerQueryTiming& q, const std::vector<double>& ours, const std::vector<double>& theirs) {
        q.queries = static_cast<long>(ours.size());
        q.ours_us = percentiles(ours);
        q.peer_us = percentiles(theirs);
        q.ratio = q.ours_us.median > 0.0 ? q.peer_us.median / q.ours_us.median : 0.0;
    };
    finish(dist, ours_d, peer_d);
    finish(coll, ours_c, peer_c);
    out.queries.push_back(dist);
    out.queries.push_back(coll);
    return out;
}

#endif

}  // namespace sulcus::cli
