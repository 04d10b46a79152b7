// Device discovery: the USB ID table, the usability judgement, libusb enumeration, the hidraw
// nodes of SpaceMice (through hidapi) and the libHD load check.
#include "sulcus/haptics/usb_discovery.h"

#include "sulcus/haptics/spacemouse.h"
#include "sulcus/haptics/spacemouse_device.h"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <fstream>
#include <string_view>

#include <dlfcn.h>
#include <unistd.h>

#ifdef SULCUS_HAVE_LIBUSB
#include <libusb.h>
#endif

namespace sulcus {

namespace {

struct TableEntry {
    uint16_t vendor;
    uint16_t product;
    UsbDeviceClass cls;
};

// IDs from /work/shared/reference/haptic-devices.md §2: the USB Touch enumerates as 0301:2988
// (jhu-saw/sawSensablePhantom README), one user reports 2988:0302 (bharatm11 issue #2); the
// Falcon is an FTDI chip with its own product ID 0403:CB48 (libnifalcon). SpaceMice are matched
// by is_spacemouse(). FireWire Phantoms are not USB; the Touch HID's IDs are not published.
constexpr TableEntry kTable[] = {
    {0x0301, 0x2988, {UsbDeviceKind::touch, "3D Systems Touch", "haptic device, 6 DOF in / 3 out"}},
    {0x2988, 0x0302, {UsbDeviceKind::touch, "3D Systems Touch (2988:0302)", "haptic device, 6 DOF in / 3 out"}},
    {0x0403, 0xCB48, {UsbDeviceKind::falcon, "Novint Falcon", "haptic device, 3 DOF in / 3 out"}},
};

constexpr UsbDeviceClass kSpaceMouseClass{UsbDeviceKind::spacemouse, "3Dconnexion SpaceMouse",
                                          "6-DOF input, no force"};

bool read_int_file(const std::string& path, int& value) {
    std::ifstream in(path);
    return static_cast<bool>(in >> value);
}

// The USB bus and address of a hidraw node, from sysfs: /sys/class/hidraw/hidrawN/device leads
// into the HID device, whose USB ancestor holds busnum and devnum.
bool hidraw_bus_address(const std::string& dev_path, int& bus, int& address) {
    const std::size_t slash = dev_path.rfind('/');
    const std::string node = slash == std::string::npos ? dev_path : dev_path.substr(slash + 1);
    if (node.rfind("hidraw", 0) != 0) return false;
    char resolved[PATH_MAX];
    const std::string link = "/sys/class/hidraw/" + node + "/device";
    if (::realpath(link.c_str(), resolved) == nullptr) return false;
    std::string dir = resolved;
    while (dir.size() > 4) {
        if (read_int_file(dir + "/busnum", bus) && read_int_file(dir + "/devnum", address)) return true;
        const std::size_t s = dir.rfind('/');
        if (s == std::string::npos || s == 0) break;
        dir.resize(s);
    }
    return false;
}

std::string hex4(uint16_t v) {
    static const char digits[] = "0123456789abcdef";
    std::string s(4, '0');
    for (int i = 3; i >= 0; --i, v >>= 4) s[static_cast<std::size_t>(i)] = digits[v & 0xF];
    return s;
}

}  // namespace

UsbDeviceClass classify_usb_device(uint16_t vendor, uint16_t product) noexcept {
    for (const TableEntry& e : kTable)
        if (e.vendor == vendor && e.product == product) return e.cls;
    if (is_spacemouse(vendor, product)) return kSpaceMouseClass;
    return UsbDeviceClass{};
}

UsbUsability assess_usb_device(const UsbDeviceClass& c, const UsbHostFacts& facts) {
    UsbUsability u;
    switch (c.kind) {
    case UsbDeviceKind::touch:
        u.usable = facts.libhd_loadable;
        u.needs = "OpenHaptics libHD.so and the Touch driver (TouchDriver); libHD.so ";
        u.needs += facts.libhd_loadable ? "found"
                                        : "not loadable" + (facts.libhd_error.empty()
                                                                ? std::string()
                                                                : " (" + facts.libhd_error + ")");
        return u;
    case UsbDeviceKind::falcon:
        u.needs = "not supported: needs libnifalcon, no backend in this build";
        return u;
    case UsbDeviceKind::spacemouse:
        if (!facts.hidapi_in_build) {
            u.needs = "not available in this build (built without hidapi)";
        } else if (facts.hidraw_path.empty()) {
            u.needs = "hidraw read access, but no hidraw node found for it (is the usbhid driver bound?)";
        } else if (!facts.hidraw_accessible) {
            u.needs = "permission denied on " + facts.hidraw_path + ": needs a udev rule for vendor 046d/256f: " +
                      spacemouse_udev_rule();
        } else {
            u.usable = true;
            u.needs = "hidraw read access to " + facts.hidraw_path + " (granted)";
        }
        return u;
    case UsbDeviceKind::unknown:
        break;
    }
    u.needs = "not a device Sulcus knows";
    return u;
}

bool library_loadable(const std::vector<std::string>& names, std::string* error) {
    std::string last;
    for (const std::string& name : names) {
        dlerror();  // clear a stale message
        if (void* h = dlopen(name.c_str(), RTLD_LAZY | RTLD_LOCAL)) {
            dlclose(h);
            return true;
        }
        const char* e = dlerror();
        last = e ? e : name + ": cannot be loaded";
    }
    if (error) *error = last;
    return false;
}

bool libhd_loadable(std::string* error) {
    // The Phantom backend loads $SULCUS_LIBHD instead when it is set; check the same library.
    if (const char* env = std::getenv("SULCUS_LIBHD"); env != nullptr && *env != 0)
        return library_loadable({env}, error);
    return library_loadable({"libHD.so", "libHD.so.3.4", "libHD.so.3"}, error);
}

#ifdef SULCUS_HAVE_LIBUSB

bool enumerate_usb(std::vector<UsbDeviceRecord>& out, std::string* error) {
    out.clear();
    libusb_context* ctx = nullptr;
    int rc = libusb_init(&ctx);
    if (rc != 0) {
        if (error)
            *error = std::string("USB enumeration failed: libusb_init: ") + libusb_strerror(rc) +
                     (::access("/dev/bus/usb", F_OK) != 0 ? " (no /dev/bus/usb: no USB access here, e.g. a container)"
                                                          : "");
        return false;
    }
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    if (n < 0) {
        if (error)
            *error = std::string("USB enumeration failed: libusb_get_device_list: ") +
                     libusb_strerror(static_cast<int>(n));
        libusb_exit(ctx);
        return false;
    }
    for (ssize_t i = 0; i < n; ++i) {
        libusb_device* dev = list[i];
        libusb_device_descriptor desc{};
        if (libusb_get_device_descriptor(dev, &desc) != 0) continue;
        UsbDeviceRecord r;
        r.vendor = desc.idVendor;
        r.product = desc.idProduct;
        r.bus = libusb_get_bus_number(dev);
        r.address = libusb_get_device_address(dev);
        // Strings need the device opened; only try for devices we recognise, and never insist.
        if (classify_usb_device(r.vendor, r.product).recognised()) {
            libusb_device_handle* h = nullptr;
            if (libusb_open(dev, &h) == 0) {
                unsigned char buf[256];
                if (desc.iManufacturer != 0 &&
                    libusb_get_string_descriptor_ascii(h, desc.iManufacturer, buf, sizeof buf) > 0)
                    r.manufacturer = reinterpret_cast<const char*>(buf);
                if (desc.iProduct != 0 &&
                    libusb_get_string_descriptor_ascii(h, desc.iProduct, buf, sizeof buf) > 0)
                    r.product_name = reinterpret_cast<const char*>(buf);
                libusb_close(h);
            }
        }
        out.push_back(std::move(r));
    }
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    std::sort(out.begin(), out.end(), [](const UsbDeviceRecord& a, const UsbDeviceRecord& b) {
        return a.bus != b.bus ? a.bus < b.bus : a.address < b.address;
    });
    return true;
}

#else

bool enumerate_usb(std::vector<UsbDeviceRecord>& out, std::string* error) {
    out.clear();
    if (error) *error = "USB enumeration not available in this build (built without libusb-1.0)";
    return false;
}

#endif

Discovery discover_devices() {
    Discovery d;
    UsbHostFacts host;
#ifdef SULCUS_HAVE_HIDAPI
    host.hidapi_in_build = true;
#endif
    bool libhd_checked = false;

    std::vector<UsbDeviceRecord> usb;
    std::string error;
    if (!enumerate_usb(usb, &error)) d.messages.push_back(error);
    for (const UsbDeviceRecord& r : usb) {
        const UsbDeviceClass c = classify_usb_device(r.vendor, r.product);
        if (!c.recognised()) continue;
        if (c.kind == UsbDeviceKind::touch && !libhd_checked) {
            host.libhd_loadable = libhd_loadable(&host.libhd_error);
            libhd_checked = true;
        }
        d.devices.push_back(DiscoveredDevice{r, c, "", {}});
    }

    // SpaceMice through hidapi: their hidraw nodes, and the devices themselves when libusb
    // could not look (hidapi reads sysfs, which a container may still show).
    std::string hid_error;
    std::vector<SpaceMouseHidEntry> hid = enumerate_spacemouse_hid(&hid_error);
    if (!hid_error.empty()) d.messages.push_back(hid_error);
    std::vector<bool> claimed(d.devices.size(), false);
    for (const SpaceMouseHidEntry& e : hid) {
        int bus = -1, address = -1;
        hidraw_bus_address(e.identity.path, bus, address);
        // The USB device this node belongs to: same bus/address, else the first same-ID one.
        DiscoveredDevice* match = nullptr;
        for (std::size_t i = 0; i < d.devices.size() && match == nullptr; ++i) {
            DiscoveredDevice& dd = d.devices[i];
            if (dd.cls.kind != UsbDeviceKind::spacemouse) continue;
            const bool same = bus >= 0 ? (dd.usb.bus == bus && dd.usb.address == address)
                                       : (!claimed[i] && dd.usb.vendor == e.identity.vendor &&
                                          dd.usb.product == e.identity.product);
            if (same) {
                match = &dd;
                claimed[i] = true;
            }
        }
        if (match == nullptr) {
            DiscoveredDevice dd;
            dd.usb.vendor = e.identity.vendor;
            dd.usb.product = e.identity.product;
            dd.usb.bus = bus;
            dd.usb.address = address;
            dd.cls = classify_usb_device(e.identity.vendor, e.identity.product);
            d.devices.push_back(dd);
            claimed.push_back(true);
            match = &d.devices.back();
        }
        if (match->usb.product_name.empty()) match->usb.product_name = e.identity.product_name;
        if (match->hidraw_path.empty()) match->hidraw_path = e.identity.path;  // first interface
    }

    for (DiscoveredDevice& dd : d.devices) {
        UsbHostFacts facts = host;
        facts.hidraw_path = dd.hidraw_path;
        facts.hidraw_accessible = !dd.hidraw_path.empty() && ::access(dd.hidraw_path.c_str(), R_OK | W_OK) == 0;
        dd.usability = assess_usb_device(dd.cls, facts);
    }
    return d;
}

std::string usb_id_string(uint16_t vendor, uint16_t product) { return hex4(vendor) + ":" + hex4(product); }

}  // namespace sulcus
