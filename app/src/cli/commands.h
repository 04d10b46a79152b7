// The subcommands of sulcus-cli and what they share: exit codes and the usage message.
#pragma once

#include <string>
#include <vector>

namespace sulcus::cli {

inline constexpr int kOk = 0;
inline constexpr int kFailed = 1;  // ran, but a requested check failed
inline constexpr int kUsage = 2;   // bad input or usage
inline constexpr int kInternal = 3;

// Prints "sulcus-cli: MSG" and a hint to stderr; returns kUsage.
int usage(const std::string& msg);

// The whole of `text` as a whole number in [lo, hi]; false when it is not one.
bool parse_whole(const std::string& text, long lo, long hi, long* out);

extern const char* const kHelpContent;
int cmd_content(const std::vector<std::string>& args);

extern const char* const kHelpTissue;
int cmd_tissue(const std::vector<std::string>& args);

extern const char* const kHelpServo;
int cmd_servo(const std::vector<std::string>& args);

extern const char* const kHelpDevices;
int cmd_devices(const std::vector<std::string>& args);

extern const char* const kHelpReplay;
int cmd_replay(const std::vector<std::string>& args);

extern const char* const kHelpLesson;
int cmd_lesson(const std::vector<std::string>& args);

extern const char* const kHelpBench;
int cmd_bench(const std::vector<std::string>& args);

extern const char* const kHelpWpd;
int cmd_wpd(const std::vector<std::string>& args);

}  // namespace sulcus::cli
