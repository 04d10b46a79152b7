// The servo-side safety layer: what force actually reaches the device, tick by tick, at start,
// in steady state, on stalls, bad numbers, disconnects, faults and e-stops, and under random input.
#include "sulcus/haptics/safety.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <utility>

#include "allocation_counter.h"

namespace sulcus {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDt = 0.001;  // 1 kHz servo tick

using S = SafetyState;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A healthy tick requesting this wrench.
SafetyInput good(const Vec3& f, const Vec3& t = Vec3(0.0)) {
    SafetyInput in;
    in.force_N = f;
    in.torque_Nm = t;
    in.step_ok = true;
    in.deadline_missed = false;
    in.device_connected = true;
    in.device_fault = false;
    in.dt_s = kDt;
    return in;
}

// Engages a fresh layer with a zero request, ramps in, and settles on sending exactly f, t.
void bring_to(SafetyLayer& s, const Vec3& f, const Vec3& t = Vec3(0.0)) {
    for (int i = 0; i < s.config().engage_ticks; ++i) s.tick(good(Vec3(0.0)));
    ASSERT_EQ(s.state(), S::RampIn);
    SafetyOutput o;
    for (int i = 0; i < 700; ++i) o = s.tick(good(f, t));
    ASSERT_EQ(o.state, S::Active);
    ASSERT_EQ(o.force_N, f);
    ASSERT_EQ(o.torque_Nm, t);
}

TEST(Safety, DefaultInputSendsNothing) {
    // A default-constructed input (not connected, no good step) never lets force through.
    SafetyLayer s;
    SafetyInput in;
    in.force_N = Vec3(0.0);
    for (int i = 0; i < 1000; ++i) {
        const SafetyOutput o = s.tick(in);
        EXPECT_EQ(o.force_N, Vec3(0.0));
        EXPECT_EQ(o.state, S::Idle);
    }
}

TEST(Safety, EngagesOnlyAfterTheRequestHasBeenSmall) {
    SafetyLayer s;  // 0.5 N / 0.01 N m for 3 consecutive ticks
    // A large request at start is never passed on, however long it lasts.
    for (int i = 0; i < 2000; ++i) {
        const SafetyOutput o = s.tick(good(Vec3(0, 2.0, 0)));
        ASSERT_EQ(o.force_N, Vec3(0.0));
        ASSERT_EQ(o.state, S::Idle);
    }
    // Two small ticks then a large one: the count starts over.
    EXPECT_EQ(s.tick(good(Vec3(0, 0.3, 0))).state, S::Idle);
    EXPECT_EQ(s.tick(good(Vec3(0, 0.3, 0))).state, S::Idle);
    EXPECT_EQ(s.tick(good(Vec3(0, 0.6, 0))).state, S::Idle);
    // A small force with a large torque does not count either.
    EXPECT_EQ(s.tick(good(Vec3(0, 0.3, 0), Vec3(0, 0.05, 0))).state, S::Idle);
    // Nor does a small request from a late step.
    SafetyInput late = good(Vec3(0.0));
    late.deadline_missed = true;
    EXPECT_EQ(s.tick(late).state, S::Idle);
    // Three small, good ticks engage; nothing is sent on them.
    for (int i = 0; i < 2; ++i) {
        const SafetyOutput o = s.tick(good(Vec3(0, 0.3, 0)));
        EXPECT_EQ(o.state, S::Idle);
        EXPECT_EQ(o.force_N, Vec3(0.0));
    }
    const SafetyOutput o = s.tick(good(Vec3(0, 0.3, 0)));
    EXPECT_EQ(o.state, S::RampIn);
    EXPECT_EQ(o.force_N, Vec3(0.0));
}

TEST(Safety, RampInIsLinearOverTheRampTime) {
    for (double ramp_s : {0.5, 0.2}) {
        SafetyConfig cfg;
        cfg.ramp_in_time_s = ramp_s;
        SafetyLayer s(cfg);
        for (int i = 0; i < cfg.engage_ticks; ++i) s.tick(good(Vec3(0.0)));
        ASSERT_EQ(s.state(), S::RampIn);
        const int n = int(std::lround(ramp_s / kDt));
        const Vec3 f(0, 2.0, 0), t(0, 0, 0.05);
        for (int k = 1; k <= n + 50; ++k) {
            const SafetyOutput o = s.tick(good(f, t));
            const double scale = std::min(1.0, k / double(n));
            EXPECT_NEAR(o.force_N.y, 2.0 * scale, 1e-9) << "tick " << k;
            EXPECT_NEAR(o.torque_Nm.z, 0.05 * scale, 1e-11) << "tick " << k;
            EXPECT_NEAR(o.scale, scale, 1e-9) << "tick " << k;
            EXPECT_EQ(o.state, k < n ? S::RampIn : S::Active) << "tick " << k;
            EXPECT_FALSE(o.rate_limited);
        }
    }
}

TEST(Safety, ClampsToTheDeviceLimits) {
    SafetyLayer s;  // 3 N, 0.1 N m
    bring_to(s, Vec3(0.0));
    const Vec3 f(6.0, 8.0, 0.0), t(0.0, 0.0, -1.0);  // 10 N, 1 N m
    SafetyOutput o;
    for (int i = 0; i < 20; ++i) {
        o = s.tick(good(f, t));
        ASSERT_LE(glm::length(o.force_N), 3.0 + 1e-12);
        ASSERT_LE(glm::length(o.torque_Nm), 0.1 + 1e-12);
    }
    EXPECT_TRUE(o.force_clamped);
    EXPECT_TRUE(o.torque_clamped);
    EXPECT_NEAR(o.force_N.x, 1.8, 1e-12);  // 3 N along (0.6, 0.8, 0)
    EXPECT_NEAR(o.force_N.y, 2.4, 1e-12);
    EXPECT_NEAR(o.torque_Nm.z, -0.1, 1e-14);
    EXPECT_EQ(o.state, S::Active);
}

TEST(Safety, RateLimitsTheChangePerTick) {
    SafetyLayer s;  // 1000 N/s: 1 N per 1 ms tick
    bring_to(s, Vec3(0.0));
    const double expect_up[] = {1.0, 2.0, 2.5};
    for (double e : expect_up) {
        const SafetyOutput o = s.tick(good(Vec3(0, 0, 2.5)));
        EXPECT_NEAR(o.force_N.z, e, 1e-12);
        EXPECT_EQ(o.rate_limited, e != 2.5);
    }
    const double expect_down[] = {1.5, 0.5, -0.5, -1.5, -2.0};
    for (double e : expect_down) EXPECT_NEAR(s.tick(good(Vec3(0, 0, -2.0))).force_N.z, e, 1e-12);
    // A longer tick allows a proportionally larger step (2 ms: 2 N).
    SafetyInput in = good(Vec3(0, 0, 2.0));
    in.dt_s = 0.002;
    EXPECT_NEAR(s.tick(in).force_N.z, 0.0, 1e-12);
}

TEST(Safety, FadesAfterConsecutiveDeadlineMisses) {
    SafetyLayer s;  // 3 misses, 50 ms fade
    const Vec3 f(0, 2.0, 0);
    bring_to(s, f);
    SafetyInput late = good(f);
    late.deadline_missed = true;
    // Two late steps: the request still passes (stale but bounded).
    for (int i = 0; i < 2; ++i) {
        const SafetyOutput o = s.tick(late);
        EXPECT_EQ(o.force_N, f);
        EXPECT_EQ(o.state, S::Active);
    }
    // The third starts a linear fade of what was sent, 2 N to 0 in 50 ticks.
    for (int k = 1; k <= 50; ++k) {
        const SafetyOutput o = s.tick(late);
        EXPECT_EQ(o.state, S::Fading);
        EXPECT_TRUE(o.deadline_stall);
        EXPECT_NEAR(o.force_N.y, 2.0 * (1.0 - k / 50.0), 1e-9) << "tick " << k;
    }
    for (int i = 0; i < 100; ++i) EXPECT_EQ(s.tick(late).force_N, Vec3(0.0));
}

TEST(Safety, ScatteredDeadlineMissesDoNotFade) {
    SafetyLayer s;
    const Vec3 f(0, 2.0, 0);
    bring_to(s, f);
    SafetyInput late = good(f);
    late.deadline_missed = true;
    for (int i = 0; i < 300; ++i) {
        const SafetyOutput o = s.tick(i % 3 == 2 ? good(f) : late);
        EXPECT_EQ(o.force_N, f);
        EXPECT_EQ(o.state, S::Active);
    }
}

TEST(Safety, FadesAfterAFailedStep) {
    SafetyLayer s;
    const Vec3 f(0, 2.0, 0);
    bring_to(s, f);
    SafetyInput held = good(f);
    held.step_ok = false;
    SafetyOutput o = s.tick(held);
    EXPECT_TRUE(o.step_failed);
    EXPECT_EQ(o.state, S::Fading);
    EXPECT_NEAR(o.force_N.y, 1.96, 1e-9);
    // Good steps afterwards do not snap the force back: the fade runs to zero.
    for (int k = 2; k <= 50; ++k) {
        o = s.tick(good(f));
        EXPECT_NEAR(o.force_N.y, 2.0 * (1.0 - k / 50.0), 1e-9) << "tick " << k;
        EXPECT_EQ(o.state, S::Fading);
    }
    EXPECT_EQ(o.force_N, Vec3(0.0));
}

TEST(Safety, NonFiniteOrHugeInputFadesAndNeverEmitsNaN) {
    const Vec3 f(1.2, -1.6, 0.0), t(0.0, 0.05, 0.0);
    struct Bad {
        Vec3 f, t;
        bool non_finite;
    };
    const Bad bad[] = {{Vec3(kNaN, 0, 0), t, true},  {f, Vec3(0, kInf, 0), true},
                       {Vec3(0, 0, -kInf), t, true}, {Vec3(0, 1e6, 0), t, false},
                       {f, Vec3(1e3, 0, 0), false},  {Vec3(1e300, 1e300, 0), t, false}};
    for (const Bad& b : bad) {
        SafetyLayer s;
        bring_to(s, f, t);
        SafetyInput in = good(b.f, b.t);
        for (int k = 1; k <= 60; ++k) {
            const SafetyOutput o = s.tick(in);
            ASSERT_TRUE(finite(o.force_N) && finite(o.torque_Nm));
            EXPECT_EQ(o.non_finite_input, b.non_finite);
            EXPECT_EQ(o.huge_input, !b.non_finite);
            EXPECT_EQ(o.state, S::Fading);
            // The last good wrench fades, in its own direction; the bad request is not clamped in.
            const double scale = std::max(0.0, 1.0 - k / 50.0);
            EXPECT_NEAR(glm::distance(o.force_N, f * scale), 0.0, 1e-9) << "tick " << k;
            EXPECT_NEAR(glm::distance(o.torque_Nm, t * scale), 0.0, 1e-11) << "tick " << k;
        }
    }
}

TEST(Safety, DisconnectZeroesInTheSameTick) {
    SafetyLayer s;
    const Vec3 f(0, 0, 3.0);
    bring_to(s, f);
    SafetyInput gone = good(f);
    gone.device_connected = false;
    SafetyOutput o = s.tick(gone);
    EXPECT_EQ(o.force_N, Vec3(0.0));  // no fade: zero at once
    EXPECT_EQ(o.torque_Nm, Vec3(0.0));
    EXPECT_TRUE(o.disconnected);
    EXPECT_TRUE(o.immediate_zero);
    EXPECT_EQ(o.state, S::Idle);
    // Back again with a large request: it waits for a small one, as at start.
    for (int i = 0; i < 500; ++i) {
        o = s.tick(good(f));
        ASSERT_EQ(o.force_N, Vec3(0.0));
        ASSERT_EQ(o.state, S::Idle);
    }
    for (int i = 0; i < 3; ++i) s.tick(good(Vec3(0.0)));
    EXPECT_EQ(s.state(), S::RampIn);
    EXPECT_NEAR(s.tick(good(f)).force_N.z, 3.0 / 500, 1e-12);
}

TEST(Safety, DeviceFaultLatchesUntilResetWithTheFaultCleared) {
    SafetyLayer s;
    const Vec3 f(0, 2.0, 0);
    bring_to(s, f);
    SafetyInput faulty = good(f);
    faulty.device_fault = true;
    SafetyOutput o = s.tick(faulty);
    EXPECT_EQ(o.force_N, Vec3(0.0));  // zero in the tick the fault is reported
    EXPECT_TRUE(o.fault);
    EXPECT_TRUE(o.immediate_zero);
    EXPECT_EQ(o.state, S::Faulted);
    // The fault goes away by itself: the latch holds.
    for (int i = 0; i < 500; ++i) {
        o = s.tick(good(Vec3(0.0)));
        ASSERT_EQ(o.force_N, Vec3(0.0));
        ASSERT_EQ(o.state, S::Faulted);
    }
    // A reset while the fault is still reported is refused, and dropped.
    s.reset();
    o = s.tick(faulty);
    EXPECT_TRUE(o.reset_refused);
    EXPECT_EQ(o.state, S::Faulted);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(s.tick(good(Vec3(0.0))).state, S::Faulted);
    // Likewise with the device gone.
    s.reset();
    SafetyInput gone = good(Vec3(0.0));
    gone.device_connected = false;
    EXPECT_TRUE(s.tick(gone).reset_refused);
    EXPECT_EQ(s.state(), S::Faulted);
    // Reset with the fault cleared: back to Idle, then engage and ramp in as at start.
    s.reset();
    o = s.tick(good(Vec3(0.0)));
    EXPECT_FALSE(o.reset_refused);
    EXPECT_FALSE(o.fault);
    EXPECT_EQ(o.state, S::Idle);
    EXPECT_EQ(o.force_N, Vec3(0.0));
    for (int i = 0; i < 2; ++i) s.tick(good(Vec3(0.0)));  // the reset tick was the first small one
    EXPECT_EQ(s.state(), S::RampIn);
    EXPECT_NEAR(s.tick(good(f)).force_N.y, 2.0 / 500, 1e-12);
}

TEST(Safety, EmergencyStopLatchesUntilReset) {
    SafetyLayer s;
    const Vec3 f(0, 2.0, 0), t(0.03, 0, 0);
    bring_to(s, f, t);
    s.emergency_stop();
    SafetyOutput o = s.tick(good(f, t));
    EXPECT_EQ(o.force_N, Vec3(0.0));  // the first tick after the call
    EXPECT_EQ(o.torque_Nm, Vec3(0.0));
    EXPECT_TRUE(o.estop);
    EXPECT_TRUE(o.immediate_zero);
    EXPECT_EQ(o.state, S::EStopped);
    EXPECT_EQ(s.state(), S::EStopped);
    for (int i = 0; i < 500; ++i) ASSERT_EQ(s.tick(good(Vec3(0.0))).force_N, Vec3(0.0));
    EXPECT_EQ(s.state(), S::EStopped);
    s.reset();
    o = s.tick(good(f));
    EXPECT_EQ(o.state, S::Idle);
    EXPECT_EQ(o.force_N, Vec3(0.0));
    // The button path latches the same way; a reset while it is held is refused.
    bring_to(s, f);
    SafetyInput pressed = good(f);
    pressed.estop_button = true;
    EXPECT_EQ(s.tick(pressed).force_N, Vec3(0.0));
    s.reset();
    o = s.tick(pressed);
    EXPECT_TRUE(o.reset_refused);
    EXPECT_EQ(o.state, S::EStopped);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(s.tick(good(f)).state, S::EStopped);
    s.reset();
    EXPECT_EQ(s.tick(good(f)).state, S::Idle);
    // An e-stop in the same tick as a reset wins.
    bring_to(s, f);
    s.emergency_stop();
    s.tick(good(f));
    s.reset();
    s.emergency_stop();
    o = s.tick(good(f));
    EXPECT_EQ(o.state, S::EStopped);
    EXPECT_EQ(o.force_N, Vec3(0.0));
}

TEST(Safety, RecoversOnlyAfterTheStallHasClearedForTheHoldOff) {
    SafetyLayer s;  // 50 ms fade, 200 ms hold-off
    const Vec3 f(0, 2.0, 0);
    bring_to(s, f);
    SafetyInput held = good(f);
    held.step_ok = false;
    s.tick(held);  // tick 1: stall; clear from tick 2 on
    SafetyOutput o;
    for (int n = 2; n <= 150; ++n) {
        o = s.tick(good(f));
        ASSERT_EQ(o.state, S::Fading) << n;
    }
    EXPECT_EQ(o.force_N, Vec3(0.0));
    // A late step at tick 151 starts the hold-off over: clear again from tick 152.
    SafetyInput late = good(f);
    late.deadline_missed = true;
    EXPECT_EQ(s.tick(late).state, S::Fading);
    for (int n = 152; n < 351; ++n) {
        o = s.tick(good(f));
        ASSERT_EQ(o.state, S::Fading) << n;
        ASSERT_EQ(o.force_N, Vec3(0.0)) << n;
    }
    o = s.tick(good(f));  // tick 351: 200 clear ticks
    EXPECT_EQ(o.state, S::RampIn);
    EXPECT_EQ(o.force_N, Vec3(0.0));
    // Then the ramp, from zero, over the ramp time.
    for (int k = 1; k <= 500; ++k) {
        o = s.tick(good(f));
        ASSERT_NEAR(o.force_N.y, 2.0 * k / 500.0, 1e-9) << k;
    }
    EXPECT_EQ(o.state, S::Active);
}

TEST(Safety, RandomInputAlwaysGivesFiniteBoundedOutput) {
    const SafetyConfig cfg;
    SafetyLayer s(cfg);
    std::mt19937_64 rng(20261124);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> n(0.0, 1.0);
    bool rough = false;  // rough stretches carry NaN, infinity, huge values and failed steps
    auto component = [&](double sigma) {
        const double r = rough ? u(rng) : 1.0;
        if (r < 0.002) return kNaN;
        if (r < 0.003) return u(rng) < 0.5 ? kInf : -kInf;
        if (r < 0.004) return (u(rng) < 0.5 ? 1.0 : -1.0) * std::pow(10.0, 3.0 + 305.0 * u(rng));
        return sigma * n(rng);
    };
    int seen[6] = {0, 0, 0, 0, 0, 0};
    Vec3 prev_f(0.0), prev_t(0.0);
    double sigma_f = 0.1, sigma_t = 0.002;
    for (int i = 0; i < 300000; ++i) {
        if (i % 1000 == 0) {  // calm and rough stretches, so that every state is reached
            rough = u(rng) < 0.5;
            sigma_f = u(rng) < 0.5 ? 0.1 : 5.0 * u(rng);
            sigma_t = u(rng) < 0.5 ? 0.002 : 0.2 * u(rng);
        }
        SafetyInput in;
        in.force_N = Vec3(component(sigma_f), component(sigma_f), component(sigma_f));
        in.torque_Nm = Vec3(component(sigma_t), component(sigma_t), component(sigma_t));
        in.step_ok = !rough || u(rng) > 0.003;
        in.deadline_missed = u(rng) < 0.05;
        in.device_connected = u(rng) > 0.0005;
        in.device_fault = u(rng) < 0.0002;
        in.estop_button = u(rng) < 0.00005;
        const double r = u(rng);
        in.dt_s = r < 0.97 ? kDt : r < 0.99 ? 0.02 * u(rng) : r < 0.995 ? kNaN : r < 0.998 ? -1.0 : 5.0;
        if (u(rng) < 0.002) s.reset();
        if (u(rng) < 0.00005) s.emergency_stop();

        const SafetyOutput o = s.tick(in);
        ++seen[int(o.state)];
        ASSERT_TRUE(finite(o.force_N) && finite(o.torque_Nm)) << i;
        ASSERT_LE(glm::length(o.force_N), cfg.limits.max_force_N + 1e-12) << i;
        ASSERT_LE(glm::length(o.torque_Nm), cfg.limits.max_torque_Nm + 1e-12) << i;
        if (!in.device_connected || in.device_fault || in.estop_button || o.immediate_zero) {
            ASSERT_EQ(o.force_N, Vec3(0.0)) << i;
            ASSERT_EQ(o.torque_Nm, Vec3(0.0)) << i;
        } else {
            const double dt =
                std::isfinite(in.dt_s) && in.dt_s > 0 ? std::min(in.dt_s, cfg.max_dt_s) : cfg.nominal_dt_s;
            ASSERT_LE(glm::distance(o.force_N, prev_f), cfg.limits.max_force_rate_N_per_s * dt + 1e-12) << i;
            ASSERT_LE(glm::distance(o.torque_Nm, prev_t), cfg.limits.max_torque_rate_Nm_per_s * dt + 1e-12) << i;
        }
        prev_f = o.force_N;
        prev_t = o.torque_Nm;
    }
    // The run went through every state, so the bounds above were checked in each.
    for (int k = 0; k < 6; ++k) EXPECT_GT(seen[k], 0) << to_string(SafetyState(k));
}

TEST(Safety, TickNeitherAllocatesNorThrows) {
    static_assert(noexcept(std::declval<SafetyLayer&>().tick(std::declval<const SafetyInput&>())));
    static_assert(noexcept(std::declval<SafetyLayer&>().emergency_stop()));
    static_assert(noexcept(std::declval<SafetyLayer&>().reset()));
    SafetyLayer s;
    const long before = sulcus::test::heap_allocations();
    const Vec3 f(0, 2.0, 0);
    for (int i = 0; i < 3; ++i) s.tick(good(Vec3(0.0)));
    for (int i = 0; i < 600; ++i) s.tick(good(f));
    SafetyInput bad = good(Vec3(kNaN));
    for (int i = 0; i < 300; ++i) s.tick(i < 10 ? bad : good(f));
    SafetyInput faulty = good(f);
    faulty.device_fault = true;
    s.tick(faulty);
    s.reset();
    s.tick(good(Vec3(0.0)));
    s.emergency_stop();
    s.tick(good(f));
    EXPECT_EQ(sulcus::test::heap_allocations() - before, 0);
    // The counter does count.
    const long probe = sulcus::test::heap_allocations();
    int* volatile p = new int(1);
    delete p;
    EXPECT_EQ(sulcus::test::heap_allocations() - probe, 1);
}

}  // namespace
}  // namespace sulcus
