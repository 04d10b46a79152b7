// sulcus-cli devices: the attached haptic and 6-DOF input devices Sulcus recognises, and whether
// it can use them here (docs/devices.md, "Discovery").
#include "cli/commands.h"
#include "sulcus/haptics/usb_discovery.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>

namespace sulcus::cli {

const char* const kHelpDevices =
    "usage: sulcus-cli devices [--json]\n"
    "\n"
    "Lists the attached devices Sulcus recognises (3D Systems Touch, Novint Falcon, 3Dconnexion\n"
    "SpaceMouse), found through libusb and hidapi, one line each: name, VID:PID, USB bus and\n"
    "address, whether Sulcus can use it on this host, and what it needs (OpenHaptics libHD.so,\n"
    "hidraw access through a udev rule, ...). Prints 'no haptic or 6-DOF device attached' when\n"
    "there is none. A part of the search that cannot run (no USB in a container) is reported on\n"
    "stderr. Exit status 0 either way.\n"
    "\n"
    "  --json   print one JSON object: {\"devices\": [...], \"messages\": [...]}\n";

namespace {

std::string display_name(const DiscoveredDevice& d) {
    std::string name = d.cls.name;
    if (!d.usb.product_name.empty() && d.usb.product_name != name) name += " (" + d.usb.product_name + ")";
    return name;
}

std::string location(const DiscoveredDevice& d) {
    if (d.usb.bus < 0) return "bus ? address ?";
    char buf[48];
    std::snprintf(buf, sizeof buf, "bus %03d address %03d", d.usb.bus, d.usb.address);
    return buf;
}

}  // namespace

int cmd_devices(const std::vector<std::string>& args) {
    bool json = false;
    for (const std::string& a : args) {
        if (a == "--json") json = true;
        else return usage("devices: unknown argument '" + a + "'");
    }
    const Discovery found = discover_devices();

    if (json) {
        nlohmann::json out;
        out["devices"] = nlohmann::json::array();
        for (const DiscoveredDevice& d : found.devices) {
            nlohmann::json j;
            j["name"] = display_name(d);
            j["id"] = usb_id_string(d.usb.vendor, d.usb.product);
            j["bus"] = d.usb.bus >= 0 ? nlohmann::json(d.usb.bus) : nlohmann::json(nullptr);
            j["address"] = d.usb.address >= 0 ? nlohmann::json(d.usb.address) : nlohmann::json(nullptr);
            if (!d.hidraw_path.empty()) j["hidraw"] = d.hidraw_path;
            j["usable"] = d.usability.usable;
            j["needs"] = d.usability.needs;
            out["devices"].push_back(j);
        }
        out["messages"] = found.messages;
        std::printf("%s\n", out.dump(2).c_str());
        return kOk;
    }

    for (const std::string& m : found.messages) std::fprintf(stderr, "note: %s\n", m.c_str());
    if (found.devices.empty()) {
        std::printf("no haptic or 6-DOF device attached\n");
        return kOk;
    }
    for (const DiscoveredDevice& d : found.devices)
        std::printf("%s  %s  %s  usable: %s  needs: %s\n", display_name(d).c_str(),
                    usb_id_string(d.usb.vendor, d.usb.product).c_str(), location(d).c_str(),
                    d.usability.usable ? "yes" : "no", d.usability.needs.c_str());
    return kOk;
}

}  // namespace sulcus::cli
