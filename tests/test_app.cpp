// The desktop app end to end: screenshots under Xvfb (Mesa llvmpipe) show the case, the tooth and
// the probe; a 60 s session driven by real pointer events runs and reports the servo loop's
// deadline misses; a live lesson is recorded and replays to the same scores; the headless command
// line links no window, GL or GUI library.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

#ifdef SULCUS_APP_BINARY
const std::string kApp = SULCUS_APP_BINARY;
#else
const std::string kApp;
#endif
const std::string kCli = std::string(SULCUS_BINARY_DIR) + "/bin/sulcus-cli";
const std::string kCases = std::string(SULCUS_BINARY_DIR) + "/cases";
// Runs the rest of the command line under an X server of its own; the screen follows.
const std::string kXvfb = std::string(SULCUS_SOURCE_DIR) + "/tests/app/xvfb.sh ";

std::string temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sulcus_test_app_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d.string();
}

// Runs a shell command; its exit status and what it printed (stdout and stderr).
struct Shell {
    int status = -1;
    std::string output;
};
Shell run(const std::string& command) {
    Shell r;
    FILE* p = popen((command + " 2>&1").c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n = 0;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

struct Image {
    int w = 0, h = 0;
    std::vector<unsigned char> rgb;
    const unsigned char* at(int x, int y) const { return &rgb[(size_t(y) * size_t(w) + size_t(x)) * 3]; }
};
Image load_png(const std::string& path) {
    Image im;
    int n = 0;
    unsigned char* data = stbi_load(path.c_str(), &im.w, &im.h, &n, 3);
    if (!data) return im;
    im.rgb.assign(data, data + size_t(im.w) * size_t(im.h) * 3);
    stbi_image_free(data);
    return im;
}

double luminance(const unsigned char* p) { return (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) / 255.0; }

#define REQUIRE_APP()                                                           \
    do {                                                                        \
        if (kApp.empty()) GTEST_FAIL() << "the desktop app (sulcus) is not built"; \
    } while (0)

}  // namespace

TEST(App, ScreenshotShowsTheToothAndTheProbe) {
    REQUIRE_APP();
    const std::string dir = temp_dir("screenshot");
    const std::string shot = dir + "/shot.png", ids = dir + "/ids.png";
    // The quadrant from buccal of sextant 6, gingiva see-through, the probe where the case starts it.
    const Shell r = run(kXvfb + "1920x1080x24 " + kApp + " --case " + kCases +
                      "/quadrant_44_47 --device mouse --frames 20 --size 1280x720 --gingiva 0.4 --sextant 6 "
                      "--screenshot " + shot + " --ids " + ids);
    ASSERT_EQ(r.status, 0) << r.output;

    const Image im = load_png(shot), id = load_png(ids);
    ASSERT_EQ(im.w, 1280) << "screenshot width";
    ASSERT_EQ(im.h, 720) << "screenshot height";
    ASSERT_EQ(id.w, 1280);
    ASSERT_EQ(id.h, 720);

    // Not blank and not one colour: many colours and a real spread of brightness.
    std::set<uint32_t> colours;
    double sum = 0, sum2 = 0;
    for (int y = 0; y < im.h; ++y)
        for (int x = 0; x < im.w; ++x) {
            const unsigned char* p = im.at(x, y);
            colours.insert(uint32_t(p[0]) << 16 | uint32_t(p[1]) << 8 | p[2]);
            const double l = luminance(p);
            sum += l;
            sum2 += l * l;
        }
    const double n = double(im.w) * im.h, mean = sum / n;
    EXPECT_GT(colours.size(), 2000u) << "distinct colours";
    EXPECT_GT(std::sqrt(sum2 / n - mean * mean), 0.05) << "brightness spread";

    // The id pass says where the tooth and the probe are drawn (nearest surface); the picture must
    // show them there: tooth pixels light and warm, probe pixels unlike the background.
    const unsigned char* bg = nullptr;
    int tooth_px = 0, tooth_lit = 0, probe_px = 0, probe_seen = 0;
    for (int y = 0; y < id.h && !bg; ++y)
        for (int x = 0; x < id.w && !bg; ++x)
            if (id.at(x, y)[0] == 0 && x > 400 && x < 800) bg = im.at(x, y);  // a background pixel mid-view
    ASSERT_NE(bg, nullptr) << "no background in the view";
    std::set<int> teeth;
    for (int y = 0; y < id.h; ++y)
        for (int x = 0; x < id.w; ++x) {
            const unsigned char* k = id.at(x, y);
            const unsigned char* p = im.at(x, y);
            if (k[0] == 1) {
                ++tooth_px;
                teeth.insert(k[1]);
                if (luminance(p) > 0.45 && p[0] >= p[2]) ++tooth_lit;
            } else if (k[0] == 4) {
                ++probe_px;
                const int d = std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]);
                if (d > 60) ++probe_seen;
            }
        }
    EXPECT_GT(tooth_px, 20000) << "tooth pixels in the id pass";
    EXPECT_GT(tooth_lit, 10000) << "tooth pixels drawn light (not covered, not dark)";
    EXPECT_EQ(teeth, (std::set<int>{44, 45, 46, 47})) << "every tooth of the case drawn";
    EXPECT_GT(probe_px, 150) << "probe pixels in the id pass";
    EXPECT_GT(probe_seen, 100) << "probe pixels that stand out from the background";
}

