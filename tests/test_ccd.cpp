// Continuous collision detection against brute-force sampling of the motion with the
// independent exact check: it never misses a contact (thin walls, fast motion, rotation), and
// the time it reports is the first one.
#include "ccd.h"
#include "scene_helpers.h"
#include "sulcus/engine/exact_check.h"
#include "so3.h"

#include <random>

using namespace sulcus;
using namespace sulcus::test;

namespace {

struct CcdCase {
    std::unique_ptr<Model> model;
    std::vector<NearTriangle> near;
    TriMesh tool, object_mesh;

    CcdCase(const TriMesh& tool_mesh, const TriMesh& obj) : tool(tool_mesh), object_mesh(obj) {
        model = model_of(tool, {object("obj", obj)});
        for (uint32_t t = 0; t < obj.triangles.size(); ++t) near.push_back({0, t});
    }

    CcdResult run(const Pose& base, const double x[6], double clearance, bool first_only = false) {
        return conservative_advancement(*model, base, x, clearance, near.data(), static_cast<int>(near.size()), 4096,
                                        first_only);
    }

    Pose at(const Pose& base, const double x[6], double tau) const {
        Pose p;
        p.position = base.position + tau * Vec3(x[0], x[1], x[2]);
        p.orientation = glm::normalize(quat_exp(tau * Vec3(x[3], x[4], x[5])) * base.orientation);
        return p;
    }

    // Brute force: the first sampled tau at which the tool is within `clearance`, or 2 when none.
    double sampled_first_contact(const Pose& base, const double x[6], double clearance, int samples) const {
        std::vector<PlacedMesh> objs{PlacedMesh{&object_mesh, Pose{}}};
        for (int i = 0; i <= samples; ++i) {
            const double tau = static_cast<double>(i) / samples;
            const ExactCheck c = exact_check(tool, at(base, x, tau), objs, 1.0);
            if (c.penetration_m > 0.0 || c.distance_m <= clearance) return tau;
        }
        return 2.0;
    }
};

}  // namespace

TEST(Ccd, ThinPlateAtHighSpeedIsNeverTunnelled) {
    // A 0.05 mm plate and a 2 mm cube crossing it in one step at up to 10 m/s (10 mm per tick).
    CcdCase c(make_box(Vec3(1 * mm)), make_box(Vec3(20 * mm, 0.025 * mm, 20 * mm)));
    for (double speed_mm : {0.5, 1.0, 5.0, 10.0}) {
        const Pose base = pose(Vec3(0, 1.5 * mm, 0));
        const double x[6] = {0.3 * mm, -(1.5 * mm + speed_mm * mm), 0, 0, 0, 0};
        const CcdResult r = c.run(base, x, 1e-6);
        EXPECT_TRUE(r.hit) << speed_mm;
        // The reported time is before the sampled first contact and the tool is there within
        // the clearance of the plate.
        const double sampled = c.sampled_first_contact(base, x, 1e-6, 4000);
        EXPECT_LE(r.toi, sampled + 1e-12);
        std::vector<PlacedMesh> objs{PlacedMesh{&c.object_mesh, Pose{}}};
        const ExactCheck e = exact_check(c.tool, c.at(base, x, r.toi), objs, 1.0);
        EXPECT_EQ(e.penetration_m, 0.0);
        EXPECT_LE(e.distance_m, 1e-6 + 1e-12);
    }
}

TEST(Ccd, RotationSweepsThroughAThinPlate) {
    // A long thin tool spinning a quarter turn in one step: its end sweeps through the plate
    // while both end poses are clear of it.
    CcdCase c(make_box(Vec3(10 * mm, 0.5 * mm, 0.5 * mm)), make_box(Vec3(0.025 * mm, 20 * mm, 20 * mm), Vec3(5 * mm, 0, 0)));
    const Pose base = pose(Vec3(0, 0, 0), axis_angle(Vec3(0, 0, 1), 1.5707963267948966));
    const double x[6] = {0, 0, 0, 0, 0, -3.0};
    std::vector<PlacedMesh> objs{PlacedMesh{&c.object_mesh, Pose{}}};
    EXPECT_GT(exact_check(c.tool, c.at(base, x, 0.0), objs, 1.0).distance_m, 0.0);
    const CcdResult r = c.run(base, x, 1e-6);
    EXPECT_TRUE(r.hit);
    EXPECT_LE(r.toi, c.sampled_first_contact(base, x, 1e-6, 4000) + 1e-12);
}

