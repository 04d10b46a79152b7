// PhantomDevice against the fake libHD (tests/fake_hd): loading and its failures, device
// initialisation, calibration, the scheduler, unit and frame conversions, force and torque
// output, error handling in the servo callback, the watchdog, stop(), and a short ServoLoop run.
#include "scene_helpers.h"

#include "fake_hd/fake_hd_control.h"
#include "openhaptics_abi.h"
#include "sulcus/content/primitives.h"
#include "sulcus/haptics/phantom_device.h"
#include "sulcus/haptics/servo_loop.h"

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

namespace sulcus {
namespace {

using namespace hd;
using test::mm;

template <class P>
bool eventually(P pred, double timeout_s = 0.5) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!pred()) {
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

bool near(const Vec3& a, const Vec3& b, double tol = 1e-12) { return glm::length(a - b) <= tol; }

class PhantomFake : public ::testing::Test {
protected:
    void SetUp() override {
        // The same file PhantomDevice opens: one library, one simulated device.
        lib_ = dlopen(SULCUS_FAKE_LIBHD, RTLD_NOW | RTLD_GLOBAL);
        ASSERT_NE(lib_, nullptr) << dlerror();
        reset = sym<fake_hd_reset_fn>("fake_hd_reset");
        state_fn = sym<fake_hd_state_fn>("fake_hd_state");
        set_init_error = sym<fake_hd_set_init_error_fn>("fake_hd_set_init_error");
        set_calibration = sym<fake_hd_set_calibration_fn>("fake_hd_set_calibration");
        set_start_error = sym<fake_hd_set_start_error_fn>("fake_hd_set_start_error");
        inject_error = sym<fake_hd_inject_error_fn>("fake_hd_inject_error");
        set_model = sym<fake_hd_set_model_fn>("fake_hd_set_model");
        set_figures = sym<fake_hd_set_figures_fn>("fake_hd_set_figures");
        set_transform = sym<fake_hd_set_transform_fn>("fake_hd_set_transform");
        set_velocity = sym<fake_hd_set_velocity_fn>("fake_hd_set_velocity");
        set_buttons = sym<fake_hd_set_buttons_fn>("fake_hd_set_buttons");
        reset();
        options.library_path = SULCUS_FAKE_LIBHD;
        options.use_env = false;
    }
    void TearDown() override {
        if (reset) reset();  // stops the fake's scheduler thread before the next test
        if (lib_) dlclose(lib_);
    }

    template <class F>
    F sym(const char* name) {
        F f = reinterpret_cast<F>(dlsym(lib_, name));
        EXPECT_NE(f, nullptr) << name;
        return f;
    }
    FakeHdState state() {
        FakeHdState s;
        state_fn(&s);
        return s;
    }
    Vec3 fake_force() {
        const FakeHdState s = state();
        return Vec3(s.last_force[0], s.last_force[1], s.last_force[2]);
    }
    void* lib_ = nullptr;
    PhantomOptions options;
    fake_hd_reset_fn reset = nullptr;
    fake_hd_state_fn state_fn = nullptr;
    fake_hd_set_init_error_fn set_init_error = nullptr;
    fake_hd_set_calibration_fn set_calibration = nullptr;
    fake_hd_set_start_error_fn set_start_error = nullptr;
    fake_hd_inject_error_fn inject_error = nullptr;
    fake_hd_set_model_fn set_model = nullptr;
    fake_hd_set_figures_fn set_figures = nullptr;
    fake_hd_set_transform_fn set_transform = nullptr;
    fake_hd_set_velocity_fn set_velocity = nullptr;
    fake_hd_set_buttons_fn set_buttons = nullptr;
};

TEST(PhantomDevice, MissingLibraryGivesOneLineMessageWithoutCrashing) {
    PhantomOptions o;
    o.use_env = false;
    o.library_candidates = {"libHD_sulcus_absent.so", "libHD_sulcus_absent.so.3"};
    PhantomDevice dev(o);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("OpenHaptics library libHD_sulcus_absent.so not found"), std::string::npos) << msg;
    EXPECT_NE(msg.find("tried: libHD_sulcus_absent.so, libHD_sulcus_absent.so.3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("install OpenHaptics"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    DeviceSample s;
    EXPECT_FALSE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNotStarted);
    dev.write(Vec3(1.0), Vec3(0.0));
    dev.stop();
    // A failed start leaves nothing held: a second device may try.
    PhantomDevice again(o);
    EXPECT_NE(again.start().find("not found"), std::string::npos);
}

TEST(PhantomDevice, LibraryWithoutTheEntryPointsIsNamed) {
    PhantomOptions o;
    o.use_env = false;
    o.library_path = "libm.so.6";
    PhantomDevice dev(o);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("libm.so.6 lacks the entry point hdInitDevice"), std::string::npos) << msg;
}

TEST_F(PhantomFake, InitFailureNamesTheHdError) {
    set_init_error(HD_COMM_CONFIG_ERROR);
    options.device_name = "Left Touch";
    PhantomDevice dev(options);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("could not initialise \"Left Touch\""), std::string::npos) << msg;
    EXPECT_NE(msg.find("HD_COMM_CONFIG_ERROR (0x0303)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("[OpenHaptics: Fake error]"), std::string::npos) << msg;
    const FakeHdState s = state();
    EXPECT_STREQ(s.last_init_name, "Left Touch");
    EXPECT_EQ(s.scheduler_running, 0);
    EXPECT_EQ(s.callbacks_scheduled, 0);
}

TEST_F(PhantomFake, EveryHdErrorCodeHasATableEntry) {
    for (unsigned code : {HD_SUCCESS, HD_INVALID_ENUM, HD_INVALID_VALUE, HD_INVALID_OPERATION, HD_INVALID_INPUT_TYPE,
                          HD_BAD_HANDLE, HD_WARM_MOTORS, HD_EXCEEDED_MAX_FORCE, HD_EXCEEDED_MAX_FORCE_IMPULSE,
                          HD_EXCEEDED_MAX_VELOCITY, HD_FORCE_ERROR, HD_DEVICE_FAULT, HD_DEVICE_ALREADY_INITIATED,
                          HD_COMM_ERROR, HD_COMM_CONFIG_ERROR, HD_TIMER_ERROR, HD_ILLEGAL_BEGIN, HD_ILLEGAL_END,
                          HD_FRAME_ERROR, HD_INVALID_PRIORITY, HD_SCHEDULER_FULL, HD_INVALID_LICENSE})
        EXPECT_EQ(describe_hd_error(code).rfind("HD_", 0), 0u) << describe_hd_error(code);
    EXPECT_EQ(describe_hd_error(0x0999), "unknown HD error 0x0999");
}

TEST_F(PhantomFake, AlreadyInitiatedDeviceIsDisabledAndInitialisedAgain) {
    // A device this process left enabled (e.g. by other code).
    auto init = reinterpret_cast<InitDeviceFn>(dlsym(lib_, "hdInitDevice"));
    ASSERT_EQ(init(nullptr), 1u);
    PhantomDevice dev(options);
    EXPECT_EQ(dev.start(), "");
    const FakeHdState s = state();
    EXPECT_EQ(s.init_calls, 3);
    EXPECT_EQ(s.disable_calls, 1);
    EXPECT_EQ(s.initialized, 1);
    dev.stop();
}

TEST_F(PhantomFake, CalibrationNeedingTheInkwellIsRefused) {
    set_calibration(HD_CALIBRATION_NEEDS_MANUAL_INPUT, HD_CALIBRATION_INKWELL, 1);
    PhantomDevice dev(options);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("put the stylus in the inkwell"), std::string::npos) << msg;
    const FakeHdState s = state();
    EXPECT_EQ(s.initialized, 0);  // disabled again
    EXPECT_EQ(s.scheduler_running, 0);
    EXPECT_EQ(s.callbacks_scheduled, 0);
}

TEST_F(PhantomFake, CalibrationNeedingAnUpdateIsUpdatedWithASafeStyleOnly) {
    set_calibration(HD_CALIBRATION_NEEDS_UPDATE, HD_CALIBRATION_INKWELL | HD_CALIBRATION_ENCODER_RESET, 1);
    {
        PhantomDevice dev(options);
        EXPECT_EQ(dev.start(), "");
        EXPECT_EQ(state().last_update_style, HD_CALIBRATION_INKWELL);
    }
    reset();
    set_calibration(HD_CALIBRATION_NEEDS_UPDATE, HD_CALIBRATION_ENCODER_RESET, 1);
    PhantomDevice dev(options);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("encoder-reset calibration"), std::string::npos) << msg;
    EXPECT_EQ(state().calibration_updates, 0);
    // An update that does not take is a refusal, not a start.
    reset();
    set_calibration(HD_CALIBRATION_NEEDS_UPDATE, HD_CALIBRATION_AUTO, 0);
    EXPECT_NE(dev.start().find("not calibrated"), std::string::npos);
    EXPECT_EQ(state().calibration_updates, 1);
}

