// The device-side wrench guard: finite output, magnitude clamp keeping direction, bounded change
// per tick, and no change at all to a wrench that is already within every limit.
#include "sulcus/haptics/force_limits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sulcus {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDt = 0.001;  // 1 kHz servo tick

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

TEST(ForceLimits, NonFiniteInputGivesFiniteZero) {
    const ForceLimits limits;
    const Vec3 prev_f(1.0, 0.0, 0.0), prev_t(0.0, 0.01, 0.0);
    const Vec3 bad[] = {Vec3(kNaN, 0, 0), Vec3(0, kInf, 0), Vec3(0, 0, -kInf)};
    for (const Vec3& b : bad) {
        const WrenchOut f = limit_wrench(limits, b, Vec3(0.0), prev_f, prev_t, kDt);
        EXPECT_TRUE(f.non_finite_input);
        EXPECT_EQ(f.force_N, Vec3(0.0));
        EXPECT_EQ(f.torque_Nm, Vec3(0.0));
        // A bad torque discards the force too: the whole wrench is suspect.
        const WrenchOut t = limit_wrench(limits, Vec3(0.5, 0, 0), b, prev_f, prev_t, kDt);
        EXPECT_TRUE(t.non_finite_input);
        EXPECT_EQ(t.force_N, Vec3(0.0));
        EXPECT_EQ(t.torque_Nm, Vec3(0.0));
    }
}

TEST(ForceLimits, ClampKeepsDirection) {
    ForceLimits limits;
    limits.max_force_rate_N_per_s = kInf;  // isolate the clamp
    limits.max_torque_rate_Nm_per_s = kInf;
    const Vec3 f(30.0, -40.0, 0.0);    // 50 N
    const Vec3 t(0.0, 0.3, 0.4);       // 0.5 N m
    const WrenchOut w = limit_wrench(limits, f, t, Vec3(0.0), Vec3(0.0), kDt);
    EXPECT_TRUE(w.force_clamped);
    EXPECT_TRUE(w.torque_clamped);
    EXPECT_NEAR(glm::length(w.force_N), limits.max_force_N, 1e-12);
    EXPECT_NEAR(glm::length(w.torque_Nm), limits.max_torque_Nm, 1e-14);
    EXPECT_NEAR(glm::distance(glm::normalize(w.force_N), glm::normalize(f)), 0.0, 1e-15);
    EXPECT_NEAR(glm::distance(glm::normalize(w.torque_Nm), glm::normalize(t)), 0.0, 1e-15);
}

TEST(ForceLimits, HugeFiniteForceIsClampedNotZeroed) {
    ForceLimits limits;
    limits.max_force_rate_N_per_s = kInf;
    const Vec3 f(1e300, 1e300, 0.0);  // its plain length overflows to infinity
    const WrenchOut w = limit_wrench(limits, f, Vec3(0.0), Vec3(0.0), Vec3(0.0), kDt);
    EXPECT_FALSE(w.non_finite_input);
    ASSERT_TRUE(finite(w.force_N));
    EXPECT_NEAR(glm::length(w.force_N), limits.max_force_N, 1e-12);
    EXPECT_NEAR(w.force_N.x, w.force_N.y, 1e-15);
}

TEST(ForceLimits, RateLimitBoundsTheChangePerTick) {
    const ForceLimits limits;  // 1000 N/s and 30 N m/s: 1 N and 0.03 N m per 1 ms tick
    const Vec3 prev_f(0.5, 0.0, 0.0), prev_t(0.0, 0.0, 0.0);
    const Vec3 target_f(0.5, 2.5, 0.0), target_t(0.0, 0.0, 0.09);
    const WrenchOut w = limit_wrench(limits, target_f, target_t, prev_f, prev_t, kDt);
    EXPECT_TRUE(w.rate_limited);
    EXPECT_FALSE(w.force_clamped);
    EXPECT_NEAR(glm::distance(w.force_N, prev_f), 1.0, 1e-12);
    EXPECT_NEAR(glm::distance(w.torque_Nm, prev_t), 0.03, 1e-14);
    // The change points toward the target.
    EXPECT_NEAR(glm::distance(w.force_N, Vec3(0.5, 1.0, 0.0)), 0.0, 1e-12);

    // Ticking on reaches the target in the least number of ticks and never overshoots.
    Vec3 f = prev_f, t = prev_t;
    int ticks = 0;
    while (f != target_f && ticks < 100) {
        const WrenchOut step = limit_wrench(limits, target_f, target_t, f, t, kDt);
        EXPECT_LE(glm::distance(step.force_N, f), 1.0 + 1e-12);
        EXPECT_LE(glm::distance(step.torque_Nm, t), 0.03 + 1e-14);
        f = step.force_N;
        t = step.torque_Nm;
        ++ticks;
    }
    EXPECT_EQ(ticks, 3);
    EXPECT_NEAR(t.z, 0.09, 1e-15);
}

