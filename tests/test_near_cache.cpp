// The step's near cache (RendererSettings::near_cache) changes what the step measures, not what it
// finds: with and without it, the bench scenes' probing gives the same graphic poses, forces and
// statuses bit for bit, and the same near set on ticks of one pass. A later pass narrows the
// earlier pass's near set: it keeps every triangle the pass's box can reach but may leave out
// ones only a fresh detect's looser reach takes in, so there its set is no larger. And what it carries from tick to tick stays within one session: sessions
// interleaved on one thread, or a session run again after another, repeat their lone runs exactly.
#include "bench_scene_helpers.h"
#include "sulcus/engine/renderer.h"
#include "near_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace sulcus;

namespace {

struct Tick {
    Pose graphic;
    Vec3 force, torque;
    StepStatus status;
    int near;
    int passes;
};

bool same_bits(const Tick& a, const Tick& b) {
    return std::memcmp(&a.graphic.position, &b.graphic.position, sizeof(Vec3)) == 0 &&
           std::memcmp(&a.graphic.orientation, &b.graphic.orientation, sizeof(Quat)) == 0 &&
           std::memcmp(&a.force, &b.force, sizeof(Vec3)) == 0 && std::memcmp(&a.torque, &b.torque, sizeof(Vec3)) == 0 &&
           a.status == b.status && a.passes == b.passes && (a.passes > 0 ? a.near <= b.near : a.near == b.near);
}

cli::BenchScene load(const std::string& name) { return test::load_bench_scene(name); }

std::unique_ptr<Model> model_for(const cli::BenchScene& b, bool near_cache, bool rescue_virtual = true) {
    RendererSettings settings;
    settings.near_cache = near_cache;
    settings.rescue_virtual = rescue_virtual;
    return test::bench_model(b, settings);
}

Tick tick_of(const StepResult& r) {
    return Tick{r.graphic, r.force_N, r.torque_Nm, r.status, r.stats.triangles_near, r.stats.passes};
}

std::vector<Tick> run(const Model& model, const std::vector<Pose>& poses, size_t count) {
    std::vector<Tick> out;
    State state = make_state(poses.front());
    for (size_t i = 0; i < count && i < poses.size(); ++i) out.push_back(tick_of(step(model, state, poses[i])));
    return out;
}

// Where run `a` (with the cache) first differs from run `b` (without) (-1: nowhere).
long first_difference(const std::vector<Tick>& a, const std::vector<Tick>& b) {
    if (a.size() != b.size()) return 0;
    for (size_t i = 0; i < a.size(); ++i)
        if (!same_bits(a[i], b[i])) return long(i);
    return -1;
}

// Ticks where the cached run's near set is smaller than the fresh one's.
int narrower_ticks(const std::vector<Tick>& a, const std::vector<Tick>& b) {
    int n = 0;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) n += a[i].near < b[i].near;
    return n;
}

int contact_ticks(const std::vector<Tick>& t) {
    int n = 0;
    for (const Tick& k : t) n += k.status == StepStatus::Contact;
    return n;
}

// Later passes, whose near sets the cache narrows, take on the virtual contacts the rescue leaves
// (all of them with `rescue_virtual` off); `narrowed`: some did.
void expect_cache_changes_nothing(const std::string& name, size_t count, bool narrowed,
                                  bool rescue_virtual = true) {
    const cli::BenchScene b = load(name);
    ASSERT_FALSE(b.ticks.empty()) << name;
    const auto with = model_for(b, true, rescue_virtual), without = model_for(b, false, rescue_virtual);
    const std::vector<Tick> a = run(*with, b.ticks, count), c = run(*without, b.ticks, count);
    EXPECT_GT(contact_ticks(a), 100) << name;  // the probe is in contact for much of the run
    EXPECT_EQ(first_difference(a, c), -1) << name;
    if (narrowed) {
        EXPECT_GT(narrower_ticks(a, c), 0) << name;
    }
}

}  // namespace

TEST(NearCache, DenseWedgeProbingIsTheSameWithAndWithoutIt) {
    expect_cache_changes_nothing("dense_wedge_250k", 100000, false);
    expect_cache_changes_nothing("dense_wedge_250k", 100000, true, false);
}

// The rescue takes every virtual contact of the session round within its pass: the later passes
// whose near sets the cache narrows come with it off.
TEST(NearCache, QuadrantTwoRegionSessionIsTheSameWithAndWithoutIt) {
    expect_cache_changes_nothing("quadrant_two_regions", 100000, false);
    expect_cache_changes_nothing("quadrant_two_regions", 100000, true, false);
}

TEST(NearCache, PaperScenesAreTheSameWithAndWithoutIt) {
    for (const std::string& name : cli::bench_scene_names()) {
        if (name.rfind("paper/", 0) != 0) continue;
        const cli::BenchScene b = load(name);
        ASSERT_FALSE(b.ticks.empty()) << name;
        const auto with = model_for(b, true), without = model_for(b, false);
        EXPECT_EQ(first_difference(run(*with, b.ticks, 100000), run(*without, b.ticks, 100000)), -1) << name;
    }
}

