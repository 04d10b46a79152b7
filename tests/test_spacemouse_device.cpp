// SpaceMouseDevice: recorded report bytes of both layouts go through the real reader thread (a
// scripted byte source in place of hidapi) and come out of read() as the pose integrate_spacemouse
// gives by hand, with the buttons, the comm fault on a source error, and no allocation in
// read()/write(). Report bytes as in test_spacemouse.cpp (docs/spacemouse.md layouts).
#include "sulcus/haptics/spacemouse_device.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <thread>
#include <vector>

#include "allocation_counter.h"

namespace sulcus {
namespace {

using Bytes = std::vector<uint8_t>;

// Split layout: report 1 x = 350, y = -100, z = 0; report 2 rx = -350, ry = 175, rz = -175.
const Bytes kSplitTranslation = {0x01, 0x5E, 0x01, 0x9C, 0xFF, 0x00, 0x00};
const Bytes kSplitRotation = {0x02, 0xA2, 0xFE, 0xAF, 0x00, 0x51, 0xFF};
// Combined layout, report 1: x = 100, y = -350, z = 350, rx = 0, ry = -100, rz = 175.
const Bytes kCombined = {0x01, 0x64, 0x00, 0xA2, 0xFE, 0x5E, 0x01, 0x00, 0x00, 0x9C, 0xFF, 0xAF, 0x00};
// Buttons 1, 3 and 32.
const Bytes kButtons = {0x03, 0x05, 0x00, 0x00, 0x80};
// Battery level (report 0x17): not a motion report, rejected.
const Bytes kBattery = {0x17, 0x64};

// Plays a fixed list of reports to the reader thread, then either idles (0 = no report in time)
// or fails (-1, as hid_read_timeout does on an unplug). Nothing here allocates after open().
class ScriptedSource final : public HidReportSource {
public:
    ScriptedSource(HidDeviceIdentity id, std::vector<Bytes> reports, bool fail_at_end = false)
        : id_(std::move(id)), reports_(std::move(reports)), fail_at_end_(fail_at_end) {}

    std::string open_error;
    std::atomic<int> opens{0};
    std::atomic<int> closes{0};

    std::string open(HidDeviceIdentity& identity) override {
        if (!open_error.empty()) return open_error;
        identity = id_;
        next_.store(0);
        opens.fetch_add(1);
        return "";
    }
    int read_timeout(uint8_t* buffer, std::size_t size, int timeout_ms) noexcept override {
        const std::size_t i = next_.load();
        if (i < reports_.size()) {
            const std::size_t n = std::min(size, reports_[i].size());
            std::memcpy(buffer, reports_[i].data(), n);
            next_.store(i + 1);
            return static_cast<int>(n);
        }
        if (fail_at_end_) return -1;
        std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeout_ms, 2)));
        return 0;
    }
    void close() noexcept override { closes.fetch_add(1); }

private:
    HidDeviceIdentity id_;
    std::vector<Bytes> reports_;
    bool fail_at_end_;
    std::atomic<std::size_t> next_{0};
};

HidDeviceIdentity identity(uint16_t product, const char* name) {
    HidDeviceIdentity id;
    id.vendor = kSpaceMouseVendor3Dconnexion;
    id.product = product;
    id.product_name = name;
    id.path = "/dev/hidraw-test";
    return id;
}

