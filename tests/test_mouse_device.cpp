// MouseDevice: the rate limit per tick (linear and angular), reaching the target, the workspace
// clamp, rejected targets, reads before start, no allocation in read/write, determinism, and a
// short run of the real servo loop with a UI thread handing over targets at display rate.
#include "allocation_counter.h"
#include "scene_helpers.h"

#include "sulcus/content/primitives.h"
#include "sulcus/haptics/mouse_device.h"
#include "sulcus/haptics/servo_loop.h"

#include <gtest/gtest.h>

#include <atomic>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

namespace sulcus {
namespace {

using test::mm;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

double angle_between(const Quat& a, const Quat& b) {
    const double d = std::abs(glm::dot(a, b));
    return 2.0 * std::acos(std::min(1.0, d));
}

TEST(MouseDevice, CapabilitiesAreAnInputOnlyDeviceWithTheConfiguredBoxAndRate) {
    MouseDeviceConfig config;
    config.rate_hz = 500.0;
    config.start_pose.position = Vec3(0.01, 0.02, 0.03);
    MouseDevice dev(config);
    const DeviceCapabilities& c = dev.capabilities();
    EXPECT_EQ(c.name, "Mouse and keyboard");
    EXPECT_EQ(c.input_dof, 6);
    EXPECT_EQ(c.output_dof, 0);
    EXPECT_EQ(c.max_force_N, 0.0);
    EXPECT_EQ(c.nominal_rate_Hz, 500.0);
    // Left zero: ±0.1 m around the start position.
    EXPECT_EQ(c.workspace_min_m, Vec3(0.01 - 0.1, 0.02 - 0.1, 0.03 - 0.1));
    EXPECT_EQ(c.workspace_max_m, Vec3(0.01 + 0.1, 0.02 + 0.1, 0.03 + 0.1));

    config.workspace_min_m = Vec3(-0.02, -0.01, -0.03);
    config.workspace_max_m = Vec3(0.02, 0.05, 0.03);
    MouseDevice boxed(config);
    EXPECT_EQ(boxed.capabilities().workspace_min_m, config.workspace_min_m);
    EXPECT_EQ(boxed.capabilities().workspace_max_m, config.workspace_max_m);
}

TEST(MouseDevice, ReadBeforeStartAndAfterStopFailsWithNotStarted) {
    MouseDevice dev;
    DeviceSample s;
    s.connected = true;
    EXPECT_FALSE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNotStarted);
    EXPECT_FALSE(s.connected);

    ASSERT_EQ(dev.start(), "");
    EXPECT_TRUE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNone);
    EXPECT_TRUE(s.connected);

    dev.stop();
    EXPECT_FALSE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNotStarted);
    EXPECT_FALSE(s.connected);
}

TEST(MouseDevice, StartRefusesBadSettings) {
    MouseDeviceConfig c;
    c.rate_hz = 0.0;
    EXPECT_NE(MouseDevice(c).start(), "");
    c = {};
    c.max_speed_m_per_s = -1.0;
    EXPECT_NE(MouseDevice(c).start(), "");
    c = {};
    c.max_angular_speed_rad_per_s = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NE(MouseDevice(c).start(), "");
    c = {};
    c.start_pose.position.x = std::numeric_limits<double>::infinity();
    EXPECT_NE(MouseDevice(c).start(), "");
}

TEST(MouseDevice, HoldsStillUntilATargetArrives) {
    MouseDeviceConfig config;
    config.start_pose.position = Vec3(0.001, 0.002, 0.003);
    MouseDevice dev(config);
    ASSERT_EQ(dev.start(), "");
    DeviceSample s;
    for (int i = 0; i < 10; ++i) {
        ASSERT_TRUE(dev.read(s));
        EXPECT_EQ(s.pose.position, config.start_pose.position);
        EXPECT_EQ(s.linear_velocity_m_per_s, Vec3(0.0));
    }
}