namespace {

// Two sessions stepped in turn on one thread (the second `lag` ticks behind the first, both from
// tick `from`), and the first again after both: each repeats its lone run bit for bit. A copy of a
// state stepped on its own does not change what the original does next.
void expect_interleaved_sessions_repeat_their_lone_runs(const std::string& name, size_t from, size_t n,
                                                        size_t lag) {
    const cli::BenchScene b = load(name);
    ASSERT_GT(b.ticks.size(), from + lag + n) << name;
    const auto model = model_for(b, true);
    const std::vector<Pose> first(b.ticks.begin() + long(from), b.ticks.begin() + long(from + n));
    const std::vector<Pose> second(b.ticks.begin() + long(from + lag), b.ticks.begin() + long(from + lag + n));
    const std::vector<Tick> alone_first = run(*model, first, n), alone_second = run(*model, second, n);
    ASSERT_GT(contact_ticks(alone_first), 100) << name;
    ASSERT_GT(contact_ticks(alone_second), 100) << name;
    State s1 = make_state(first.front()), s2 = make_state(second.front());
    std::vector<Tick> mixed_first, mixed_second;
    for (size_t i = 0; i < n; ++i) {
        mixed_first.push_back(tick_of(step(*model, s1, first[i])));
        mixed_second.push_back(tick_of(step(*model, s2, second[i])));
    }
    EXPECT_EQ(first_difference(mixed_first, alone_first), -1) << name;
    EXPECT_EQ(first_difference(mixed_second, alone_second), -1) << name;
    EXPECT_EQ(first_difference(run(*model, first, n), alone_first), -1) << name;
    State a = make_state(first.front());
    std::vector<Tick> with_copy;
    for (size_t i = 0; i < n; ++i) {
        if (i == n / 2) {
            State copy = a;
            for (size_t j = i; j < i + 50; ++j) step(*model, copy, second[j]);
        }
        with_copy.push_back(tick_of(step(*model, a, first[i])));
    }
    EXPECT_EQ(first_difference(with_copy, alone_first), -1) << name;
}

}  // namespace

TEST(NearCache, InterleavedSessionsRepeatTheirLoneRuns) {
    expect_interleaved_sessions_repeat_their_lone_runs("dense_wedge_250k", 0, 2000, 400);
}

// The same in the tissue, where detect keeps the gingiva triangles round each piece and their
// bounds from tick to tick (Workspace::CompliantSet) and the guard their separations
// (SeparationMemo): the two sessions lean against the root 0.3 s apart.
TEST(NearCache, InterleavedTissueSessionsRepeatTheirLoneRuns) {
    expect_interleaved_sessions_repeat_their_lone_runs("quadrant_two_regions", 0, 2000, 300);
}

// The probe's pieces move together, and the sets of gingiva triangles round them (one per piece)
// used to leave their boxes at the same tick: five walks of the tissue's hierarchy in one. Each is
// now gathered anew ahead of need, one a tick, at the tick's end, and not on a tick where a piece
// has already outrun its set's room. Where that work goes depends on which ticks count as long
// (RendererSettings::defer_after_us, by the clock), so the session runs with the placement fixed
// (State::defer): by the ticks' counts of work alone, with the work waiting at every tick it may,
// and in spells of waiting and not, as on a machine whose ticks run long now and then. In every
// one the sets are gathered anew hundreds of times and no tick gathers more than two; by the
// counts alone, and always waiting, no more than one. (Spells once gave a tick three: on long
// ticks the sets waited, one gathered a tick, under a quarter of their room, until three pieces
// outran theirs at one tick. Now a set waits on a long tick only while it is the only one due.)
TEST(NearCache, TissueSetsAreGatheredAheadOneATick) {
    const cli::BenchScene b = load("quadrant_two_regions");
    ASSERT_FALSE(b.ticks.empty());
    const auto model = model_for(b, true);
    // placement: 0 by the counts, 1 always waiting, 2 + k spells from seed k.
    for (int placement = 0; placement < 2 + 24; ++placement) {
        const unsigned k = unsigned(std::max(placement - 2, 0));
        std::mt19937 rng(k);
        // Spells whose length is on average 5 to 45 ticks.
        const unsigned spell = 5 + 10 * (k % 5);
        bool waits = false;
        State state = make_state(b.ticks.front());
        int most = 0, total = 0, in_contact = 0;
        for (const Pose& p : b.ticks) {
            if (placement >= 2 && rng() % spell == 0) waits = !waits;
            state.defer = placement < 2 ? placement : int(waits);
            const StepResult r = step(*model, state, p);
            most = std::max(most, r.stats.compliant_gathers);
            total += r.stats.compliant_gathers;
            in_contact += r.status == StepStatus::Contact;
        }
        EXPECT_GT(in_contact, 4000) << "placement " << placement;
        EXPECT_GT(total, 200) << "placement " << placement;
        EXPECT_LE(most, placement < 2 ? 1 : 2) << "placement " << placement;
    }
}