TEST(App, BadArgumentsGiveOneLineAndExitTwo) {
    REQUIRE_APP();
    Shell r = run(kApp + " --frames 0");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("--frames"), std::string::npos) << r.output;
    r = run(kApp + " --case /nonexistent/case --frames 1");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("/nonexistent/case"), std::string::npos) << r.output;
    r = run(kApp + " --screenshot x.png");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("--frames"), std::string::npos) << r.output;
}

TEST(App, NoDisplayIsAClearError) {
    REQUIRE_APP();
    const Shell r = run("env -u DISPLAY -u WAYLAND_DISPLAY " + kApp + " --case " + kCases + "/healthy_11 --frames 1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("no display"), std::string::npos) << r.output;
}

// With no Phantom answering, the default device is the mouse, and the app says why.
TEST(App, AutoDeviceFallsBackToTheMouse) {
    REQUIRE_APP();
    const Shell r = run("SULCUS_LIBHD=/nonexistent/libHD.so " + kXvfb + "1280x800x24 " + kApp +
                        " --case " + kCases + "/healthy_11 --frames 3 --size 800x600");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("/nonexistent/libHD.so"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("the mouse drives the probe"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("(Mouse and keyboard)"), std::string::npos) << r.output;
}

// The simulated hand probes every site of healthy_11 along the case's trajectory and charts each
// at its pass's hold, whatever the frame rate.
TEST(App, SimulatedHandChartsEverySite) {
    REQUIRE_APP();
    const std::string dir = temp_dir("sim");
    const Shell r = run(kXvfb + "1280x800x24 " + kApp + " --case " + kCases +
                        "/healthy_11 --device sim --ticks 8600 --size 800x600 --report " + dir + "/report.json");
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream in(dir + "/report.json");
    ASSERT_TRUE(in);
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j.at("sites_total").get<int>(), 6);
    EXPECT_EQ(j.at("sites_charted").get<int>(), 6);
}

// A lesson run live by the simulated hand: every chart entry goes through the servo loop as a
// posted event, the live runtime scores it, the scores are stored in the recording, and the
// headless replay of that recording recomputes them bit for bit (`sulcus-cli replay --check`).
TEST(App, LiveLessonScoresEqualTheReplayedOnes) {
    REQUIRE_APP();
    const std::string dir = temp_dir("lesson");
    const std::string rec = dir + "/R.rec", report = dir + "/report.json";
    const std::string lesson = std::string(SULCUS_SOURCE_DIR) + "/content/assets/lessons/healthy_11.json";
    // 8700 ticks: the hand's whole probing script of healthy_11 (8.58 s at 1 kHz) and a little more.
    const Shell r = run(kXvfb + "1280x800x24 " + kApp + " --lesson " + lesson +
                        " --device sim --record " + rec + " --ticks 8700 --frames 2 --size 800x600 --report " + report);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("session recorded to " + rec), std::string::npos) << r.output;

    std::ifstream in(report);
    ASSERT_TRUE(in) << report;
    const nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_TRUE(j.contains("lesson")) << j.dump(2);
    const nlohmann::json& l = j.at("lesson");
    EXPECT_EQ(l.at("title").get<std::string>(), "Healthy 11: six sites");
    EXPECT_EQ(l.at("sites_target").get<int>(), 6);
    EXPECT_EQ(l.at("sites_charted").get<int>(), 6) << "the hand's entries reached the lesson";
    EXPECT_GT(l.at("overall").get<double>(), 0.0);
    EXPECT_EQ(l.at("recording").get<std::string>(), rec);
    EXPECT_EQ(j.at("sites_charted").get<int>(), 6) << "the chart panel shows what was posted";

    const Shell check = run(kCli + " replay " + rec + " --check");
    EXPECT_EQ(check.status, 0) << check.output;
}