TEST(MouseDevice, MovesExactlyMaxSpeedTimesDtPerTickThenReachesTheTarget) {
    MouseDeviceConfig config;  // 1 kHz, 0.05 m/s: 50 um per tick
    MouseDevice dev(config);
    ASSERT_EQ(dev.start(), "");
    const double step = config.max_speed_m_per_s / config.rate_hz;
    const Vec3 target(0.003, -0.004, 0.0);  // 5 mm away: 100 full ticks
    ASSERT_TRUE(dev.set_target(Pose{target, Quat(1, 0, 0, 0)}));
    const Vec3 dir = glm::normalize(target);

    DeviceSample s;
    Vec3 prev = config.start_pose.position;
    for (int i = 1; i <= 99; ++i) {
        ASSERT_TRUE(dev.read(s));
        // Each tick: exactly one step along the straight line to the target.
        ASSERT_NEAR(glm::length(s.pose.position - prev), step, 1e-18) << "tick " << i;
        ASSERT_NEAR(glm::length(s.pose.position - dir * (i * step)), 0.0, 1e-15) << "tick " << i;
        ASSERT_NEAR(glm::length(s.linear_velocity_m_per_s), config.max_speed_m_per_s, 1e-12) << "tick " << i;
        ASSERT_NEAR(glm::length(s.linear_velocity_m_per_s - dir * config.max_speed_m_per_s), 0.0, 1e-12);
        prev = s.pose.position;
    }
    // The 100th tick lands on the target exactly, and then it stays.
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.pose.position, target);
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.pose.position, target);
    EXPECT_EQ(s.linear_velocity_m_per_s, Vec3(0.0));
}

TEST(MouseDevice, TurnsAtMostMaxAngularSpeedTimesDtPerTick) {
    MouseDeviceConfig config;  // 2 rad/s at 1 kHz: 2 mrad per tick
    MouseDevice dev(config);
    ASSERT_EQ(dev.start(), "");
    const double step = config.max_angular_speed_rad_per_s / config.rate_hz;
    const Vec3 axis = glm::normalize(Vec3(1.0, 2.0, -0.5));
    const Quat target = glm::angleAxis(0.1, axis);  // 50 ticks away
    ASSERT_TRUE(dev.set_target(Pose{Vec3(0.0), target}));
    DeviceSample s;
    Quat prev(1, 0, 0, 0);
    for (int i = 1; i < 50; ++i) {
        ASSERT_TRUE(dev.read(s));
        EXPECT_NEAR(angle_between(s.pose.orientation, prev), step, 1e-7) << "tick " << i;
        // On the way, about the same axis.
        EXPECT_NEAR(angle_between(s.pose.orientation, glm::angleAxis(i * step, axis)), 0.0, 1e-7) << "tick " << i;
        EXPECT_NEAR(glm::length(s.pose.orientation), 1.0, 1e-14);
        prev = s.pose.orientation;
    }
    for (int i = 0; i < 2; ++i) ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.pose.orientation, target);
}

TEST(MouseDevice, KeepsThePositionInsideTheWorkspaceBox) {
    MouseDeviceConfig config;
    config.workspace_min_m = Vec3(-0.002, -0.002, -0.002);
    config.workspace_max_m = Vec3(0.002, 0.002, 0.002);
    MouseDevice dev(config);
    ASSERT_EQ(dev.start(), "");
    ASSERT_TRUE(dev.set_target(Pose{Vec3(0.05, -0.01, 0.001), Quat(1, 0, 0, 0)}));
    DeviceSample s;
    for (int i = 0; i < 500; ++i) {
        ASSERT_TRUE(dev.read(s));
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(s.pose.position, config.workspace_min_m))) << i;
        ASSERT_TRUE(glm::all(glm::lessThanEqual(s.pose.position, config.workspace_max_m))) << i;
    }
    // It ends on the box point nearest the target.
    EXPECT_EQ(s.pose.position, Vec3(0.002, -0.002, 0.001));
    EXPECT_EQ(s.linear_velocity_m_per_s, Vec3(0.0));

    // A start pose outside the box starts on the box.
    config.start_pose.position = Vec3(0.0, 0.01, 0.0);
    MouseDevice outside(config);
    ASSERT_EQ(outside.start(), "");
    ASSERT_TRUE(outside.read(s));
    EXPECT_EQ(s.pose.position, Vec3(0.0, 0.002, 0.0));
}

