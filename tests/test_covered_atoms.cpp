// Gather leaves out the atoms of compliant objects that cannot hold the tool in the step's box
// (RendererSettings::drop_covered_atoms): those that stay clear of the surface whatever the zone
// gives, and those the zone's give covers. The QP's problem holds the same, so with and without it
// the bench's tissue runs give the same statuses and passes on every tick, and graphic poses,
// forces and depths in the tissue that differ at most in the QP's last bits, from far fewer atoms.
// Rigid objects are not touched: their scenes give the same answers bit for bit.
#include "bench_scene_helpers.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

using namespace sulcus;

namespace {

struct Tick {
    Pose graphic;
    Vec3 force;
    StepStatus status;
    int passes;
    double soft_depth;
    long atoms_gathered;
};

cli::BenchScene load(const std::string& name) { return test::load_bench_scene(name); }

std::unique_ptr<Model> model_for(const cli::BenchScene& b, bool drop_covered) {
    RendererSettings settings;
    settings.drop_covered_atoms = drop_covered;
    return test::bench_model(b, settings);
}

std::vector<Tick> run(const Model& model, const std::vector<Pose>& poses, size_t count) {
    std::vector<Tick> out;
    State state = make_state(poses.front());
    for (size_t i = 0; i < count && i < poses.size(); ++i) {
        const StepResult r = step(model, state, poses[i]);
        out.push_back(Tick{r.graphic, r.force_N, r.status, r.stats.passes, r.stats.soft_depth_m, r.stats.atoms_gathered});
    }
    return out;
}

long total_atoms(const std::vector<Tick>& t) {
    long n = 0;
    for (const Tick& k : t) n += k.atoms_gathered;
    return n;
}

int contact_ticks(const std::vector<Tick>& t) {
    int n = 0;
    for (const Tick& k : t) n += k.status == StepStatus::Contact;
    return n;
}

double max_abs(const Vec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); }

// Runs `name` with and without leaving atoms out; every tick must agree to rounding, and the
// atoms gathered with it must be at most `atom_share` of those without.
void expect_same_answers_from_fewer_atoms(const std::string& name, double atom_share) {
    const cli::BenchScene b = load(name);
    ASSERT_FALSE(b.ticks.empty()) << name;
    const auto with = model_for(b, true), without = model_for(b, false);
    const std::vector<Tick> a = run(*with, b.ticks, b.ticks.size()), c = run(*without, b.ticks, b.ticks.size());
    ASSERT_EQ(a.size(), c.size());
    EXPECT_GT(contact_ticks(a), 1000) << name;
    double worst_position = 0.0, worst_orientation = 0.0, worst_force = 0.0, worst_depth = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].status, c[i].status) << name << " tick " << i;
        ASSERT_EQ(a[i].passes, c[i].passes) << name << " tick " << i;
        worst_position = std::max(worst_position, max_abs(a[i].graphic.position - c[i].graphic.position));
        const Quat& p = a[i].graphic.orientation;
        const Quat& q = c[i].graphic.orientation;
        worst_orientation = std::max({worst_orientation, std::abs(p.w - q.w), std::abs(p.x - q.x), std::abs(p.y - q.y),
                                      std::abs(p.z - q.z)});
        worst_force = std::max(worst_force, max_abs(a[i].force - c[i].force));
        worst_depth = std::max(worst_depth, std::abs(a[i].soft_depth - c[i].soft_depth));
    }
    // The last bits of a solution: far under the constraint tolerance (1e-7 m), which a
    // different answer of the QP would show.
    EXPECT_LE(worst_position, 1e-15) << name;
    EXPECT_LE(worst_orientation, 1e-14) << name;
    EXPECT_LE(worst_force, 1e-12) << name;
    EXPECT_LE(worst_depth, 1e-15) << name;
    EXPECT_LE(double(total_atoms(a)), atom_share * double(total_atoms(c))) << name;
}

TEST(CoveredAtoms, TwoRegionTissueSessionAnswersTheSameFromFewerAtoms) {
    expect_same_answers_from_fewer_atoms("quadrant_two_regions", 0.4);
}

TEST(CoveredAtoms, QuadrantProbingRunAnswersTheSameFromFewerAtoms) {
    expect_same_answers_from_fewer_atoms("quadrant_44_47", 0.7);
}

TEST(CoveredAtoms, RigidScenesAreTheSameBitForBit) {
    for (const std::string& name : cli::bench_scene_names()) {
        if (name.rfind("paper/", 0) != 0 && name != "dense_wedge_250k") continue;
        const cli::BenchScene b = load(name);
        ASSERT_FALSE(b.ticks.empty()) << name;
        const auto with = model_for(b, true), without = model_for(b, false);
        ASSERT_FALSE(with->any_compliant) << name;
        const size_t count = std::min<size_t>(b.ticks.size(), 3000);
        const std::vector<Tick> a = run(*with, b.ticks, count), c = run(*without, b.ticks, count);
        for (size_t i = 0; i < a.size(); ++i) {
            const bool same = std::memcmp(&a[i].graphic.position, &c[i].graphic.position, sizeof(Vec3)) == 0 &&
                              std::memcmp(&a[i].graphic.orientation, &c[i].graphic.orientation, sizeof(Quat)) == 0 &&
                              std::memcmp(&a[i].force, &c[i].force, sizeof(Vec3)) == 0 &&
                              a[i].status == c[i].status && a[i].atoms_gathered == c[i].atoms_gathered;
            ASSERT_TRUE(same) << name << " tick " << i;
        }
    }
}

}  // namespace
