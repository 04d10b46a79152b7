// Small text helpers shared by the reports, the scoring sentences and the command line.
#pragma once

#include <string>
#include <string_view>

namespace sulcus {

// printf into a std::string, whatever its length.
std::string format_text(const char* format, ...) __attribute__((format(printf, 1, 2)));

// Text safe inside XML or HTML, in element content and in quoted attributes: & < > " ' escaped,
// control characters other than tab (not allowed in XML 1.0) replaced by a space.
std::string xml_escape(std::string_view s);

}  // namespace sulcus