TEST(MouseDevice, IgnoresAndCountsNonFiniteTargets) {
    MouseDevice dev(MouseDeviceConfig{});
    ASSERT_EQ(dev.start(), "");
    const Pose good{Vec3(0.001, 0.0, 0.0), Quat(1, 0, 0, 0)};
    ASSERT_TRUE(dev.set_target(good));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_FALSE(dev.set_target(Pose{Vec3(nan, 0.0, 0.0), Quat(1, 0, 0, 0)}));
    EXPECT_FALSE(dev.set_target(Pose{Vec3(0.0, inf, 0.0), Quat(1, 0, 0, 0)}));
    EXPECT_FALSE(dev.set_target(Pose{Vec3(0.0), Quat(nan, 0, 0, 0)}));
    EXPECT_FALSE(dev.set_target(Pose{Vec3(0.0), Quat(0, 0, 0, 0)}));
    EXPECT_EQ(dev.rejected_targets(), 4u);
    DeviceSample s;
    for (int i = 0; i < 40; ++i) {
        ASSERT_TRUE(dev.read(s));
        ASSERT_TRUE(finite(s.pose.position) && finite(s.linear_velocity_m_per_s));
    }
    EXPECT_EQ(s.pose.position, good.position);  // the good target was kept
    EXPECT_EQ(s.pose.orientation, good.orientation);

    // A non-unit quaternion is taken, normalised.
    ASSERT_TRUE(dev.set_target(Pose{good.position, Quat(2, 0, 0, 0)}));
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.pose.orientation, Quat(1, 0, 0, 0));
    EXPECT_EQ(dev.rejected_targets(), 4u);
}

TEST(MouseDevice, KeepsTheLastWrenchAndZeroForABadOne) {
    MouseDevice dev(MouseDeviceConfig{});
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(dev.last_force(), Vec3(0.0));
    dev.write(Vec3(0.1, -0.2, 0.3), Vec3(0.0, 0.001, 0.0));
    EXPECT_EQ(dev.last_force(), Vec3(0.1, -0.2, 0.3));
    EXPECT_EQ(dev.last_torque(), Vec3(0.0, 0.001, 0.0));
    DeviceSample s;
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNone);

    dev.write(Vec3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0), Vec3(0.0));
    EXPECT_EQ(dev.last_force(), Vec3(0.0));
    EXPECT_EQ(dev.bad_commands(), 1u);
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultBadCommand);
}

TEST(MouseDevice, ReadAndWriteDoNotAllocate) {
    MouseDevice dev(MouseDeviceConfig{});
    ASSERT_EQ(dev.start(), "");
    ASSERT_TRUE(dev.set_target(Pose{Vec3(0.01, 0.0, 0.0), glm::angleAxis(0.5, Vec3(0, 1, 0))}));
    DeviceSample s;
    const long before = test::heap_allocations();
    for (int i = 0; i < 1000; ++i) {
        if (i % 16 == 0) dev.set_target(Pose{Vec3(0.01, 1e-4 * i, 0.0), glm::angleAxis(0.5 + 1e-3 * i, Vec3(0, 1, 0))});
        dev.read(s);
        dev.write(Vec3(0.01 * i, 0.0, 0.0), Vec3(0.0));
        (void)dev.last_force();
    }
    EXPECT_EQ(test::heap_allocations(), before);
    EXPECT_NE(s.pose.position, Vec3(0.0));  // it did move
}

TEST(MouseDevice, SameTargetsAtTheSameTicksGiveTheSamePosesBitForBit) {
    auto run = [] {
        MouseDeviceConfig config;
        config.start_pose = Pose{Vec3(0.001, 0.0, -0.002), glm::angleAxis(0.3, glm::normalize(Vec3(1, 1, 0)))};
        MouseDevice dev(config);
        EXPECT_EQ(dev.start(), "");
        std::vector<DeviceSample> out;
        DeviceSample s;
        for (int i = 0; i < 600; ++i) {
            if (i % 17 == 0)  // a 60 Hz-ish UI: irregular jumps in position and orientation
                dev.set_target(Pose{Vec3(0.003 * std::sin(0.01 * i), 0.002 * std::cos(0.02 * i), 1e-4 * i),
                                    glm::angleAxis(0.002 * i, glm::normalize(Vec3(0.3, -1.0, 0.2)))});
            dev.read(s);
            out.push_back(s);
        }
        return out;
    };
    const std::vector<DeviceSample> a = run();
    const std::vector<DeviceSample> b = run();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(std::memcmp(&a[i].pose, &b[i].pose, sizeof(Pose)), 0) << "tick " << i;
        ASSERT_EQ(std::memcmp(&a[i].linear_velocity_m_per_s, &b[i].linear_velocity_m_per_s, sizeof(Vec3)), 0);
    }
    EXPECT_NE(a.back().pose.position, a.front().pose.position);
}