// When the UI's telemetry queue overflows the live runtime misses ticks: the app then scores the
// session by replaying its recording and stores those scores, so the check still passes.
TEST(App, DroppedTelemetryIsScoredFromTheRecording) {
    REQUIRE_APP();
    const std::string dir = temp_dir("drops");
    const std::string rec = dir + "/R.rec", report = dir + "/report.json";
    const std::string lesson = std::string(SULCUS_SOURCE_DIR) + "/content/assets/lessons/healthy_11.json";
    // 16 ticks of queue against frames of tens of milliseconds: samples are dropped.
    const Shell r = run(kXvfb + "1280x800x24 " + kApp + " --lesson " + lesson +
                        " --device sim --record " + rec + " --telemetry-queue 16 --ticks 3000 --frames 2 --size 800x600"
                        " --report " + report);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("scoring the session from its recording"), std::string::npos) << r.output;
    std::ifstream in(report);
    ASSERT_TRUE(in) << report;
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_GT(j.at("servo").at("telemetry_drops").get<uint64_t>(), 0u);
    ASSERT_TRUE(j.contains("lesson"));
    EXPECT_GE(j.at("lesson").at("sites_charted").get<int>(), 1);
    const Shell check = run(kCli + " replay " + rec + " --check");
    EXPECT_EQ(check.status, 0) << check.output;
}

// With a lesson and no --record the session goes to the sessions folder, named after the lesson
// and the UTC time; it replays to the stored scores too (here a lesson ended before any charting).
TEST(App, LessonIsRecordedToTheSessionsFolderByDefault) {
    REQUIRE_APP();
    const std::string dir = temp_dir("sessions");
    const std::string lesson = std::string(SULCUS_SOURCE_DIR) + "/content/assets/lessons/healthy_11.json";
    const Shell r = run("SULCUS_SESSIONS_DIR=" + dir + " " + kXvfb + "1280x800x24 " + kApp +
                        " --lesson " + lesson + " --device sim --ticks 200 --frames 2 --size 800x600");
    ASSERT_EQ(r.status, 0) << r.output;
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().filename().string());
    ASSERT_EQ(files.size(), 1u);
    EXPECT_TRUE(std::regex_match(files[0], std::regex(R"(healthy_11-\d{8}T\d{6}Z\.rec)"))) << files[0];
    const Shell check = run(kCli + " replay " + dir + "/" + files[0] + " --check");
    EXPECT_EQ(check.status, 0) << check.output;

    // --record none: nothing is written.
    const std::string none = temp_dir("sessions_none");
    const Shell r2 = run("SULCUS_SESSIONS_DIR=" + none + " " + kXvfb + "1280x800x24 " + kApp +
                         " --lesson " + lesson + " --device sim --record none --ticks 50 --frames 2 --size 800x600");
    ASSERT_EQ(r2.status, 0) << r2.output;
    EXPECT_TRUE(fs::is_empty(none));
}

// A lesson that does not load is one line naming the file, and exit 2.
TEST(App, BadLessonFileIsOneLineAndExitTwo) {
    REQUIRE_APP();
    const std::string dir = temp_dir("bad_lesson");
    const std::string bad = dir + "/lessons/bad.json";
    fs::create_directories(dir + "/lessons");
    std::ofstream(bad) << R"({"format": "sulcus.lesson/2", "title": "x", "steps": []})";
    for (const std::string& path : {bad, dir + "/lessons/none.json"}) {
        const Shell r = run(kApp + " --lesson " + path + " --frames 1");
        EXPECT_EQ(r.status, 2) << r.output;
        EXPECT_NE(r.output.find(path), std::string::npos) << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    }
}