// A session starts the step's caches afresh, the tissue sets and the edge and face memos as well
// as the near cache (Workspace::owner): run again after itself on one thread, the whole session does the
// same work at every tick (the same sets gathered anew, the same quiet triangles passed over, the
// same edges and vertices missing from the memos, the same triangles tested), not only gives the
// same answers. The bench's runs each start from such
// a state, so its least time over runs compares like with like at every tick. (With the memos
// kept from the session before, the second run found in them what the first had to search for.)
TEST(NearCache, ASessionRunAgainDoesTheSameWork) {
    const cli::BenchScene b = load("quadrant_two_regions");
    ASSERT_GT(b.ticks.size(), size_t(5000));
    // The work ahead of need placed by the ticks' counts of work alone, not by the clock
    // (RendererSettings::defer_after_us).
    RendererSettings settings;
    settings.defer_after_us = std::numeric_limits<double>::infinity();
    const auto model = test::bench_model(b, settings);
    struct Work {
        int tested, gathers, quiet, near, edge_queries, face_searches;
        bool operator==(const Work&) const = default;
    };
    auto session = [&] {
        std::vector<Work> out;
        State state = make_state(b.ticks.front());
        for (size_t i = 0; i < b.ticks.size(); ++i) {
            const StepResult r = step(*model, state, b.ticks[i]);
            out.push_back(Work{r.stats.triangles_tested, r.stats.compliant_gathers, r.stats.quiet_triangles,
                               r.stats.triangles_near, r.stats.edge_queries, r.stats.face_searches});
        }
        return out;
    };
    const std::vector<Work> first = session(), second = session();
    int gathers = 0, quiet = 0, edges = 0, faces = 0;
    for (size_t i = 0; i < first.size(); ++i) {
        ASSERT_EQ(first[i], second[i]) << "tick " << i;
        gathers += first[i].gathers;
        quiet += first[i].quiet;
        edges += first[i].edge_queries;
        faces += first[i].face_searches;
    }
    // The sets are gathered anew along the way, their quiet marks used, and the memos both filled
    // and missed.
    EXPECT_GT(gathers, 100);
    EXPECT_GT(quiet, 100000);
    EXPECT_GT(edges, 1000);
    EXPECT_GT(faces, 1000);
}

// When the work ahead of need is done (a slice of the next superset, a tissue set gathered anew
// before the tool leaves it) changes no answer: the tissue session with that work waiting at every
// tick it may (State::defer = 1, as after a tick longer than RendererSettings::defer_after_us)
// and with it never waiting (0) gives the same pose, force, torque and status to the bit at every
// tick, though the two do other work at many ticks.
TEST(NearCache, WorkAheadOfNeedWaitingChangesNoAnswer) {
    const cli::BenchScene b = load("quadrant_two_regions");
    ASSERT_GT(b.ticks.size(), size_t(5000));
    const auto model = model_for(b, true);
    // One session after the other on this thread (each carries its caches along its own ticks).
    auto session = [&](int defer) {
        std::vector<StepResult> out;
        State state = make_state(b.ticks.front());
        for (size_t i = 0; i < b.ticks.size(); ++i) {
            state.defer = defer;
            out.push_back(step(*model, state, b.ticks[i]));
            EXPECT_EQ(state.defer, -1) << "tick " << i;  // for one step only
        }
        return out;
    };
    const std::vector<StepResult> waits = session(1), never = session(0);
    int other_work = 0, deferred = 0, in_contact = 0;
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        const StepResult &a = waits[i], &c = never[i];
        ASSERT_EQ(a.status, c.status) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.graphic, &c.graphic, sizeof(Pose)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.force_N, &c.force_N, sizeof(Vec3)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.torque_Nm, &c.torque_Nm, sizeof(Vec3)), 0) << "tick " << i;
        EXPECT_FALSE(c.stats.deferred) << "tick " << i;
        deferred += a.stats.deferred;
        in_contact += a.status == StepStatus::Contact;
        other_work += a.stats.triangles_tested != c.stats.triangles_tested ||
                      a.stats.compliant_gathers != c.stats.compliant_gathers ||
                      a.stats.quiet_triangles != c.stats.quiet_triangles;
    }
    EXPECT_EQ(deferred, int(b.ticks.size()));
    EXPECT_GT(in_contact, 4000);
    // The placement did change: the work differs at many ticks.
    EXPECT_GT(other_work, 500);
}