// The real loop, 200 ms: a UI thread moves the target 4 mm along +x in 60 Hz jumps while the
// servo thread reads the device at 1 kHz over a tiny free-space scene.
TEST(MouseDevice, DrivesTheServoLoopTowardTheTargetWithFiniteForce) {
    const TriMesh tool = make_box(Vec3(1.0 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -10.0 * mm, 0.0));
    const std::unique_ptr<Model> model = test::model_of(tool, {test::object("slab", slab)});
    ASSERT_TRUE(model);

    MouseDeviceConfig dconfig;
    MouseDevice dev(dconfig);

    ServoConfig config;
    config.rate_hz = 1000.0;
    config.duration_s = 0.2;
    config.trace_ticks = 400;
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, dev, *model), "");

    // The UI: 1 mm per 16 ms frame (62.5 mm/s, above the 50 mm/s limit), up to 3 mm, then hold.
    const double goal_x = 3.0 * mm;
    std::atomic<int> frames{0};
    std::thread ui([&] {
        for (int k = 1; loop.running(); ++k) {
            dev.set_target(Pose{Vec3(std::min(goal_x, k * 1.0 * mm), 0.0, 0.0), Quat(1, 0, 0, 0)});
            frames.fetch_add(1, std::memory_order_relaxed);
            std::this_thread::sleep_for(std::chrono::milliseconds(16));
        }
    });
    // Another thread watching the snapshots, as the display does.
    uint64_t seen = 0, backwards = 0, bad_force = 0;
    double last_x = 0.0;
    ServoSnapshot snap;
    while (loop.running()) {
        if (!loop.latest(snap)) continue;
        ++seen;
        if (snap.haptic.position.x < last_x) ++backwards;
        if (!finite(snap.force_N) || !finite(snap.torque_Nm)) ++bad_force;
        last_x = snap.haptic.position.x;
        std::this_thread::yield();
    }
    loop.wait();
    ui.join();

    const ServoStats st = loop.stats();
    std::printf("ticks %llu, UI frames %d, device at x = %.3f mm\n", static_cast<unsigned long long>(st.ticks),
                frames.load(), dev.current().position.x / mm);
    EXPECT_GT(seen, 0u);
    EXPECT_EQ(backwards, 0u);  // the target only moves forward, so the published pose does too
    EXPECT_EQ(bad_force, 0u);
    EXPECT_FALSE(st.non_finite_sent);
    EXPECT_EQ(st.read_failures, 0u);
    EXPECT_TRUE(finite(dev.last_force()));

    // Every tick: at most max_speed * dt toward +x, never past the goal, finite wrench.
    ASSERT_GT(loop.trace_size(), 100u);
    const double step = dconfig.max_speed_m_per_s / config.rate_hz;
    for (std::size_t i = 1; i < loop.trace_size(); ++i) {
        const TickSample& a = loop.trace()[i - 1];
        const TickSample& b = loop.trace()[i];
        ASSERT_TRUE(finite(b.force_N) && finite(b.torque_Nm)) << "tick " << i;
        ASSERT_LE(glm::length(b.device_pose.position - a.device_pose.position), step * (1 + 1e-9)) << "tick " << i;
        ASSERT_GE(b.device_pose.position.x, a.device_pose.position.x) << "tick " << i;
        ASSERT_LE(b.device_pose.position.x, goal_x) << "tick " << i;
    }

    // Both poses moved toward the target: the haptic one (the device's) and the drawn one (free
    // space, so the graphic tool follows it).
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_GT(last.haptic.position.x, 1.0 * mm);
    EXPECT_GT(last.graphic.position.x, 1.0 * mm);
    EXPECT_NEAR(last.graphic.position.x, last.haptic.position.x, 0.1 * mm);
    EXPECT_NEAR(last.haptic.position.y, 0.0, 1e-12);
}

}  // namespace
}  // namespace sulcus
