#include "sulcus/engine/json_text.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <system_error>

namespace sulcus::textio {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Messages are single lines: control characters are written as escapes.
std::string one_line(const std::string& s) {
    std::string out;
    out.reserve(s.size());
    for (const char c : s) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '\n') {
            out += "\\n";
        } else if (c == '\r') {
            out += "\\r";
        } else if (c == '\t') {
            out += "\\t";
        } else if (u < 0x20 || u == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", u);
            out += buf;
        } else {
            out += c;
        }
    }
    return out;
}

// A value quoted in a message: single line, and not endless.
std::string shown(const std::string& s) {
    constexpr size_t kMax = 60;
    std::string v = one_line(s);
    if (v.size() > kMax) v = v.substr(0, kMax) + "...";
    return "'" + v + "'";
}

// Shortest text that reads back as the same double.
std::string num(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// One reference token of a JSON pointer (RFC 6901: '~' -> "~0", '/' -> "~1").
std::string pointer_token(const std::string& key) {
    std::string out;
    for (const char c : key) {
        if (c == '~')
            out += "~0";
        else if (c == '/')
            out += "~1";
        else
            out += c;
    }
    return out;
}

// Reads a whole file; on failure returns false with a one-line reason.
bool read_file(const std::string& path, std::string& text, std::string& why) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) {
        why = "file not found";
        return false;
    }
    if (fs::is_directory(st)) {
        why = "is a folder, not a file";
        return false;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        why = "cannot be opened for reading";
        return false;
    }
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) {
        why = "read error";
        return false;
    }
    return true;
}

namespace {

// Line and column (1-based, columns in characters of UTF-8 text) of the byte at `index`.
void line_column(const std::string& text, size_t index, size_t& line, size_t& column) {
    index = std::min(index, text.size());
    line = 1;
    column = 1;
    for (size_t i = 0; i < index; ++i) {
        const auto u = static_cast<unsigned char>(text[i]);
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else if ((u & 0xC0) != 0x80) {  // count characters, not UTF-8 continuation bytes
            ++column;
        }
    }
}

// Byte index at which the JSON parser gives up: a second, DOM-less pass whose only job is
// to catch the parser's position (json::parse's exceptions do not all carry one).
size_t parse_stop(const std::string& text) {
    struct Locator : nlohmann::json_sax<json> {
        size_t stop = 0;
        bool null() override { return true; }
        bool boolean(bool) override { return true; }
        bool number_integer(number_integer_t) override { return true; }
        bool number_unsigned(number_unsigned_t) override { return true; }
        bool number_float(number_float_t, const string_t&) override { return true; }
        bool string(string_t&) override { return true; }
        bool binary(binary_t&) override { return true; }
        bool start_object(std::size_t) override { return true; }
        bool key(string_t&) override { return true; }
        bool end_object() override { return true; }
        bool start_array(std::size_t) override { return true; }
        bool end_array() override { return true; }
        bool parse_error(std::size_t position, const std::string&, const json::exception&) override {
            stop = position;  // 1-based index of the last character read (size + 1 at the end)
            return false;
        }
    } locator;
    json::sax_parse(text, &locator, json::input_format_t::json, /*strict=*/true, /*ignore_comments=*/false);
    return locator.stop > 0 ? locator.stop - 1 : 0;
}

// nlohmann's message without its "[json.exception...] parse error at ..." prefix.
std::string parse_error_text(const std::string& what) {
    size_t at = what.find("column ");
    if (at != std::string::npos) {
        at = what.find(": ", at);
        if (at != std::string::npos) return what.substr(at + 2);
    }
    at = what.find("] ");
    return at == std::string::npos ? what : what.substr(at + 2);
}

}  // namespace

bool parse_json(const std::string& path, const std::string& text, json& out, std::string& why) {
    try {
        out = json::parse(text, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/false);
        return true;
    } catch (const json::exception& e) {
        // Parse errors and number overflow (1e999) both land here; the locating pass finds
        // where the parser stopped.
        size_t line = 0, column = 0;
        line_column(text, parse_stop(text), line, column);
        why = one_line(path + ": line " + std::to_string(line) + ", column " + std::to_string(column) + ": " +
                       parse_error_text(e.what()));
        return false;
    }
}

}  // namespace sulcus::textio