// Edge memos made together run out together: where a stroke carries the probe on, some 50-90 of
// them at one tick, each a walk of the piece's edge hierarchy and a sort. With
// RendererSettings::edge_memos_ahead, one that a tick used after it had moved past half its room
// is made anew at the tick's end, a few a tick. The tissue session gives the same pose, force,
// torque and status to the bit at every tick with it and without it; with it, less than half as
// many memos are made anew inside the ticks (not ahead), and less than half as many ticks make
// kHeavyEdgeQueries (32) or more inside.
TEST(NearCache, EdgeMemosMadeAheadChangeNoAnswerAndSpreadTheirMaking) {
    const cli::BenchScene b = load("quadrant_two_regions");
    ASSERT_GT(b.ticks.size(), size_t(5000));
    RendererSettings ahead;
    ahead.defer_after_us = std::numeric_limits<double>::infinity();  // placed by the counts
    RendererSettings inside = ahead;
    inside.edge_memos_ahead = false;
    const auto with = test::bench_model(b, ahead), without = test::bench_model(b, inside);
    struct Session {
        std::vector<StepResult> ticks;
        long made_inside = 0, made_ahead = 0;
        int burst_ticks = 0;
    };
    auto session = [&](const Model& model) {
        Session out;
        State state = make_state(b.ticks.front());
        for (const Pose& p : b.ticks) {
            out.ticks.push_back(step(model, state, p));
            const StepStats& s = out.ticks.back().stats;
            const int made_inside = s.edge_queries - s.edge_memos_ahead;
            out.made_inside += made_inside;
            out.made_ahead += s.edge_memos_ahead;
            out.burst_ticks += made_inside >= 32;
        }
        return out;
    };
    const Session on = session(*with), off = session(*without);
    for (size_t i = 0; i < b.ticks.size(); ++i) {
        const StepResult &a = on.ticks[i], &c = off.ticks[i];
        ASSERT_EQ(a.status, c.status) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.graphic, &c.graphic, sizeof(Pose)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.force_N, &c.force_N, sizeof(Vec3)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a.torque_Nm, &c.torque_Nm, sizeof(Vec3)), 0) << "tick " << i;
    }
    EXPECT_EQ(off.made_ahead, 0);
    EXPECT_GT(on.made_ahead, 1000);
    // Measured: 14,365 made inside ticks without, 2,557 with (and 20,621 ahead); 65 ticks that
    // made 32 or more without, 20 with.
    EXPECT_LT(2 * on.made_inside, off.made_inside);
    EXPECT_LT(2 * on.burst_ticks, off.burst_ticks);
}

// Most gingiva triangles near the probe are near its long faces, not its vertices: gather's search
// of the piece's vertices finds none within its bounds, tick after tick. Each set's slot keeps how
// long its triangle stays so (Workspace::CompliantSet::quiet), and gather passes over it until
// then: some 350 of the ~400 such triangles a contact tick of the session. Looked at all the same
// (RendererSettings::audit_quiet_triangles), none of them has a vertex within the bounds (a vertex
// whose feature there gather leaves out, leaves_out_far_plane, is clear of them by how far it is
// from one it keeps): the step finds the features it would find without the cache, which passes
// over nothing.
TEST(NearCache, QuietTissueTrianglesArePassedOverAndGiveNoFeature) {
    const cli::BenchScene b = load("quadrant_two_regions");
    ASSERT_FALSE(b.ticks.empty());
    RendererSettings audited;
    audited.audit_quiet_triangles = true;
    // The work ahead of need (which sets the quiet marks afresh) placed by the ticks' counts
    // alone, not by the clock (RendererSettings::defer_after_us).
    audited.defer_after_us = std::numeric_limits<double>::infinity();
    const auto with = test::bench_model(b, audited), without = model_for(b, false);
    State state = make_state(b.ticks.front()), plain = make_state(b.ticks.front());
    long quiet = 0, featured = 0, quiet_without = 0;
    int in_contact = 0;
    for (const Pose& p : b.ticks) {
        const StepResult r = step(*with, state, p);
        quiet += r.stats.quiet_triangles;
        featured += r.stats.quiet_featured;
        in_contact += r.status == StepStatus::Contact;
        quiet_without += step(*without, plain, p).stats.quiet_triangles;
    }
    EXPECT_GT(in_contact, 4000);
    EXPECT_GT(quiet, 250L * in_contact);
    EXPECT_EQ(featured, 0);
    EXPECT_EQ(quiet_without, 0);
}

