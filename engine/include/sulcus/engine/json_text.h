// Text helpers shared by the readers of project files (scenes, charts, lessons): one-line
// messages, quoted values, JSON pointers, whole-file reads and JSON parsing with the line and column
// of a syntax error.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace sulcus::textio {

// Control characters written as escapes, so a message stays on one line.
std::string one_line(const std::string& s);
// A value quoted in a message: single line, at most 60 characters, in single quotes.
std::string shown(const std::string& s);
// Shortest text that reads back as the same double.
std::string num(double v);
// One reference token of a JSON pointer (RFC 6901: '~' -> "~0", '/' -> "~1").
std::string pointer_token(const std::string& key);
// Collects "file: place: what" lines (place a JSON pointer) into a reader's errors and warnings.
struct Reporter {
    std::string file;
    std::vector<std::string>* errors;
    std::vector<std::string>* warnings;
    void error(const std::string& place, const std::string& what) const {
        errors->push_back(one_line(file + ": " + place + ": " + what));
    }
    void warning(const std::string& place, const std::string& what) const {
        warnings->push_back(one_line(file + ": " + place + ": " + what));
    }
};

// Reads a whole file; on failure returns false with a one-line reason ("file not found", ...).
bool read_file(const std::string& path, std::string& text, std::string& why);
// Parses `text` (read from `path`) as strict JSON without comments; on failure returns false
// with "path: line L, column C: what".
bool parse_json(const std::string& path, const std::string& text, nlohmann::json& out, std::string& why);

}  // namespace sulcus::textio
