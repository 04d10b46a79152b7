// Writing an output file whole or not at all (DESIGN.md: a temporary name in the same folder,
// synced, then renamed), so a crash leaves the old file or the complete new one.
#pragma once

#include <string>

namespace sulcus {

// Returns "" or one line "path: what went wrong".
std::string write_file_atomic(const std::string& path, const std::string& text);

}  // namespace sulcus