// Instructor mode opens with the reference chart editable and the save panel, and draws.
TEST(App, InstructorModeRuns) {
    REQUIRE_APP();
    const std::string dir = temp_dir("instructor");
    const Shell r = run(kXvfb + "1280x800x24 " + kApp + " --case " + kCases +
                        "/healthy_11 --instructor --device mouse --frames 3 --size 1280x720 --screenshot " + dir +
                        "/shot.png");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(load_png(dir + "/shot.png").w, 1280);
}

// A lesson session under Xvfb: the mouse device driven by real X pointer events for 60 s of servo
// time; the app exits cleanly and reports the servo thread's deadline misses.
TEST(App, MouseSessionOfSixtySecondsUnderXvfb) {
    REQUIRE_APP();
    const std::string dir = temp_dir("session");
    const std::string report = dir + "/report.json";
    const Shell r = run("timeout 240 " + kXvfb + "1920x1080x24 " + std::string(SULCUS_SOURCE_DIR) +
                      "/tests/app/mouse_session.sh " + kApp + " " + kCases + "/healthy_11 60 " + report);
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream in(report);
    ASSERT_TRUE(in) << report;
    const nlohmann::json j = nlohmann::json::parse(in);
    const auto& servo = j.at("servo");
    EXPECT_GE(servo.at("elapsed_s").get<double>(), 59.0);
    // The servo thread kept its rate (at least 75 % of the ticks of 60 s at 1 kHz).
    EXPECT_GT(servo.at("ticks").get<uint64_t>(), 45000u);
    ASSERT_TRUE(servo.contains("deadline_misses"));
    EXPECT_FALSE(servo.at("non_finite_sent").get<bool>());
    EXPECT_EQ(servo.at("read_failures").get<uint64_t>(), 0u);
    // The pointer moved the probe.
    EXPECT_GT(j.at("haptic_travel_m").get<double>(), 1e-3);
    // ... into contact with the case, the renderer holding it outside.
    EXPECT_GT(j.at("contact_ticks").get<uint64_t>(), 100u);
    EXPECT_GT(j.at("frames").get<int>(), 300);
    // The summary line names the deadline misses.
    EXPECT_NE(r.output.find("deadline misses"), std::string::npos) << r.output;
    std::printf("%s", r.output.c_str());
}

// DESIGN.md: only `sulcus` links GLFW, OpenGL and ImGui. Checked on the linked libraries (ELF
// NEEDED entries) and, for the static ImGui, on the defined symbols; the app itself is the
// control that the check can see them.
TEST(App, CommandLineLinksNoWindowGlOrGuiLibrary) {
    const std::regex gui(R"((glfw|libGL\b|libGL\.|libOpenGL|libGLX|libEGL|imgui|libX11))");
    auto needed = [](const std::string& bin) {
        const Shell r = run("readelf -d " + bin);
        std::vector<std::string> libs;
        const std::regex line(R"(\(NEEDED\)\s+Shared library: \[([^\]]+)\])");
        for (std::sregex_iterator it(r.output.begin(), r.output.end(), line), end; it != end; ++it)
            libs.push_back((*it)[1]);
        return std::make_pair(r.status, libs);
    };
    auto imgui_symbols = [](const std::string& bin) {
        const Shell r = run("nm -C --defined-only " + bin + " | grep -c 'ImGui::'");
        return std::atoi(r.output.c_str());
    };
    const auto [cli_status, cli_libs] = needed(kCli);
    ASSERT_EQ(cli_status, 0) << "readelf on " << kCli;
    ASSERT_FALSE(cli_libs.empty()) << "no NEEDED entries read from " << kCli;
    for (const std::string& lib : cli_libs) EXPECT_FALSE(std::regex_search(lib, gui)) << "sulcus-cli links " << lib;
    EXPECT_EQ(imgui_symbols(kCli), 0) << "ImGui code in sulcus-cli";

    REQUIRE_APP();
    const auto [app_status, app_libs] = needed(kApp);
    ASSERT_EQ(app_status, 0);
    bool app_gui = false;
    for (const std::string& lib : app_libs) app_gui |= std::regex_search(lib, gui);
    EXPECT_TRUE(app_gui) << "the check does not see the app's GLFW/GL libraries";
    EXPECT_GT(imgui_symbols(kApp), 100) << "the check does not see the app's ImGui code";
}