// Waits (up to 5 s) for the reader thread to get somewhere.
bool wait_for(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!done()) {
        if (std::chrono::steady_clock::now() > deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

Pose start_pose() {
    Pose p;
    p.position = Vec3(0.01, -0.02, 0.03);
    p.orientation = glm::normalize(Quat(0.9, 0.1, -0.3, 0.2));
    return p;
}

SpaceMouseDeviceConfig config() {
    SpaceMouseDeviceConfig c;
    c.start_pose = start_pose();
    c.workspace_min_m = Vec3(-1.0);  // large: no clamping unless a test asks for it
    c.workspace_max_m = Vec3(1.0);
    c.rate_hz = 1000.0;
    return c;
}

// The pose `ticks` reads give for a state, computed directly from the documented integrator.
Pose expected_pose(const SpaceMouseState& s, int ticks, const SpaceMouseDeviceConfig& c) {
    Pose p = c.start_pose;
    for (int i = 0; i < ticks; ++i) p = integrate_spacemouse(p, s, 1.0 / c.rate_hz, c.mapping);
    return p;
}

void expect_pose_eq(const Pose& a, const Pose& b) {
    EXPECT_EQ(a.position.x, b.position.x);
    EXPECT_EQ(a.position.y, b.position.y);
    EXPECT_EQ(a.position.z, b.position.z);
    EXPECT_EQ(a.orientation.w, b.orientation.w);
    EXPECT_EQ(a.orientation.x, b.orientation.x);
    EXPECT_EQ(a.orientation.y, b.orientation.y);
    EXPECT_EQ(a.orientation.z, b.orientation.z);
}

TEST(SpaceMouseDevice, SplitReportsThroughReaderGiveIntegratedPoseAndButtons) {
    // SpaceNavigator (C626): split layout from the product table.
    auto src = std::make_unique<ScriptedSource>(identity(0xC626, "SpaceNavigator"),
                                                std::vector<Bytes>{kSplitTranslation, kSplitRotation, kButtons});
    const SpaceMouseDeviceConfig c = config();
    SpaceMouseDevice dev(c, std::move(src));
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(dev.layout(), SpaceMouseLayout::split);
    EXPECT_EQ(dev.capabilities().name, "SpaceNavigator");
    EXPECT_EQ(dev.capabilities().input_dof, 6);
    EXPECT_EQ(dev.capabilities().output_dof, 0);
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 3; }));

    // By hand: the three reports' axes, scaled by 350 and clamped.
    SpaceMouseState s;
    s.translation = Vec3(1.0, -100.0 / 350.0, 0.0);
    s.rotation = Vec3(-1.0, 0.5, -0.5);
    DeviceSample sample;
    const int ticks = 25;
    Pose previous = c.start_pose;
    for (int i = 0; i < ticks; ++i) {
        previous = sample.pose;
        ASSERT_TRUE(dev.read(sample));
    }
    expect_pose_eq(sample.pose, expected_pose(s, ticks, c));
    EXPECT_TRUE(sample.connected);
    EXPECT_EQ(sample.fault, kDeviceFaultNone);
    EXPECT_EQ(sample.buttons, 0x80000005u);
    // The velocity is the last tick's displacement over the nominal tick.
    const Vec3 v = (sample.pose.position - previous.position) * 1000.0;
    EXPECT_NEAR(sample.linear_velocity_m_per_s.x, v.x, 1e-9);
    EXPECT_NEAR(sample.linear_velocity_m_per_s.x, c.mapping.translation_gain_m_per_s, 1e-9);
    dev.stop();
}

TEST(SpaceMouseDevice, CombinedReportThroughReaderGivesIntegratedPose) {
    // SpaceMouse Compact (C635): combined layout.
    auto src = std::make_unique<ScriptedSource>(identity(0xC635, "SpaceMouse Compact"),
                                                std::vector<Bytes>{kCombined, kButtons});
    SpaceMouseDeviceConfig c = config();
    c.mapping.tool_frame = true;  // any mapping: the device hands it to the integrator
    SpaceMouseDevice dev(c, std::move(src));
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(dev.layout(), SpaceMouseLayout::combined);
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 2; }));

    SpaceMouseState s;
    s.translation = Vec3(100.0 / 350.0, -1.0, 1.0);
    s.rotation = Vec3(0.0, -100.0 / 350.0, 0.5);
    DeviceSample sample;
    for (int i = 0; i < 40; ++i) ASSERT_TRUE(dev.read(sample));
    expect_pose_eq(sample.pose, expected_pose(s, 40, c));
    EXPECT_EQ(sample.buttons, 0x80000005u);
    EXPECT_EQ(dev.reports_rejected(), 0u);
}