TEST(Ccd, AgreesWithBruteForceSamplingOnRandomMotions) {
    // A cube against an L-shaped solid with convex and concave edges.
    const std::vector<Vec2> ell = {{-10 * mm, -10 * mm}, {10 * mm, -10 * mm}, {10 * mm, -4 * mm},
                                   {-4 * mm, -4 * mm},   {-4 * mm, 10 * mm},  {-10 * mm, 10 * mm}};
    CcdCase c(make_box(Vec3(1.2 * mm, 0.8 * mm, 1.0 * mm)), make_extruded_polygon(ell, -6 * mm, 6 * mm));
    std::mt19937_64 rng(1234);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<PlacedMesh> objs{PlacedMesh{&c.object_mesh, Pose{}}};
    int hits = 0, misses = 0;
    for (int trial = 0; trial < 120; ++trial) {
        Pose base = pose(Vec3(u(rng) * 4 * mm + 2 * mm, u(rng) * 4 * mm + 2 * mm, u(rng) * 4 * mm),
                         glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))));
        if (exact_check(c.tool, base, objs, 1.0).distance_m < 1e-4) continue;
        const double x[6] = {u(rng) * 6 * mm, u(rng) * 6 * mm, u(rng) * 3 * mm, u(rng), u(rng), u(rng)};
        const CcdResult r = c.run(base, x, 1e-6);
        const double sampled = c.sampled_first_contact(base, x, 1e-6, 2000);
        if (sampled <= 1.0) {
            // Sampling saw a contact: CCD must have reported one no later.
            EXPECT_TRUE(r.hit) << trial;
            EXPECT_LE(r.toi, sampled + 1e-12) << trial;
        }
        // Stopping at the first contact found gives the same verdict, at a contact.
        const CcdResult first = c.run(base, x, 1e-6, true);
        EXPECT_EQ(first.hit, r.hit) << trial;
        EXPECT_GE(first.toi, r.toi) << trial;
        if (first.hit && !first.exhausted) {
            EXPECT_LE(exact_check(c.tool, c.at(base, x, first.toi), objs, 1.0).distance_m, 1e-6 + 1e-12) << trial;
        }
        if (r.hit && !r.exhausted) {
            ++hits;
            const ExactCheck e = exact_check(c.tool, c.at(base, x, r.toi), objs, 1.0);
            EXPECT_EQ(e.penetration_m, 0.0) << trial;
            EXPECT_LE(e.distance_m, 1e-6 + 1e-12) << trial;
        } else if (!r.hit) {
            ++misses;
        }
    }
    EXPECT_GT(hits, 5);
    EXPECT_GT(misses, 5);
}

TEST(Ccd, AContactAtTheEndSettlesTheFirstContactSearchAtOnce) {
    // A cube sliding 2 mm along a slab while it comes down 11 um onto it from 10 um above: the
    // advances towards the contact are about 10 um of the 2 mm each, so the full search takes
    // many; stopping at the first contact, a look at the end of the motion finds it, after a
    // few triangles the cube does not end on.
    CcdCase c(make_box(Vec3(1 * mm)), make_box(Vec3(20 * mm, 0.5 * mm, 20 * mm)));
    const Pose base = pose(Vec3(0, 1.5 * mm + 10e-6, 0));
    const double x[6] = {2 * mm, -11e-6, 0, 0, 0, 0};
    const CcdResult full = c.run(base, x, 1e-6);
    const CcdResult first = c.run(base, x, 1e-6, true);
    EXPECT_TRUE(full.hit);
    EXPECT_TRUE(first.hit);
    EXPECT_GT(full.iterations, 20);
    EXPECT_LE(4 * first.tests, full.tests) << first.tests << " " << full.tests;
    std::vector<PlacedMesh> objs{PlacedMesh{&c.object_mesh, Pose{}}};
    EXPECT_LE(exact_check(c.tool, c.at(base, x, first.toi), objs, 1.0).distance_m, 1e-6 + 1e-12);
}
