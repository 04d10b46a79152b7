// Running the built sulcus-cli from a test: exit status, standard output and standard error.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace sulcus::test {

inline const std::string kCli = std::string(SULCUS_BINARY_DIR) + "/bin/sulcus-cli";

struct Outcome {
    int status = -1;
    std::string out, err;
};

// Runs `sulcus-cli ARGS` through the shell; standard error goes through a file in `dir`.
inline Outcome run_cli(const std::string& args, const std::filesystem::path& dir) {
    const std::string err_file = (dir / "stderr.txt").string();
    const std::string cmd = kCli + " " + args + " 2>" + err_file;
    Outcome o;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return o;
    std::array<char, 4096> buf{};
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) o.out.append(buf.data(), n);
    const int st = pclose(p);
    o.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    std::ifstream e(err_file);
    std::stringstream ss;
    ss << e.rdbuf();
    o.err = ss.str();
    return o;
}

}  // namespace sulcus::test
