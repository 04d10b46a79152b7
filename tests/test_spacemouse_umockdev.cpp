// The SpaceMouse backend through real hidapi (hidraw) against a mocked device: umockdev provides
// a sysfs tree for a SpaceMouse Compact (256F:C635) with /dev/hidraw0, the HIDIOCGRDESCSIZE
// answer hidapi's open checks for, and a script of input reports. The test re-runs itself under
// `umockdev-run` (umockdev works by LD_PRELOAD, so it must wrap the process from its start) and
// skips when umockdev is not installed. See docs/spacemouse.md, "Testing without hardware".
#include "sulcus/haptics/spacemouse_device.h"
#include "sulcus/haptics/usb_discovery.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace sulcus {
namespace {

constexpr const char* kInnerEnv = "SULCUS_UMOCKDEV_INNER";

// The device tree, in umockdev-record's format: hidraw node -> HID device -> USB interface ->
// USB device (bus 1, address 4). The report descriptor is only the top-level collection
// (Generic Desktop / Multi-axis Controller), which is all hidapi reads of it.
const char* const kDeviceTree = R"(P: /devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0/0003:256F:C635.0001/hidraw/hidraw0
N: hidraw0
E: DEVNAME=/dev/hidraw0
E: MAJOR=240
E: MINOR=0
E: SUBSYSTEM=hidraw
A: dev=240:0\n
L: device=../../../0003:256F:C635.0001

P: /devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0/0003:256F:C635.0001
E: DRIVER=hid-generic
E: HID_ID=0003:0000256F:0000C635
E: HID_NAME=3Dconnexion SpaceMouse Compact
E: HID_PHYS=usb-0000:00:14.0-2/input0
E: HID_UNIQ=
E: MODALIAS=hid:b0003g0001v0000256Fp0000C635
E: SUBSYSTEM=hid
H: report_descriptor=05010908A101C0

P: /devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0
E: DEVTYPE=usb_interface
E: DRIVER=usbhid
E: PRODUCT=256f/c635/437
E: INTERFACE=3/0/0
E: SUBSYSTEM=usb
A: bInterfaceClass=03\n
A: bInterfaceNumber=00\n
A: bInterfaceProtocol=00\n
A: bInterfaceSubClass=00\n

P: /devices/pci0000:00/0000:00:14.0/usb1/1-2
E: DEVNAME=/dev/bus/usb/001/004
E: DEVTYPE=usb_device
E: DRIVER=usb
E: PRODUCT=256f/c635/437
E: BUSNUM=001
E: DEVNUM=004
E: MAJOR=189
E: MINOR=3
E: SUBSYSTEM=usb
A: busnum=1\n
A: devnum=4\n
A: idVendor=256f\n
A: idProduct=c635\n
A: bcdDevice=0437\n
A: manufacturer=3Dconnexion\n
A: product=SpaceMouse Compact\n
A: dev=189:3\n
)";

// hidapi's hid_open_path() asks HIDIOCGRDESCSIZE to make sure the node is hidraw; without this
// answer the open fails. The size is the descriptor's 7 bytes, int LE.
const char* const kIoctls = "@DEV /dev/hidraw0\nHIDIOCGRDESCSIZE 0 07000000\n";

// Combined report 1: x = 100, y = -350, z = 350, rx = 0, ry = -100, rz = 175; then buttons 1, 3, 32.
const std::vector<uint8_t> kCombined = {0x01, 0x64, 0x00, 0xA2, 0xFE, 0x5E, 0x01,
                                        0x00, 0x00, 0x9C, 0xFF, 0xAF, 0x00};
const std::vector<uint8_t> kButtons = {0x03, 0x05, 0x00, 0x00, 0x80};

// umockdev's script data escaping: bytes below 32 as '^' + (b + 64), '^' itself as "^`", the
// rest verbatim (/usr/share/doc/umockdev/script-format.txt).
std::string script_data(const std::vector<uint8_t>& bytes) {
    std::string s;
    for (uint8_t b : bytes) {
        if (b < 32) {
            s += '^';
            s += static_cast<char>(b + 64);
        } else if (b == '^') {
            s += "^`";
        } else {
            s += static_cast<char>(b);
        }
    }
    return s;
}