TEST(SpaceMouseDevice, SevenByteReportSwitchesAGuessedCombinedLayoutToSplit) {
    // A product outside the table is guessed combined; its 7-byte report 1 shows it is split.
    auto src = std::make_unique<ScriptedSource>(identity(0xC6AA, "Unlisted"),
                                                std::vector<Bytes>{kSplitTranslation, kSplitRotation});
    const SpaceMouseDeviceConfig c = config();
    SpaceMouseDevice dev(c, std::move(src));
    ASSERT_EQ(dev.start(), "");
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 2; }));
    EXPECT_EQ(dev.layout(), SpaceMouseLayout::split);
    SpaceMouseState s;
    s.translation = Vec3(1.0, -100.0 / 350.0, 0.0);
    s.rotation = Vec3(-1.0, 0.5, -0.5);
    DeviceSample sample;
    ASSERT_TRUE(dev.read(sample));
    expect_pose_eq(sample.pose, expected_pose(s, 1, c));
}

TEST(SpaceMouseDevice, UnknownReportsAreCountedAndIgnored) {
    auto src = std::make_unique<ScriptedSource>(identity(0xC635, "SpaceMouse Compact"),
                                                std::vector<Bytes>{kBattery, kCombined, kBattery});
    const SpaceMouseDeviceConfig c = config();
    SpaceMouseDevice dev(c, std::move(src));
    ASSERT_EQ(dev.start(), "");
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() + dev.reports_rejected() == 3; }));
    EXPECT_EQ(dev.reports_parsed(), 1u);
    EXPECT_EQ(dev.reports_rejected(), 2u);
    SpaceMouseState s;
    s.translation = Vec3(100.0 / 350.0, -1.0, 1.0);
    s.rotation = Vec3(0.0, -100.0 / 350.0, 0.5);
    DeviceSample sample;
    ASSERT_TRUE(dev.read(sample));
    expect_pose_eq(sample.pose, expected_pose(s, 1, c));
}

TEST(SpaceMouseDevice, SourceErrorGivesDisconnectedCommFaultAndHoldsPose) {
    auto owned = std::make_unique<ScriptedSource>(identity(0xC635, "SpaceMouse Compact"),
                                                  std::vector<Bytes>{kCombined}, /*fail_at_end=*/true);
    ScriptedSource* src = owned.get();
    SpaceMouseDevice dev(config(), std::move(owned));
    ASSERT_EQ(dev.start(), "");
    DeviceSample sample;
    ASSERT_TRUE(wait_for([&] { return !dev.read(sample); }));
    EXPECT_FALSE(sample.connected);
    EXPECT_EQ(sample.fault, kDeviceFaultComm);
    // Later reads hold the same pose and keep reporting the loss.
    const Pose held = sample.pose;
    DeviceSample again;
    EXPECT_FALSE(dev.read(again));
    EXPECT_EQ(again.fault, kDeviceFaultComm);
    expect_pose_eq(again.pose, held);
    dev.stop();
    EXPECT_EQ(src->closes.load(), 1);
    // A restart reopens and reads again.
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(src->opens.load(), 2);
}

TEST(SpaceMouseDevice, NotStartedAndOpenFailure) {
    auto owned = std::make_unique<ScriptedSource>(identity(0xC635, "x"), std::vector<Bytes>{});
    owned->open_error = "spacemouse: no SpaceMouse found";
    SpaceMouseDevice dev(config(), std::move(owned));
    DeviceSample sample;
    EXPECT_FALSE(dev.read(sample));
    EXPECT_FALSE(sample.connected);
    EXPECT_EQ(sample.fault, kDeviceFaultNotStarted);
    EXPECT_EQ(dev.start(), "spacemouse: no SpaceMouse found");
    EXPECT_FALSE(dev.read(sample));
    EXPECT_EQ(sample.fault, kDeviceFaultNotStarted);
}