// What the guard remembers of a tissue triangle's separation (SeparationMemo) comes back at a
// later pose less the piece's motion bound since, for that triangle and piece only, and not once
// the pose it held at has left the ring or the cache was reset.
TEST(SeparationMemo, ComesBackLessTheMotionSinceWhileItsPoseIsKept) {
    const cli::BenchScene b = load("paper/cavity_0mm");
    ASSERT_FALSE(b.ticks.empty());
    const auto model = model_for(b, true);
    ASSERT_FALSE(model->tool.pieces.empty());
    const ToolPiece& piece = model->tool.pieces[0];
    auto c = std::make_unique<NearCache>();
    const Pose a = b.ticks.front();
    near_cache_begin(*c, *model, a);
    ASSERT_TRUE(near_cache_at(*c, *model, a));
    EXPECT_EQ(near_cache_separation(*c, *model, 0, 5, 0), -1e300);  // nothing kept yet
    near_cache_keep_separation(*c, 0, 5, 0, 1e-4);
    EXPECT_LE(near_cache_separation(*c, *model, 0, 5, 0), 1e-4);
    EXPECT_GT(near_cache_separation(*c, *model, 0, 5, 0), 1e-4 - 1e-9);

    Pose later = a;
    later.position += Vec3(2e-5, -1e-5, 3e-5);
    later.orientation = glm::normalize(quat_exp(Vec3(1e-3, 0.0, -2e-3)) * a.orientation);
    near_cache_begin(*c, *model, later);
    EXPECT_FALSE(near_cache_at(*c, *model, a));
    ASSERT_TRUE(near_cache_at(*c, *model, later));
    const double motion = motion_bound(piece, a, later);
    ASSERT_GT(motion, 3e-5);
    EXPECT_NEAR(near_cache_separation(*c, *model, 0, 5, 0), 1e-4 - motion, 1e-15);
    // Another triangle, object or piece: nothing.
    EXPECT_EQ(near_cache_separation(*c, *model, 0, 6, 0), -1e300);
    EXPECT_EQ(near_cache_separation(*c, *model, 1, 5, 0), -1e300);
    EXPECT_EQ(near_cache_separation(*c, *model, 0, 5, 1), -1e300);
    // A triangle kept at the later pose comes back whole there.
    near_cache_keep_separation(*c, 0, 6, 0, -2e-5);
    EXPECT_GT(near_cache_separation(*c, *model, 0, 6, 0), -2e-5 - 1e-9);

    // Once the first pose has left the ring, its memo bounds nothing.
    Pose p = later;
    for (int i = 0; i < kNearCacheSlots; ++i) {
        p.position += Vec3(1e-7, 0.0, 0.0);
        near_cache_begin(*c, *model, p);
    }
    EXPECT_EQ(near_cache_separation(*c, *model, 0, 5, 0), -1e300);
    // A reset forgets the rest.
    near_cache_keep_separation(*c, 0, 7, 0, 1e-4);
    ASSERT_GT(near_cache_separation(*c, *model, 0, 7, 0), 0.0);
    near_cache_reset(*c);
    EXPECT_EQ(near_cache_separation(*c, *model, 0, 7, 0), -1e300);
}

// box_motion: no point within the radius of the tool's origin moves further from the earlier pose
// to any pose of the box than its move plus its turn times the radius, for boxes and earlier poses of every lay-out the
// passes of a tick meet (turns of the box against the way from there included), and the bound is
// not loose by more than a small factor.
TEST(BoxMotionBound, NoPointOfTheBoxMovesFurther) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto rand_vec = [&](double s) { return s * Vec3(u(rng), u(rng), u(rng)); };
    const double radius = 0.02;
    double worst = 0.0, loosest = 1e300;
    for (int trial = 0; trial < 2000; ++trial) {
        Pose from;
        from.position = rand_vec(0.05);
        from.orientation = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
        const Vec3 way_turn = rand_vec(0.03);
        Pose at;
        // Pure turns in every other trial: there the turns' composition is all the bound has.
        const bool turns_only = trial % 2 == 0;
        at.position = from.position + (turns_only ? Vec3(0.0) : rand_vec(1e-3));
        at.orientation = glm::normalize(quat_exp(way_turn) * from.orientation);
        const Mat3 frame = glm::mat3_cast(glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng))));
        double lower[6], upper[6];
        // Box turns about the way back in a third of the trials: where composing turns matters most.
        const Vec3 back = trial % 3 < 2 ? -(glm::transpose(frame) * way_turn) : Vec3(0.0);
        for (int j = 0; j < 6; ++j) {
            const double c = j < 3 ? 0.0 : back[j - 3];
            const double s = j < 3 ? (turns_only ? 0.0 : 1e-3) : 0.02;
            const double a = c + s * u(rng), b = c + s * u(rng);
            lower[j] = std::min(a, b);
            upper[j] = std::max(a, b);
        }
        const BoxMotion motion = box_motion(from, at, frame, lower, upper);
        const double bound = motion.move_m + motion.turn * radius;
        ASSERT_TRUE(std::isfinite(bound)) << "trial " << trial;
        double most = 0.0;
        for (int i = 0; i < 200; ++i) {
            double x[6];
            for (int j = 0; j < 6; ++j) {
                const bool corner = i < 64;
                const double f = corner ? double((i >> j) & 1) : 0.5 * (u(rng) + 1.0);
                x[j] = lower[j] + f * (upper[j] - lower[j]);
            }
            const Vec3 p = at.position + frame * Vec3(x[0], x[1], x[2]);
            const Quat q = glm::normalize(quat_exp(frame * Vec3(x[3], x[4], x[5])) * at.orientation);
            for (int n = 0; n < 8; ++n) {
                Vec3 a = rand_vec(1.0);
                a *= radius / std::max(glm::length(a), 1e-12) * (n < 6 ? 1.0 : 0.5 * (u(rng) + 1.0));
                most = std::max(most, glm::length((p + q * a) - (from.position + from.orientation * a)));
            }
        }
        ASSERT_LE(most, bound) << "trial " << trial;
        worst = std::max(worst, most / bound);
        loosest = std::min(loosest, most / bound);
    }
    EXPECT_GT(worst, 0.8);     // some trials come close to the bound
    EXPECT_GT(loosest, 0.25);  // and none is loose by more than 4x
}