TEST(ForceLimits, ClampedTargetIsApproachedAtTheRate) {
    // A 100 N request from rest: the first tick sends 1 N, never more than the 3 N limit.
    const ForceLimits limits;
    Vec3 f(0.0), t(0.0);
    for (int i = 0; i < 10; ++i) {
        const WrenchOut w = limit_wrench(limits, Vec3(0, 0, -100.0), Vec3(0.0), f, t, kDt);
        EXPECT_LE(glm::length(w.force_N), limits.max_force_N + 1e-12);
        EXPECT_LE(glm::distance(w.force_N, f), 1.0 + 1e-12);
        f = w.force_N;
    }
    EXPECT_NEAR(f.z, -3.0, 1e-12);
}

TEST(ForceLimits, PassthroughWithinLimits) {
    const ForceLimits limits;
    const Vec3 f(0.3, -1.2, 0.7), t(0.01, 0.02, -0.03);
    const Vec3 prev_f(0.25, -1.0, 0.5), prev_t(0.0, 0.01, -0.02);
    const WrenchOut w = limit_wrench(limits, f, t, prev_f, prev_t, kDt);
    EXPECT_EQ(w.force_N, f);  // bit for bit
    EXPECT_EQ(w.torque_Nm, t);
    EXPECT_FALSE(w.non_finite_input);
    EXPECT_FALSE(w.force_clamped);
    EXPECT_FALSE(w.torque_clamped);
    EXPECT_FALSE(w.rate_limited);
}

TEST(ForceLimits, BadTickLengthHoldsThePreviousOutput) {
    const ForceLimits limits;
    const Vec3 prev_f(1.0, 0.0, 0.0), prev_t(0.0, 0.02, 0.0);
    for (double dt : {0.0, -0.001, kNaN, kInf}) {
        const WrenchOut w = limit_wrench(limits, Vec3(2.0, 0, 0), Vec3(0.0), prev_f, prev_t, dt);
        EXPECT_EQ(w.force_N, prev_f) << dt;
        EXPECT_EQ(w.torque_Nm, prev_t) << dt;
        EXPECT_TRUE(w.rate_limited) << dt;
    }
}

TEST(ForceLimits, BrokenLimitsFailSafeToZero) {
    ForceLimits limits;
    limits.max_force_N = kNaN;
    limits.max_torque_Nm = -1.0;
    const WrenchOut w = limit_wrench(limits, Vec3(1, 0, 0), Vec3(0, 0.01, 0), Vec3(0.0), Vec3(0.0), kDt);
    EXPECT_EQ(w.force_N, Vec3(0.0));
    EXPECT_EQ(w.torque_Nm, Vec3(0.0));
    EXPECT_TRUE(w.force_clamped);
    EXPECT_TRUE(w.torque_clamped);
}

TEST(ForceLimits, PreviousAboveTighterLimitIsBroughtDown) {
    // Limits lowered at run time: the output obeys the new magnitude limit at once.
    const ForceLimits limits;
    const WrenchOut w = limit_wrench(limits, Vec3(5, 0, 0), Vec3(0.0), Vec3(5, 0, 0), Vec3(0.0), kDt);
    EXPECT_NEAR(glm::length(w.force_N), limits.max_force_N, 1e-12);
    EXPECT_TRUE(w.force_clamped);
}

}  // namespace
}  // namespace sulcus