TEST_F(PhantomFake, SchedulerErrorIsReportedAndEverythingUndone) {
    set_start_error(HD_TIMER_ERROR);
    PhantomDevice dev(options);
    const std::string msg = dev.start();
    EXPECT_NE(msg.find("could not start its scheduler"), std::string::npos) << msg;
    EXPECT_NE(msg.find("HD_TIMER_ERROR (0x0304)"), std::string::npos) << msg;
    FakeHdState s = state();
    EXPECT_EQ(s.initialized, 0);
    EXPECT_EQ(s.disable_calls, 1);
    EXPECT_EQ(s.callbacks_scheduled, 0);
    EXPECT_EQ(s.scheduler_running, 0);
    // Nothing is left held: the next start works.
    set_start_error(HD_SUCCESS);
    EXPECT_EQ(dev.start(), "");
    dev.stop();
}

TEST_F(PhantomFake, PoseVelocityAndButtonsAreConverted) {
    // 90 degrees about +Y, column-major, translation in mm.
    const double m[16] = {0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 12, -34, 56, 1};
    set_transform(m);
    const double v[3] = {100, -200, 300};
    set_velocity(v);
    set_buttons(3);
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    DeviceSample s;
    ASSERT_TRUE(dev.read(s));
    EXPECT_TRUE(s.connected);
    EXPECT_EQ(s.fault, kDeviceFaultNone);
    EXPECT_TRUE(near(s.pose.position, Vec3(0.012, -0.034, 0.056), 1e-15));
    const Quat expected = glm::angleAxis(glm::pi<double>() / 2, Vec3(0, 1, 0));
    EXPECT_NEAR(std::abs(glm::dot(s.pose.orientation, expected)), 1.0, 1e-12);
    EXPECT_NEAR(glm::length(s.pose.orientation), 1.0, 1e-12);
    EXPECT_TRUE(near(s.linear_velocity_m_per_s, Vec3(0.1, -0.2, 0.3), 1e-15));
    EXPECT_EQ(s.buttons, 3u);
    // The sample follows the stylus.
    const double m2[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -5, 0, 0, 1};
    set_transform(m2);
    EXPECT_TRUE(eventually([&] { return dev.read(s) && near(s.pose.position, Vec3(-0.005, 0, 0), 1e-15); }));
}