// Turns beyond the bound's small-angle reasoning give no bound.
TEST(BoxMotionBound, LargeTurnsGiveNoBound) {
    Pose from, at;
    const double lower[6] = {0, 0, 0, -0.2, 0, 0}, upper[6] = {0, 0, 0, 0.2, 0, 0};
    const BoxMotion motion = box_motion(from, at, Mat3(1.0), lower, upper);
    EXPECT_TRUE(std::isinf(motion.move_m + motion.turn * 0.01));
}

namespace {

// A probe-like piece for the per-triangle bounds: a bent line of segments from the tool's origin
// (its tip end) 12 mm up, in the tool frame. Every point of it is a point of the piece, so the
// bounds, which hold for any set of points, hold for it.
struct Polyline {
    std::vector<Vec3> points;
    double radius = 0.0;  // furthest point from the origin
};

Polyline probe_line(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Polyline p;
    for (int i = 0; i <= 6; ++i) {
        const double y = 0.002 * i;
        p.points.push_back(i == 0 ? Vec3(0.0) : Vec3(2e-4 * u(rng), y, 2e-4 * u(rng)));
        p.radius = std::max(p.radius, glm::length(p.points.back()));
    }
    return p;
}

double polyline_distance(const Polyline& line, const Pose& pose, const Vec3& a, const Vec3& b, const Vec3& c) {
    double d = 1e300;
    for (size_t i = 0; i + 1 < line.points.size(); ++i)
        d = std::min(d, segment_triangle_distance(pose.position + pose.orientation * line.points[i],
                                                  pose.position + pose.orientation * line.points[i + 1], a, b, c));
    return d;
}

// A small triangle (about 0.1 mm, as on a dense tooth mesh) round a point.
void small_triangle(std::mt19937& rng, const Vec3& at, Vec3& a, Vec3& b, Vec3& c) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    a = at + 5e-5 * Vec3(u(rng), u(rng), u(rng));
    b = at + 5e-5 * Vec3(u(rng), u(rng), u(rng));
    c = at + 5e-5 * Vec3(u(rng), u(rng), u(rng));
}

// A pose within 10 mm of the origin on each axis, turned anyhow.
Pose random_pose(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Pose p;
    p.position = 0.01 * Vec3(u(rng), u(rng), u(rng));
    p.orientation = glm::normalize(Quat(u(rng), u(rng), u(rng), u(rng)));
    return p;
}

// A box of the step's coordinates as the force-continuity boxes are: up to 20 um of move and
// 2 mrad of turn a side on each axis.
void random_box(std::mt19937& rng, double lower[6], double upper[6]) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int j = 0; j < 6; ++j) {
        const double s = j < 3 ? 2e-5 : 2e-3;
        lower[j] = -s * 0.5 * (u(rng) + 1.0);
        upper[j] = s * 0.5 * (u(rng) + 1.0);
    }
}

}  // namespace

