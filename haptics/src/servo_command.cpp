#include "sulcus/haptics/servo_command.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace sulcus {

bool valid_workspace(const WorkspaceMap& m) noexcept {
    return std::isfinite(m.offset_m.x) && std::isfinite(m.offset_m.y) && std::isfinite(m.offset_m.z) &&
           m.scale >= 1e-3 && m.scale <= 1e3;
}

Pose map_device_pose(const WorkspaceMap& m, const Pose& p) noexcept {
    return Pose{m.offset_m + m.scale * p.position, p.orientation};
}

WorkspaceMap anchored_workspace(double scale, const Vec3& device_position, const Vec3& world_position) noexcept {
    return WorkspaceMap{world_position - scale * device_position, scale};
}

bool is_servo_event(std::string_view kind) noexcept {
    return kind == kEventServoBegin || kind == kEventServoWorkspace || kind == kEventServoEStop ||
           kind == kEventServoReset;
}

std::string make_event_command(std::string_view kind, std::string_view json, ServoCommand& out) {
    if (kind.empty()) return "servo event: empty kind";
    if (kind.size() > kServoEventKindBytes)
        return "servo event '" + std::string(kind.substr(0, 40)) + "': kind longer than " +
               std::to_string(kServoEventKindBytes) + " bytes";
    if (kind.substr(0, 6) == "servo.") return "servo event '" + std::string(kind) + "': the servo. kinds are the loop's own";
    if (json.size() > kServoEventTextBytes)
        return "servo event '" + std::string(kind) + "': text of " + std::to_string(json.size()) +
               " bytes, longer than " + std::to_string(kServoEventTextBytes);
    out.type = ServoCommandKind::Event;
    out.kind_size = static_cast<uint16_t>(kind.size());
    out.text_size = static_cast<uint16_t>(json.size());
    std::memcpy(out.kind, kind.data(), kind.size());
    if (!json.empty()) std::memcpy(out.text, json.data(), json.size());
    return "";
}

std::string make_workspace_command(const WorkspaceMap& map, ServoCommand& out) {
    if (!valid_workspace(map)) return "workspace map: offset must be finite and scale in [0.001, 1000]";
    out.type = ServoCommandKind::SetWorkspace;
    out.workspace = map;
    out.kind_size = out.text_size = 0;
    return "";
}

std::size_t format_workspace(const WorkspaceMap& m, char* buf, std::size_t cap) noexcept {
    const int n = std::snprintf(buf, cap, "{\"offset_m\":[%.17g,%.17g,%.17g],\"scale\":%.17g}", m.offset_m.x,
                                m.offset_m.y, m.offset_m.z, m.scale);
    return n > 0 && static_cast<std::size_t>(n) < cap ? static_cast<std::size_t>(n) : 0;
}

std::string parse_workspace(std::string_view text, WorkspaceMap& out) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) return "workspace map: not a JSON object";
    const auto off = j.find("offset_m");
    const auto sc = j.find("scale");
    if (off == j.end() || !off->is_array() || off->size() != 3 || sc == j.end() || !sc->is_number())
        return "workspace map: needs \"offset_m\": [x, y, z] and \"scale\"";
    for (const auto& v : *off)
        if (!v.is_number()) return "workspace map: offset_m holds a non-number";
    WorkspaceMap m{Vec3((*off)[0].get<double>(), (*off)[1].get<double>(), (*off)[2].get<double>()), sc->get<double>()};
    if (!valid_workspace(m)) return "workspace map: offset must be finite and scale in [0.001, 1000]";
    out = m;
    return "";
}

namespace {

// Every SafetyConfig field with its JSON key, so writing and reading cannot disagree.
template <class F>
void for_each_safety_field(SafetyConfig& c, F&& f) {
    f("max_force_N", c.limits.max_force_N);
    f("max_torque_Nm", c.limits.max_torque_Nm);
    f("max_force_rate_N_per_s", c.limits.max_force_rate_N_per_s);
    f("max_torque_rate_Nm_per_s", c.limits.max_torque_rate_Nm_per_s);
    f("ramp_in_time_s", c.ramp_in_time_s);
    f("engage_force_N", c.engage_force_N);
    f("engage_torque_Nm", c.engage_torque_Nm);
    f("fade_time_s", c.fade_time_s);
    f("recover_hold_off_s", c.recover_hold_off_s);
    f("huge_force_N", c.huge_force_N);
    f("huge_torque_Nm", c.huge_torque_Nm);
    f("nominal_dt_s", c.nominal_dt_s);
    f("max_dt_s", c.max_dt_s);
}

// 17 significant digits; JSON has no infinity or NaN, so those go as strings.
std::string number_text(double v) {
    if (std::isnan(v)) return "\"nan\"";
    if (std::isinf(v)) return v > 0 ? "\"inf\"" : "\"-inf\"";
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

bool number_of(const nlohmann::json& j, double& out) {
    if (j.is_number()) {
        out = j.get<double>();
        return true;
    }
    if (j.is_string()) {
        const std::string s = j.get<std::string>();
        if (s == "nan") out = std::nan("");
        else if (s == "inf") out = INFINITY;
        else if (s == "-inf") out = -INFINITY;
        else return false;
        return true;
    }
    return false;
}

}  // namespace

std::string format_servo_begin(const WorkspaceMap& map, const SafetyConfig& safety) {
    char buf[160];
    std::string out(buf, format_workspace(map, buf, sizeof buf));
    out.pop_back();  // the closing brace
    out += ",\"safety\":{";
    SafetyConfig c = safety;
    bool first = true;
    for_each_safety_field(c, [&](const char* key, double& v) {
        out += (first ? "\"" : ",\"") + std::string(key) + "\":" + number_text(v);
        first = false;
    });
    out += ",\"engage_ticks\":" + std::to_string(c.engage_ticks) +
           ",\"stall_deadline_misses\":" + std::to_string(c.stall_deadline_misses) + "}}";
    return out;
}

std::string parse_servo_begin(std::string_view text, WorkspaceMap& map, SafetyConfig& safety, bool& has_safety) {
    has_safety = false;
    if (std::string err = parse_workspace(text, map); !err.empty()) return err;
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    const auto s = j.find("safety");
    if (s == j.end()) return "";
    if (!s->is_object()) return "servo.begin: safety is not an object";
    SafetyConfig c;
    std::string err;
    for_each_safety_field(c, [&](const char* key, double& v) {
        const auto f = s->find(key);
        if (f == s->end() || !number_of(*f, v)) err = err.empty() ? std::string("servo.begin: safety.") + key + " missing or not a number" : err;
    });
    for (const auto& [key, dst] : {std::pair{"engage_ticks", &c.engage_ticks}, std::pair{"stall_deadline_misses", &c.stall_deadline_misses}}) {
        const auto f = s->find(key);
        if (f == s->end() || !f->is_number_integer()) {
            if (err.empty()) err = std::string("servo.begin: safety.") + key + " missing or not an integer";
        } else {
            *dst = f->get<int>();
        }
    }
    if (!err.empty()) return err;
    safety = c;
    has_safety = true;
    return "";
}

}  // namespace sulcus
