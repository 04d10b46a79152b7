// What other threads ask of the servo loop, and how it is recorded so a replay redoes it.
//
// Commands travel UI/lesson thread -> servo thread through a bounded SPSC queue (spsc_queue.h) and
// are applied at the start of a tick. The servo thread writes each applied command into the
// session recording as an event at that tick (kinds below), and a UI or lesson event posted
// through the loop is recorded the same way, so the servo thread is the recording's only event
// producer and every event sits at the tick the servo saw it. The emergency stop and the safety
// reset do not queue (they must never be refused); they are flags the next tick takes, and are
// recorded too.
#pragma once

#include "sulcus/engine/types.h"
#include "sulcus/haptics/safety.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace sulcus {

// Device frame -> world (scene) frame for the haptic pose:
//   position_world = offset_m + scale * position_device; orientation unchanged.
// The device frame's axes are the scene's (+Y up, +Z toward the user), so forces and torques
// pass between the frames unchanged. With scale s the hand feels the scene's stiffness times s.
struct WorkspaceMap {
    Vec3 offset_m{0.0};
    double scale = 1.0;  // world metres per device metre
};

// Finite offset, scale in [1e-3, 1e3].
bool valid_workspace(const WorkspaceMap& map) noexcept;
Pose map_device_pose(const WorkspaceMap& map, const Pose& device_pose) noexcept;
// The map with `scale` that puts `device_position` on `world_position`.
WorkspaceMap anchored_workspace(double scale, const Vec3& device_position, const Vec3& world_position) noexcept;

// Recorded event kinds written by the servo thread.
inline constexpr std::string_view kEventServoBegin = "servo.begin";          // map in force at the first tick
inline constexpr std::string_view kEventServoWorkspace = "servo.workspace";  // map changed at this tick
inline constexpr std::string_view kEventServoEStop = "servo.estop";          // emergency stop latched
inline constexpr std::string_view kEventServoReset = "servo.reset";          // safety reset asked
// True for the kinds above (a replay applies them; other kinds are the UI's and lesson's own).
bool is_servo_event(std::string_view kind) noexcept;

inline constexpr std::size_t kServoEventKindBytes = 32;   // longest event kind
inline constexpr std::size_t kServoEventTextBytes = 984;  // longest event JSON text

enum class ServoCommandKind : uint8_t {
    Event,         // record `kind` / `text` at the tick it is taken
    SetWorkspace,  // replace the workspace map from this tick on
};

// One queued command; fixed size, trivially copyable (the queue copies it whole).
struct ServoCommand {
    ServoCommandKind type = ServoCommandKind::Event;
    WorkspaceMap workspace;
    uint16_t kind_size = 0;
    uint16_t text_size = 0;
    char kind[kServoEventKindBytes] = {};
    char text[kServoEventTextBytes] = {};

    std::string_view kind_view() const noexcept { return {kind, kind_size}; }
    std::string_view text_view() const noexcept { return {text, text_size}; }
};

// Builders for the producer side. "" or one line saying why the command cannot be made: an empty
// or too long kind, a kind in the servo's own "servo." namespace, too long a text, a bad map.
std::string make_event_command(std::string_view kind, std::string_view json, ServoCommand& out);
std::string make_workspace_command(const WorkspaceMap& map, ServoCommand& out);

// The JSON text of a map: {"offset_m":[x,y,z],"scale":s}, every number with 17 significant digits
// so it reads back to the same bits. Writes into `buf` (no allocation); returns the length, or 0
// when `cap` is too small (128 bytes always suffice).
std::size_t format_workspace(const WorkspaceMap& map, char* buf, std::size_t cap) noexcept;
// Reads that text back; "" or why not. Keys other than offset_m and scale are ignored.
std::string parse_workspace(std::string_view json, WorkspaceMap& out);

// The servo.begin payload: the starting map and the safety layer's settings in force,
// {"offset_m":[..],"scale":s,"safety":{"max_force_N":..,...}} (numbers to 17 digits). Made once
// before the first tick (it allocates).
std::string format_servo_begin(const WorkspaceMap& map, const SafetyConfig& safety);
// Reads it back: the map, and the safety settings when present (`has_safety`).
std::string parse_servo_begin(std::string_view json, WorkspaceMap& map, SafetyConfig& safety, bool& has_safety);

}  // namespace sulcus