TEST_F(PhantomFake, WrittenForceReachesTheDeviceWithinTwoFramesAndNoTorqueOnThreeDof) {
    PhantomDevice dev(options);  // model "Touch": 3 actuated DOF
    ASSERT_EQ(dev.start(), "");
    EXPECT_FALSE(dev.sends_torque());
    const Vec3 f(0.5, -0.25, 1.0);
    const unsigned long long frame_before = state().frames;  // frames completed before the write
    dev.write(f, Vec3(0.01, 0.0, 0.0));
    ASSERT_TRUE(eventually([&] { return fake_force() == f; }));
    // Counted by the fake, so a slow poll here cannot inflate it.
    EXPECT_LE(state().force_change_frame, frame_before + 2);
    EXPECT_EQ(state().torque_writes, 0u);
    EXPECT_EQ(state().writes_outside_frame, 0u);
}

TEST_F(PhantomFake, SixDofModelGetsItsTorqueInMilliNewtonMetres) {
    set_model("PHANTOM Premium 1.5 6DOF");
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    EXPECT_TRUE(dev.sends_torque());
    EXPECT_EQ(dev.capabilities().output_dof, 6);
    dev.write(Vec3(0.0), Vec3(0.01, -0.02, 0.03));
    EXPECT_TRUE(eventually([&] {
        const FakeHdState s = state();
        return s.last_torque[0] == 10.0 && s.last_torque[1] == -20.0 && s.last_torque[2] == 30.0;
    }));
}

