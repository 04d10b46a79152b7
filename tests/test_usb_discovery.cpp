// Device discovery: the USB ID table, what each recognised device needs on a host, the library
// load check, and enumeration that answers (a list or a message) on any machine.
#include "sulcus/haptics/usb_discovery.h"

#include "sulcus/haptics/spacemouse.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace sulcus {
namespace {

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(UsbClassify, KnownIdsFromTheTable) {
    const UsbDeviceClass touch = classify_usb_device(0x0301, 0x2988);
    EXPECT_EQ(touch.kind, UsbDeviceKind::touch);
    EXPECT_TRUE(touch.recognised());
    EXPECT_STREQ(touch.name, "3D Systems Touch");

    const UsbDeviceClass touch_reported = classify_usb_device(0x2988, 0x0302);
    EXPECT_EQ(touch_reported.kind, UsbDeviceKind::touch);

    const UsbDeviceClass falcon = classify_usb_device(0x0403, 0xCB48);
    EXPECT_EQ(falcon.kind, UsbDeviceKind::falcon);
    EXPECT_STREQ(falcon.name, "Novint Falcon");

    for (uint16_t vendor : {kSpaceMouseVendorLogitech, kSpaceMouseVendor3Dconnexion})
        for (uint16_t product : {0xC603, 0xC626, 0xC62B, 0xC62E, 0xC635, 0xC652})
            EXPECT_EQ(classify_usb_device(vendor, product).kind, UsbDeviceKind::spacemouse)
                << std::hex << vendor << ":" << product;
}

TEST(UsbClassify, UnknownIdsAreNotRecognised) {
    for (auto [v, p] : {std::pair<uint16_t, uint16_t>{0x0403, 0x6001},  // a plain FTDI serial adapter
                        {0x046D, 0xC077},                               // a Logitech mouse
                        {0x0301, 0x2989},                               // next to the Touch
                        {0x2988, 0x2988},
                        {0x0000, 0x0000}}) {
        const UsbDeviceClass c = classify_usb_device(v, p);
        EXPECT_FALSE(c.recognised()) << std::hex << v << ":" << p;
        EXPECT_EQ(c.kind, UsbDeviceKind::unknown);
        EXPECT_FALSE(assess_usb_device(c, UsbHostFacts{}).usable);
    }
}

TEST(UsbClassify, IdStringIsLowerCaseHex) {
    EXPECT_EQ(usb_id_string(0x256F, 0xC635), "256f:c635");
    EXPECT_EQ(usb_id_string(0x0301, 0x2988), "0301:2988");
}

TEST(UsbAssess, TouchNeedsLoadableLibHD) {
    const UsbDeviceClass touch = classify_usb_device(0x0301, 0x2988);
    UsbHostFacts host;
    host.libhd_loadable = false;
    host.libhd_error = "libHD.so.3: cannot open shared object file: No such file or directory";
    const UsbUsability missing = assess_usb_device(touch, host);
    EXPECT_FALSE(missing.usable);
    EXPECT_TRUE(contains(missing.needs, "OpenHaptics libHD.so")) << missing.needs;
    EXPECT_TRUE(contains(missing.needs, "Touch driver")) << missing.needs;
    EXPECT_TRUE(contains(missing.needs, "not loadable")) << missing.needs;
    EXPECT_TRUE(contains(missing.needs, host.libhd_error)) << missing.needs;

    host.libhd_loadable = true;
    host.libhd_error.clear();
    const UsbUsability present = assess_usb_device(touch, host);
    EXPECT_TRUE(present.usable);
    EXPECT_TRUE(contains(present.needs, "found")) << present.needs;
    EXPECT_FALSE(contains(present.needs, "not loadable")) << present.needs;
}

TEST(UsbAssess, FalconIsNotSupported) {
    UsbHostFacts host;
    host.libhd_loadable = true;  // irrelevant to the Falcon
    host.hidapi_in_build = true;
    const UsbUsability u = assess_usb_device(classify_usb_device(0x0403, 0xCB48), host);
    EXPECT_FALSE(u.usable);
    EXPECT_EQ(u.needs, "not supported: needs libnifalcon, no backend in this build");
}

TEST(UsbAssess, SpaceMouseNeedsHidrawAccess) {
    const UsbDeviceClass sm = classify_usb_device(0x256F, 0xC635);
    UsbHostFacts host;
    host.hidapi_in_build = true;

    host.hidraw_path = "/dev/hidraw3";
    host.hidraw_accessible = true;
    UsbUsability u = assess_usb_device(sm, host);
    EXPECT_TRUE(u.usable);
    EXPECT_TRUE(contains(u.needs, "/dev/hidraw3")) << u.needs;

    host.hidraw_accessible = false;
    u = assess_usb_device(sm, host);
    EXPECT_FALSE(u.usable);
    EXPECT_TRUE(contains(u.needs, "permission denied on /dev/hidraw3")) << u.needs;
    EXPECT_TRUE(contains(u.needs, "udev rule")) << u.needs;
    EXPECT_TRUE(contains(u.needs, "256f")) << u.needs;
    EXPECT_TRUE(contains(u.needs, "uaccess")) << u.needs;

    host.hidraw_path.clear();
    u = assess_usb_device(sm, host);
    EXPECT_FALSE(u.usable);
    EXPECT_TRUE(contains(u.needs, "no hidraw node")) << u.needs;

    host.hidapi_in_build = false;
    host.hidraw_path = "/dev/hidraw3";
    host.hidraw_accessible = true;
    u = assess_usb_device(sm, host);
    EXPECT_FALSE(u.usable);
    EXPECT_TRUE(contains(u.needs, "not available in this build")) << u.needs;
}

TEST(LibraryLoad, LoadsAPresentLibraryAndExplainsAMissingOne) {
    std::string error;
    EXPECT_TRUE(library_loadable({"libc.so.6"}, &error));
    EXPECT_FALSE(library_loadable({"libsulcus-no-such-library.so", "libsulcus-nor-this.so.1"}, &error));
    EXPECT_TRUE(contains(error, "libsulcus-nor-this.so.1")) << error;  // the last name's reason
    // The first loadable name wins.
    EXPECT_TRUE(library_loadable({"libsulcus-no-such-library.so", "libc.so.6"}, &error));
    // libHD: either it loads, or there is a reason.
    std::string hd_error;
    if (!libhd_loadable(&hd_error)) {
        EXPECT_FALSE(hd_error.empty());
    }
}

TEST(LibraryLoad, LibHDCheckHonoursTheSameOverrideAsThePhantomBackend) {
    const char* saved = std::getenv("SULCUS_LIBHD");
    const std::string saved_value = saved ? saved : "";
    std::string error;
    ::setenv("SULCUS_LIBHD", "/nonexistent/sulcus/libHD.so", 1);
    EXPECT_FALSE(libhd_loadable(&error));
    EXPECT_TRUE(contains(error, "/nonexistent/sulcus/libHD.so")) << error;
    ::setenv("SULCUS_LIBHD", "libc.so.6", 1);  // any loadable library stands in
    EXPECT_TRUE(libhd_loadable(&error));
    if (saved) ::setenv("SULCUS_LIBHD", saved_value.c_str(), 1);
    else ::unsetenv("SULCUS_LIBHD");
}

TEST(UsbEnumerate, AnswersWithAListOrAMessage) {
    std::vector<UsbDeviceRecord> records;
    std::string error;
    const bool ok = enumerate_usb(records, &error);
    if (ok) {
        for (const UsbDeviceRecord& r : records) {
            EXPECT_GE(r.bus, 0);
            EXPECT_GE(r.address, 0);
        }
    } else {
        EXPECT_TRUE(records.empty());
        EXPECT_FALSE(error.empty());
        EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    }
}

TEST(UsbEnumerate, DiscoveryKeepsOnlyRecognisedDevicesAndJudgesEach) {
    const Discovery d = discover_devices();
    for (const DiscoveredDevice& dev : d.devices) {
        EXPECT_TRUE(dev.cls.recognised());
        EXPECT_EQ(dev.cls.kind, classify_usb_device(dev.usb.vendor, dev.usb.product).kind);
        EXPECT_FALSE(dev.usability.needs.empty());
    }
    for (const std::string& m : d.messages) {
        EXPECT_FALSE(m.empty());
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
}

}  // namespace
}  // namespace sulcus