bool on_path(const std::string& program, std::string& found) {
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    size_t start = 0;
    while (start <= dirs.size()) {
        const size_t end = dirs.find(':', start);
        const std::string dir = dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
        const std::string candidate = (dir.empty() ? "." : dir) + "/" + program;
        if (::access(candidate.c_str(), X_OK) == 0) {
            found = candidate;
            return true;
        }
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return false;
}

bool write_file(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    return static_cast<bool>(out);
}

bool wait_for(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!done()) {
        if (std::chrono::steady_clock::now() > deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

// Inside the testbed: real hidapi enumeration, open and reads.
void run_inside_testbed() {
    std::string error;
    const std::vector<SpaceMouseHidEntry> found = enumerate_spacemouse_hid(&error);
    ASSERT_EQ(error, "");
    ASSERT_EQ(found.size(), 1u);
    EXPECT_EQ(found[0].identity.path, "/dev/hidraw0");
    EXPECT_EQ(found[0].identity.vendor, 0x256F);
    EXPECT_EQ(found[0].identity.product, 0xC635);
    EXPECT_EQ(found[0].identity.product_name, "SpaceMouse Compact");
    EXPECT_EQ(found[0].interface_number, 0);

    // Discovery lists it with its hidraw node (libusb may or may not see the mocked bus).
    const Discovery d = discover_devices();
    const DiscoveredDevice* sm = nullptr;
    for (const DiscoveredDevice& dev : d.devices)
        if (dev.cls.kind == UsbDeviceKind::spacemouse) sm = &dev;
    ASSERT_NE(sm, nullptr);
    EXPECT_EQ(sm->hidraw_path, "/dev/hidraw0");
    EXPECT_EQ(usb_id_string(sm->usb.vendor, sm->usb.product), "256f:c635");
    EXPECT_EQ(sm->usb.bus, 1);  // from the mocked sysfs (busnum/devnum above the hidraw node)
    EXPECT_EQ(sm->usb.address, 4);
    EXPECT_TRUE(sm->usability.usable) << sm->usability.needs;

    SpaceMouseDeviceConfig c;
    c.workspace_min_m = Vec3(-1.0);
    c.workspace_max_m = Vec3(1.0);
    SpaceMouseDevice dev(c);  // the hidapi source, first SpaceMouse found
    ASSERT_EQ(dev.start(), "");
    EXPECT_EQ(dev.capabilities().name, "SpaceMouse Compact");
    EXPECT_EQ(dev.identity().path, "/dev/hidraw0");
    EXPECT_EQ(dev.layout(), SpaceMouseLayout::combined);
    ASSERT_TRUE(wait_for([&] { return dev.reports_parsed() == 2; }))
        << "parsed " << dev.reports_parsed() << ", rejected " << dev.reports_rejected();

    SpaceMouseState s;
    s.translation = Vec3(100.0 / 350.0, -1.0, 1.0);
    s.rotation = Vec3(0.0, -100.0 / 350.0, 0.5);
    Pose expected = c.start_pose;
    DeviceSample sample;
    for (int i = 0; i < 10; ++i) {
        ASSERT_TRUE(dev.read(sample));
        expected = integrate_spacemouse(expected, s, 1e-3, c.mapping);
    }
    EXPECT_EQ(sample.pose.position, expected.position);
    EXPECT_EQ(sample.buttons, 0x80000005u);
    EXPECT_TRUE(sample.connected);
    dev.stop();
}

TEST(SpaceMouseUmockdev, HidapiEnumeratesOpensAndReadsAMockedSpaceMouse) {
    if (std::getenv(kInnerEnv) != nullptr) {
        run_inside_testbed();
        return;
    }
    std::string umockdev_run;
    if (!on_path("umockdev-run", umockdev_run))
        GTEST_SKIP() << "umockdev is not installed (apt-get install umockdev): the hidapi path "
                        "against a mocked /dev/hidraw0 is not tested";

    char dir_template[] = "/tmp/sulcus_umockdev_XXXXXX";
    ASSERT_NE(::mkdtemp(dir_template), nullptr);
    const std::string dir = dir_template;
    const std::string tree = dir + "/spacemouse.umockdev", ioctl = dir + "/spacemouse.ioctl",
                      script = dir + "/spacemouse.script";
    ASSERT_TRUE(write_file(tree, kDeviceTree));
    ASSERT_TRUE(write_file(ioctl, kIoctls));
    // 100 ms apart, so each report arrives as a read of its own.
    ASSERT_TRUE(write_file(script, "r 100 " + script_data(kCombined) + "\nr 100 " + script_data(kButtons) + "\n"));

    const std::string self = "/proc/self/exe";
    char exe[4096];
    const ssize_t n = ::readlink(self.c_str(), exe, sizeof exe - 1);
    ASSERT_GT(n, 0);
    exe[n] = 0;
    const std::string filter = "--gtest_filter=SpaceMouseUmockdev.HidapiEnumeratesOpensAndReadsAMockedSpaceMouse";
    const std::string dev_arg = "/dev/hidraw0=";
    std::vector<std::string> argv_s = {umockdev_run, "-d", tree, "-i", dev_arg + ioctl, "-s", dev_arg + script,
                                       "--", exe, filter};
    std::vector<char*> argv;
    for (std::string& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);

    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::setenv(kInnerEnv, "1", 1);
        ::execv(argv[0], argv.data());
        std::_Exit(127);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    for (const std::string& f : {tree, ioctl, script}) std::remove(f.c_str());
    ::rmdir(dir.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "the run under umockdev-run failed (its output is above)";
}

}  // namespace
}  // namespace sulcus