TEST_F(PhantomFake, CapabilitiesComeFromTheModelStringAndTheDeviceFigures) {
    set_model("Touch X");
    const double ws[6] = {-80, -60, -50, 80, 60, 70};
    set_figures(7.5, 1.6, 2.5, ws, 6, 3);
    PhantomDevice dev(options);
    EXPECT_EQ(dev.capabilities().name, touch_capabilities().name);  // the fallback before start
    ASSERT_EQ(dev.start(), "");
    const DeviceCapabilities& c = dev.capabilities();
    EXPECT_EQ(dev.model(), "Touch X");
    EXPECT_EQ(c.name, touch_x_capabilities().name);
    EXPECT_DOUBLE_EQ(c.max_force_N, 7.5);
    EXPECT_DOUBLE_EQ(c.max_continuous_force_N, 1.6);
    EXPECT_DOUBLE_EQ(c.max_stiffness_N_per_m, 2500.0);
    EXPECT_TRUE(near(c.workspace_min_m, Vec3(-0.08, -0.06, -0.05), 1e-15));
    EXPECT_TRUE(near(c.workspace_max_m, Vec3(0.08, 0.06, 0.07), 1e-15));
    EXPECT_EQ(c.input_dof, 6);
    EXPECT_EQ(c.output_dof, 3);
    EXPECT_DOUBLE_EQ(c.position_resolution_m, touch_x_capabilities().position_resolution_m);  // from the record
    dev.stop();

    // Figures not reported: the record's stay. Unknown model: the fallback under the model's name.
    reset();
    set_model("Mystery Arm 9");
    PhantomOptions o = options;
    o.fallback = phantom_omni_capabilities();
    PhantomDevice other(o);
    ASSERT_EQ(other.start(), "");
    EXPECT_EQ(other.capabilities().name, "Mystery Arm 9");
    EXPECT_DOUBLE_EQ(other.capabilities().max_stiffness_N_per_m, phantom_omni_capabilities().max_stiffness_N_per_m);
}

TEST_F(PhantomFake, ModelStringsPickTheirRecords) {
    const DeviceCapabilities fb = touch_capabilities();
    EXPECT_EQ(phantom_capabilities_for_model("PHANTOM Omni", fb).name, phantom_omni_capabilities().name);
    EXPECT_EQ(phantom_capabilities_for_model("PHANTOM Desktop", fb).name, touch_x_capabilities().name);
    EXPECT_EQ(phantom_capabilities_for_model("PHANTOM Premium 1.5 6DOF", fb).name,
              phantom_premium_15_6dof_capabilities().name);
    EXPECT_EQ(phantom_capabilities_for_model("PHANTOM Premium 1.5", fb).name, phantom_premium_15_capabilities().name);
    EXPECT_EQ(phantom_capabilities_for_model("touch", phantom_omni_capabilities()).name, touch_capabilities().name);
}

TEST_F(PhantomFake, VendorClampingIsEnabledSoAnOverLimitForceArrivesClamped) {
    set_figures(3.3, 0.88, 0, nullptr, 0, 0);
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    const FakeHdState s0 = state();
    EXPECT_EQ(s0.force_output, 1);
    EXPECT_EQ(s0.force_clamping, 1);
    EXPECT_EQ(s0.software_force_limit, 1);
    dev.write(Vec3(0.0, 0.0, 10.0), Vec3(0.0));
    EXPECT_TRUE(eventually([&] { return std::abs(fake_force().z - 3.3) < 1e-12; }));
    DeviceSample s;
    ASSERT_TRUE(dev.read(s));
    EXPECT_EQ(s.fault, kDeviceFaultNone);  // without clamping the fake raises HD_EXCEEDED_MAX_FORCE
}