// triangle_motion: a triangle's distance from the piece changes by no more than the bound from
// the distance at the earlier pose and the triangle's reach from the origin now, for motions of
// a tick or a few; near the origin it is far below the piece's own bound (its centre's
// displacement plus the turn times its spread), which is what lets the near cache settle the
// triangles at a probe's tip without measuring them.
TEST(TriangleMotion, BoundsHowFarATrianglesDistanceMoves) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Polyline line = probe_line(rng);
    ToolPiece piece;  // for motion_bound: the line's box centre and spread
    Vec3 lo(1e300), hi(-1e300);
    for (const Vec3& p : line.points) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    piece.centre = 0.5 * (lo + hi);
    for (const Vec3& p : line.points) piece.spread_m = std::max(piece.spread_m, glm::length(p - piece.centre));
    double worst = 0.0;
    int near_origin = 0, tighter = 0, turning = 0, halved = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const Pose from = random_pose(rng);
        Pose to;
        const double move = trial % 4 == 0 ? 0.0 : 5e-5 * (u(rng) + 1.0);
        to.position = from.position + move * glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        to.orientation = glm::normalize(quat_exp(5e-3 * (u(rng) + 1.0) * glm::normalize(Vec3(u(rng), u(rng), u(rng)))) *
                                        from.orientation);
        // A triangle beside the line at the earlier pose, up to 0.3 mm off it.
        const Vec3 on = from.position + from.orientation * glm::mix(line.points[0], line.points.back(), 0.5 * (u(rng) + 1.0));
        Vec3 a, b, c;
        small_triangle(rng, on + 3e-4 * Vec3(u(rng), u(rng), u(rng)), a, b, c);
        const double d1 = polyline_distance(line, from, a, b, c), d2 = polyline_distance(line, to, a, b, c);
        const double rho = std::sqrt(std::max({glm::dot(a - to.position, a - to.position),
                                               glm::dot(b - to.position, b - to.position),
                                               glm::dot(c - to.position, c - to.position)}));
        const double bound = triangle_motion(origin_motion(from, to), d1, rho);
        ASSERT_LE(std::abs(d2 - d1), bound) << "trial " << trial;
        worst = std::max(worst, std::abs(d2 - d1) / bound);
        if (rho < 1.5e-3) {
            ++near_origin;
            const double piece_bound = motion_bound(piece, from, to);
            tighter += bound < piece_bound;
            if (move == 0.0) {
                ++turning;
                halved += bound < 0.5 * piece_bound;
            }
        }
    }
    EXPECT_GT(worst, 0.5);  // not loose everywhere
    ASSERT_GT(near_origin, 200);
    // Near the tip, below the piece's bound but where the turn takes the piece's centre back
    // against the move (the piece's bound then counts the smaller displacement).
    EXPECT_GT(tighter, near_origin * 9 / 10);
    ASSERT_GT(turning, 50);
    EXPECT_EQ(halved, turning);  // and where the tool only turns, under half of it
}

// PieceReach::of: a triangle further than its reach from the piece at the box's base stays out of
// the contact distance at every pose of the box (its corners and poses inside), for boxes that
// move and turn as the step's force-continuity boxes do; and near the origin that reach is well
// inside the piece's reach, so such triangles exist.
TEST(PieceReach, ATriangleBeyondItsReachStaysOutOfContactOverTheBox) {
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Polyline line = probe_line(rng);
    RendererSettings S;
    int beyond = 0, only_by_triangle = 0;
    for (int trial = 0; trial < 1500; ++trial) {
        const Pose base = random_pose(rng);
        double lower[6], upper[6];
        random_box(rng, lower, upper);
        const PieceReach pr = piece_reach(S, line.radius, base.position, lower, upper);
        const Vec3 on = base.position + base.orientation * glm::mix(line.points[0], line.points.back(), 0.5 * (u(rng) + 1.0));
        Vec3 a, b, c;
        small_triangle(rng, on + 8e-5 * Vec3(u(rng), u(rng), u(rng)), a, b, c);
        const double d = polyline_distance(line, base, a, b, c), reach = pr.of(pr.rho(a, b, c));
        ASSERT_LE(reach, pr.reach);
        if (!(d > reach)) continue;
        ++beyond;
        only_by_triangle += d <= pr.reach;
        for (int i = 0; i < 200; ++i) {
            double x[6];
            for (int j = 0; j < 6; ++j) {
                const double f = i < 64 ? double((i >> j) & 1) : 0.5 * (u(rng) + 1.0);
                x[j] = lower[j] + f * (upper[j] - lower[j]);
            }
            Pose at;
            at.position = base.position + Vec3(x[0], x[1], x[2]);
            at.orientation = glm::normalize(quat_exp(Vec3(x[3], x[4], x[5])) * base.orientation);
            ASSERT_GT(polyline_distance(line, at, a, b, c), S.contact_distance_m) << "trial " << trial << " pose " << i;
        }
    }
    EXPECT_GT(beyond, 300);
    EXPECT_GT(only_by_triangle, 50);  // beyond their own reach though within the piece's
}

