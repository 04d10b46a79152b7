// Which haptic or 6-DOF input devices are attached, and whether Sulcus can use them: a pure
// classifier over a table of USB IDs, a pure judgement of what each device still needs on this
// host, and the enumeration itself (libusb-1.0, plus hidapi for the SpaceMouse's hidraw node).
// See docs/devices.md, "Discovery".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sulcus {

enum class UsbDeviceKind : uint8_t {
    unknown,
    touch,       // 3D Systems Touch (USB): force feedback through OpenHaptics
    falcon,      // Novint Falcon: force feedback, FTDI chip
    spacemouse,  // 3Dconnexion SpaceMouse: 6-DOF input, no force
};

// What the table says about a vendor/product pair. Strings are static.
struct UsbDeviceClass {
    UsbDeviceKind kind = UsbDeviceKind::unknown;
    const char* name = "";  // e.g. "3D Systems Touch"
    const char* role = "";  // e.g. "haptic device, 6 DOF in / 3 out"
    bool recognised() const noexcept { return kind != UsbDeviceKind::unknown; }
};

// Pure: the table entry for vid:pid (kind unknown when none). SpaceMice come from is_spacemouse.
UsbDeviceClass classify_usb_device(uint16_t vendor, uint16_t product) noexcept;

// "vvvv:pppp", lower-case hex, as lsusb prints it.
std::string usb_id_string(uint16_t vendor, uint16_t product);

// What this host offers a recognised device; filled by probing (discover_devices) or by hand.
struct UsbHostFacts {
    bool libhd_loadable = false;  // OpenHaptics libHD.so can be dlopen'ed
    std::string libhd_error;      // the loader's reason when it cannot
    std::string hidraw_path;      // the SpaceMouse's hidraw node when hidapi listed it, else ""
    bool hidraw_accessible = false;  // that node opens read-write for this user
    bool hidapi_in_build = false;    // this build has the hidapi backend
};

struct UsbUsability {
    bool usable = false;
    std::string needs;  // one line: what it needs, or what is missing
};

// Pure: whether Sulcus can use a device of class `c` on a host with `facts`.
UsbUsability assess_usb_device(const UsbDeviceClass& c, const UsbHostFacts& facts);

// Tries to dlopen each name in turn (RTLD_LAZY | RTLD_LOCAL) and closes it again. True when one
// loads; else false with *error holding the last loader message.
bool library_loadable(const std::vector<std::string>& names, std::string* error = nullptr);
// libHD.so, then libHD.so.3.4, then libHD.so.3 (the OpenHaptics 3.4 installer's names); only
// $SULCUS_LIBHD when that is set, as the Phantom backend does.
bool libhd_loadable(std::string* error = nullptr);

// One USB device as libusb lists it. Strings only when the device could be opened.
struct UsbDeviceRecord {
    uint16_t vendor = 0;
    uint16_t product = 0;
    int bus = -1;  // -1 when unknown (a device found by hidapi only)
    int address = -1;
    std::string manufacturer;
    std::string product_name;
};

// Every USB device libusb sees. On failure (no USB in a container, no libusb in this build)
// returns false with *error set to one line; never throws for a missing bus.
bool enumerate_usb(std::vector<UsbDeviceRecord>& out, std::string* error);

struct DiscoveredDevice {
    UsbDeviceRecord usb;
    UsbDeviceClass cls;
    std::string hidraw_path;  // SpaceMouse only, when hidapi listed it
    UsbUsability usability;
};

struct Discovery {
    std::vector<DiscoveredDevice> devices;  // recognised devices only, in bus order
    std::vector<std::string> messages;      // why a part of the search could not run
};

// Enumerates USB (libusb) and hidraw SpaceMice (hidapi), keeps the recognised devices and
// judges each against this host (libHD loadable, hidraw access).
Discovery discover_devices();

}  // namespace sulcus