TEST_F(PhantomFake, ForceErrorLatchesAFaultAndZeroForceWhileThePoseGoesOn) {
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    const Vec3 f(0.0, 1.0, 0.0);
    dev.write(f, Vec3(0.0));
    ASSERT_TRUE(eventually([&] { return fake_force() == f; }));
    inject_error(HD_EXCEEDED_MAX_FORCE);
    DeviceSample s;
    ASSERT_TRUE(eventually([&] { return dev.read(s) && s.fault != kDeviceFaultNone; }));
    EXPECT_EQ(s.fault, phantom_fault_from_hd(HD_EXCEEDED_MAX_FORCE));
    EXPECT_TRUE(s.connected);
    EXPECT_NE(describe_phantom_fault(s.fault).find("HD_EXCEEDED_MAX_FORCE"), std::string::npos);
    // Fresh commands do not get through while the fault is latched.
    for (int i = 0; i < 5; ++i) {
        dev.write(f, Vec3(0.0));
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    EXPECT_EQ(fake_force(), Vec3(0.0));
    const double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 7, 0, 1};
    set_transform(m);
    EXPECT_TRUE(eventually([&] { return dev.read(s) && near(s.pose.position, Vec3(0, 0.007, 0), 1e-15); }));
    EXPECT_EQ(s.fault, phantom_fault_from_hd(HD_EXCEEDED_MAX_FORCE));
    // Cleared on request: force flows again.
    dev.clear_fault();
    dev.write(f, Vec3(0.0));
    EXPECT_TRUE(eventually([&] { return dev.read(s) && s.fault == kDeviceFaultNone && fake_force() == f; }));
}

TEST_F(PhantomFake, NonFiniteCommandSendsZeroAndLatchesBadCommand) {
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    dev.write(Vec3(0.0, 0.5, 0.0), Vec3(0.0));
    ASSERT_TRUE(eventually([&] { return fake_force().y == 0.5; }));
    dev.write(Vec3(std::nan(""), 0.0, 0.0), Vec3(0.0));
    DeviceSample s;
    EXPECT_TRUE(eventually([&] { return dev.read(s) && s.fault == kDeviceFaultBadCommand; }));
    EXPECT_TRUE(eventually([&] { return fake_force() == Vec3(0.0); }));
    EXPECT_EQ(state().non_finite_force, 0);
}

TEST_F(PhantomFake, CommErrorDisconnectsAndEndsTheCallback) {
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    inject_error(HD_COMM_ERROR);
    DeviceSample s;
    ASSERT_TRUE(eventually([&] { return dev.read(s) && !s.connected; }));
    EXPECT_EQ(s.fault, phantom_fault_from_hd(HD_COMM_ERROR));
    EXPECT_TRUE(eventually([&] { return state().callbacks_scheduled == 0; }));
    dev.stop();
    EXPECT_EQ(state().initialized, 0);
}

TEST_F(PhantomFake, WatchdogZeroesAStaleForce) {
    options.watchdog_s = 0.02;
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    const Vec3 f(0.3, 0.0, 0.0);
    const auto t0 = std::chrono::steady_clock::now();
    dev.write(f, Vec3(0.0));
    ASSERT_TRUE(eventually([&] { return fake_force() == f; }));
    ASSERT_TRUE(eventually([&] { return fake_force() == Vec3(0.0); }));
    const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_GE(waited_s, 0.02);  // not before the watchdog's time
    EXPECT_EQ(dev.watchdog_trips(), 1u);
    dev.write(f, Vec3(0.0));
    EXPECT_TRUE(eventually([&] { return fake_force() == f; }));
}

TEST_F(PhantomFake, StopZeroesForceStopsTheSchedulerAndDisablesTheDevice) {
    PhantomDevice dev(options);
    ASSERT_EQ(dev.start(), "");
    dev.write(Vec3(0.0, 0.0, 0.4), Vec3(0.0));
    ASSERT_TRUE(eventually([&] { return fake_force().z == 0.4; }));
    dev.stop();
    FakeHdState s = state();
    EXPECT_EQ(s.scheduler_running, 0);
    EXPECT_EQ(s.callbacks_scheduled, 0);
    EXPECT_EQ(s.initialized, 0);
    EXPECT_EQ(s.disable_calls, 1);
    EXPECT_EQ(fake_force(), Vec3(0.0));
    DeviceSample sample;
    EXPECT_FALSE(dev.read(sample));
    dev.stop();  // idempotent
    EXPECT_EQ(state().disable_calls, 1);
    EXPECT_EQ(dev.start(), "");  // and startable again
}