TEST(SpaceMouseDevice, PoseIsClampedToTheWorkspace) {
    auto src = std::make_unique<ScriptedSource>(identity(0xC635, "SpaceMouse Compact"), std::vector<Bytes>{kCombined});
    SpaceMouseDeviceConfig c = config();
    SpaceMouseDevice dev(c, std::move(src));
    dev.set_workspace(Vec3(0.02, -0.03, -0.05), Vec3(-0.02, 0.03, 0.05));  // corners in any order
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(dev.capabilities().workspace_min_m, Vec3(-0.02, -0.03, -0.05));
    EXPECT_EQ(dev.capabilities().workspace_max_m, Vec3(0.02, 0.03, 0.05));
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 1; }));
    // y at -1 and z at +1 deflection: 0.05 m/s for 2 s reaches both walls and stays there.
    DeviceSample sample;
    for (int i = 0; i < 2000; ++i) ASSERT_TRUE(dev.read(sample));
    EXPECT_EQ(sample.pose.position.y, -0.03);
    EXPECT_EQ(sample.pose.position.z, 0.05);
    EXPECT_EQ(sample.linear_velocity_m_per_s.y, 0.0);
    EXPECT_GE(sample.pose.position.x, -0.02);
    EXPECT_LE(sample.pose.position.x, 0.02);
}

TEST(SpaceMouseDevice, WriteCountsNonFiniteCommands) {
    auto src = std::make_unique<ScriptedSource>(identity(0xC635, "SpaceMouse Compact"), std::vector<Bytes>{});
    SpaceMouseDevice dev(config(), std::move(src));
    ASSERT_EQ(dev.start(), "");
    dev.write(Vec3(1.0, 2.0, 3.0), Vec3(0.0));
    DeviceSample sample;
    ASSERT_TRUE(dev.read(sample));
    EXPECT_EQ(sample.fault, kDeviceFaultNone);
    EXPECT_EQ(dev.bad_commands(), 0u);
    dev.write(Vec3(std::nan(""), 0.0, 0.0), Vec3(0.0));
    dev.write(Vec3(0.0), Vec3(0.0, INFINITY, 0.0));
    EXPECT_EQ(dev.bad_commands(), 2u);
    ASSERT_TRUE(dev.read(sample));
    EXPECT_EQ(sample.fault, kDeviceFaultBadCommand);
    EXPECT_TRUE(sample.connected);
}

TEST(SpaceMouseDevice, ReadAndWriteDoNotAllocate) {
    auto src = std::make_unique<ScriptedSource>(identity(0xC626, "SpaceNavigator"),
                                                std::vector<Bytes>{kSplitTranslation, kSplitRotation, kButtons});
    SpaceMouseDevice dev(config(), std::move(src));
    ASSERT_EQ(dev.start(), "");
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 3; }));
    DeviceSample sample;
    const long before = sulcus::test::heap_allocations();
    for (int i = 0; i < 5000; ++i) {
        dev.read(sample);
        dev.write(Vec3(0.1 * i, 0.0, 0.0), Vec3(0.0));
    }
    dev.write(Vec3(std::nan(""), 0.0, 0.0), Vec3(0.0));
    dev.read(sample);
    EXPECT_EQ(sulcus::test::heap_allocations(), before);
    EXPECT_NE(sample.pose.position, start_pose().position);  // it did move
}

TEST(SpaceMouseDevice, HidapiSourceNamesAPathThatIsNotASpaceMouse) {
    SpaceMouseDeviceConfig c = config();
    c.path = "/dev/hidraw-does-not-exist";
    SpaceMouseDevice dev(c);
    const std::string error = dev.start();
    ASSERT_FALSE(error.empty());
    EXPECT_EQ(error.find('\n'), std::string::npos);
    EXPECT_EQ(error.rfind("spacemouse: ", 0), 0u) << error;
    // It names the path, or says the build has no hidapi.
    EXPECT_TRUE(error.find(c.path) != std::string::npos ||
                error.find("not available in this build") != std::string::npos)
        << error;
}

}  // namespace
}  // namespace sulcus