// PieceReach::of, at its edge: a small triangle put where a corner of the box brings a point of
// the piece (within the contact distance of it there) is within its reach of the piece at the
// base, for points all along a probe's length; and the reach is not loose, some such triangles
// lying over three quarters of the way out to it.
TEST(PieceReach, ATriangleTheBoxBringsIntoContactIsInReach) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Polyline line = probe_line(rng);
    RendererSettings S;
    int tight = 0, trials = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const Pose base = random_pose(rng);
        double lower[6], upper[6], x[6];
        random_box(rng, lower, upper);
        for (int j = 0; j < 6; ++j) x[j] = (trial >> j) & 1 ? upper[j] : lower[j];
        const PieceReach pr = piece_reach(S, line.radius, base.position, lower, upper);
        Pose at;
        at.position = base.position + Vec3(x[0], x[1], x[2]);
        at.orientation = glm::normalize(quat_exp(Vec3(x[3], x[4], x[5])) * base.orientation);
        // A point of the piece, where it is at the base and at the corner.
        const size_t i = size_t(trial) % (line.points.size() - 1);
        const Vec3 local = glm::mix(line.points[i], line.points[i + 1], 0.5 * (u(rng) + 1.0));
        const Vec3 p0 = base.position + base.orientation * local, p1 = at.position + at.orientation * local;
        const Vec3 way = p1 - p0;
        if (!(glm::length(way) > 0.0)) continue;
        // A triangle a micrometre across just ahead of the point at the corner, facing the way.
        const Vec3 n = glm::normalize(way);
        const Vec3 e1 = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
        const Vec3 e2 = glm::cross(n, e1);
        const Vec3 c = p1 + 0.5 * S.contact_distance_m * n;
        const Vec3 a = c + 5e-7 * e1, b = c - 2.5e-7 * e1 + 4e-7 * e2, d = c - 2.5e-7 * e1 - 4e-7 * e2;
        ASSERT_LE(polyline_distance(line, at, a, b, d), S.contact_distance_m) << "trial " << trial;
        const double gap = polyline_distance(line, base, a, b, d), reach = pr.of(pr.rho(a, b, d));
        ++trials;
        ASSERT_LE(gap, reach) << "trial " << trial << ": the corner brings it into contact";
        tight += gap > 0.75 * reach;
    }
    EXPECT_GT(trials, 2500);
    EXPECT_GT(tight, 10);
}

namespace {

// The gap along unit direction n between a set of points (a convex piece's hull) and a triangle:
// the least of n . (p - t) over them.
double gap_along(const std::vector<Vec3>& points, const Pose& pose, const Vec3& n, const Vec3& a, const Vec3& b,
                 const Vec3& c) {
    double least = 1e300;
    for (const Vec3& p : points) least = std::min(least, glm::dot(n, pose.position + pose.orientation * p));
    return least - std::max({glm::dot(n, a), glm::dot(n, b), glm::dot(n, c)});
}

}  // namespace

// direction_lower_bound: after a motion of a tick or a few, the gap along the earlier direction
// is no less than the bound, and so neither is the distance (which no gap along a direction
// exceeds); the bound follows the motion along the direction, so where the tool slides across it
// the bound stays near the gap while the piece's own motion bound grows with the slide.
TEST(DirectionLowerBound, BoundsTheGapAlongTheDirectionAfterAMotion) {
    std::mt19937 rng(37);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Polyline line = probe_line(rng);
    int sliding = 0, held = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const Pose from = random_pose(rng);
        const Vec3 on = from.position + from.orientation * glm::mix(line.points[0], line.points.back(), 0.5 * (u(rng) + 1.0));
        Vec3 a, b, c;
        small_triangle(rng, on + 3e-4 * Vec3(u(rng), u(rng), u(rng)), a, b, c);
        // A direction from the triangle roughly towards the piece, as GJK leaves one.
        const Vec3 n = glm::normalize(on - (a + b + c) / 3.0 + 1e-4 * Vec3(u(rng), u(rng), u(rng)));
        const double gap = gap_along(line.points, from, n, a, b, c);
        Pose to;
        const bool slide = trial % 2 == 0;
        Vec3 shift = 5e-5 * Vec3(u(rng), u(rng), u(rng));
        if (slide) shift -= glm::dot(shift, n) * n;  // across the direction
        to.position = from.position + shift;
        const double angle = trial % 4 == 0 ? 0.0 : 2e-3 * 0.5 * (u(rng) + 1.0);
        to.orientation = glm::normalize(quat_exp(angle * glm::normalize(Vec3(u(rng), u(rng), u(rng)))) * from.orientation);
        const OriginMotion om = origin_motion(from, to);
        // Scaled by 3: the direction need not be unit.
        const double bound = direction_lower_bound(om, 3.0 * n, gap, line.radius);
        ASSERT_LE(bound, gap_along(line.points, to, n, a, b, c)) << "trial " << trial;
        ASSERT_LE(bound, polyline_distance(line, to, a, b, c) + 1e-15) << "trial " << trial;
        if (slide && angle == 0.0) {
            ++sliding;
            held += gap - bound < 1e-9 && glm::length(shift) > 1e-5;
        }
    }
    EXPECT_GT(sliding, 500);
    EXPECT_GT(held, sliding / 2);  // a slide of 10-87 um leaves it within a nanometre of the gap
    // No direction, or no gap: no bound.
    EXPECT_EQ(direction_lower_bound(OriginMotion{}, Vec3(0.0), 1e-3, 0.01), -1e300);
    EXPECT_EQ(direction_lower_bound(OriginMotion{}, Vec3(1, 0, 0), -1e300, 0.01), -1e300);
}