TEST_F(PhantomFake, OneDevicePerProcess) {
    PhantomDevice a(options), b(options);
    ASSERT_EQ(a.start(), "");
    EXPECT_NE(b.start().find("another PhantomDevice"), std::string::npos);
    a.stop();
    EXPECT_EQ(b.start(), "");
}

TEST_F(PhantomFake, ServoLoopRunsOnThePhantomAndSendsFiniteForces) {
    // A 5 mm cube over a slab 0.5 mm below it; the stylus is lowered 2 mm from 0.1 s to 0.3 s
    // (test thread's clock). The loop runs until stop(), which comes 200 servo ticks after the
    // stylus is all the way down: a lagging test thread delays the stop instead of cutting the
    // contact short.
    const TriMesh tool = make_box(Vec3(2.5 * mm));
    const TriMesh slab = make_box(Vec3(20 * mm, 2 * mm, 20 * mm), Vec3(0.0, -5.0 * mm, 0.0));
    const std::unique_ptr<Model> model = test::model_of(tool, {test::object("slab", slab)});
    ASSERT_TRUE(model);

    ServoConfig config;
    config.duration_s = 0.0;
    config.try_realtime = false;
    config.safety.limits.max_force_N = 1.0;
    config.safety.ramp_in_time_s = 0.05;
    // Runs of late ticks on a loaded machine would be stalls that hold the force at zero (the
    // stall has tests of its own); this test is about the loop on the Phantom.
    config.safety.stall_deadline_misses = 1 << 20;
    PhantomDevice dev(options);
    ServoLoop loop;
    ASSERT_EQ(loop.start(config, dev, *model), "");

    uint64_t snapshots = 0, last_tick = 0, down_tick = 0;
    bool bad = false;
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double u = std::clamp((t - 0.1) / 0.2, 0.0, 1.0);
        const double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -2.0 * u, 0, 1};
        set_transform(m);
        ServoSnapshot s;
        if (loop.latest(s)) {
            if (s.tick != last_tick) ++snapshots;
            last_tick = s.tick;
            bad |= !std::isfinite(s.force_N.x) || !std::isfinite(s.force_N.y) || !std::isfinite(s.force_N.z);
            if (u == 1.0 && down_tick == 0) down_tick = s.tick;
        }
        if ((down_tick != 0 && last_tick >= down_tick + 200) || t > 20.0) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_TRUE(loop.running());
    loop.stop();
    EXPECT_NE(down_tick, 0u) << "the stylus was never all the way down within 20 s";
    const ServoStats st = loop.stats();
    EXPECT_GT(st.ticks, 300u);
    EXPECT_EQ(st.read_failures, 0u);
    EXPECT_FALSE(st.non_finite_sent);
    EXPECT_FALSE(bad);
    EXPECT_GT(snapshots, 50u);
    ServoSnapshot last;
    ASSERT_TRUE(loop.latest(last));
    EXPECT_TRUE(last.device_ok);
    EXPECT_NEAR(last.haptic.position.y, -0.002, 1e-12);
    const FakeHdState s = state();
    EXPECT_GT(s.max_force_norm, 0.3);  // the contact force did reach the device
    EXPECT_LE(s.max_force_norm, 1.0 + 1e-9);
    EXPECT_EQ(s.non_finite_force, 0);
    EXPECT_EQ(s.scheduler_running, 0);  // the loop stopped the device
    EXPECT_EQ(s.initialized, 0);
    std::printf("servo on fake Phantom: %llu ticks, %llu fake frames, max force at device %.3f N\n",
                static_cast<unsigned long long>(st.ticks), s.frames, s.max_force_norm);
}

}  // namespace
}  // namespace sulcus
