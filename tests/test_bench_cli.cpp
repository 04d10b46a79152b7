// sulcus-cli bench and wpd end to end: bench's JSON has the documented fields and shows a step
// that allocates nothing and does not penetrate; --list names the fixed scenes; bad arguments
// exit 2 naming the problem; the FCL comparison gives a ratio and agrees on contact; wpd writes
// one CSV row per setting value and a log-log plot with markers.
#include "cli_run.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using sulcus::test::kCli;
using sulcus::test::Outcome;
using sulcus::test::run_cli;

std::string read_text(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::string item;
    std::stringstream in(s);
    while (std::getline(in, item, sep)) out.push_back(item);
    return out;
}

// The lines of standard error that say something: usage errors add the generic
// "try 'sulcus-cli help'" hint after the line naming the problem.
std::vector<std::string> message_lines(const std::string& err) {
    std::vector<std::string> out;
    for (const std::string& l : split(err, '\n'))
        if (!l.empty() && l.find("try 'sulcus-cli help'") == std::string::npos) out.push_back(l);
    return out;
}

class BenchCli : public ::testing::Test {
protected:
    fs::path dir;
    void SetUp() override {
        ASSERT_TRUE(fs::exists(kCli)) << kCli << " is missing: build the sulcus-cli target";
        dir = fs::path(::testing::TempDir()) /
              ("sulcus_bench_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }

    // `args` exits 2 with one line on standard error that contains `what`.
    void expect_bad(const std::string& args, const std::string& what) {
        const Outcome o = run_cli(args, dir);
        EXPECT_EQ(o.status, 2) << args << "\n" << o.err;
        const std::vector<std::string> lines = message_lines(o.err);
        ASSERT_EQ(lines.size(), 1u) << args << "\n" << o.err;
        EXPECT_NE(lines[0].find(what), std::string::npos) << args << "\n" << o.err;
    }
};

void expect_percentiles(const json& j, const std::string& where) {
    SCOPED_TRACE(where);
    ASSERT_TRUE(j.is_object());
    for (const char* k : {"median", "p99", "p999", "max"}) ASSERT_TRUE(j.contains(k) && j[k].is_number()) << k;
    const double median = j["median"], p99 = j["p99"], p999 = j["p999"], max = j["max"];
    EXPECT_GT(median, 0.0);
    EXPECT_LE(median, p99);
    EXPECT_LE(p99, p999);
    EXPECT_LE(p999, max);
}

}  // namespace

// The test names the brief asks for: Bench.* and Wpd.*, on the fixture above.
class Bench : public BenchCli {};
class Wpd : public BenchCli {};

TEST_F(Bench, JsonHasTheDocumentedFieldsAndNoAllocations) {
    const fs::path file = dir / "bench.json";
    const Outcome o = run_cli("bench paper/cavity_0mm paper/sharp_corner --json " + file.string(), dir);
    ASSERT_EQ(o.status, 0) << o.err;
    ASSERT_TRUE(fs::exists(file));
    const json j = json::parse(read_text(file));
    ASSERT_TRUE(j.contains("machine") && j["machine"].is_object());
    ASSERT_TRUE(j["machine"].contains("cpu") && j["machine"]["cpu"].is_string());
    EXPECT_FALSE(j["machine"]["cpu"].get<std::string>().empty());
    ASSERT_TRUE(j.contains("scenes") && j["scenes"].is_array());
    ASSERT_EQ(j["scenes"].size(), 2u);
    const std::vector<std::string> names = {"paper/cavity_0mm", "paper/sharp_corner"};
    for (size_t i = 0; i < 2; ++i) {
        const json& s = j["scenes"][i];
        SCOPED_TRACE(names[i]);
        EXPECT_EQ(s.value("name", ""), names[i]);
        EXPECT_GT(s.value("triangles", 0L), 0);
        EXPECT_GT(s.value("steps", 0L), 1000);
        ASSERT_TRUE(s.contains("step_time_us"));
        expect_percentiles(s["step_time_us"], "step_time_us");
        ASSERT_TRUE(s.contains("stages_us") && s["stages_us"].is_object());
        for (const char* stage : {"detect", "gather", "solve", "select", "force"}) {
            ASSERT_TRUE(s["stages_us"].contains(stage)) << stage;
            const json& st = s["stages_us"][stage];
            EXPECT_TRUE(st.contains("median") && st["median"].is_number()) << stage;
            EXPECT_TRUE(st.contains("p99") && st["p99"].is_number()) << stage;
        }
        ASSERT_TRUE(s.contains("allocations_per_step"));
        EXPECT_EQ(s["allocations_per_step"].get<double>(), 0.0);
        EXPECT_GT(s.value("triangles_tested_per_step", 0.0), 0.0);
        ASSERT_TRUE(s.contains("candidates_per_step"));
        EXPECT_GE(s["candidates_per_step"].get<double>(), 0.0);
        ASSERT_TRUE(s.contains("max_penetration_m"));
        EXPECT_LE(s["max_penetration_m"].get<double>(), 1e-7);
    }
}

TEST_F(Bench, TicksCsvHasOneRowPerStepAndNoChecksWhenAskedNone) {
    // The ticks' directory is made where it does not exist yet.
    const fs::path ticks = dir / "ticks" / "nested", file = dir / "bench.json";
    const Outcome o = run_cli("bench paper/cavity_1mm --check-every 0 --ticks " + ticks.string() + " --json " +
                                  file.string(),
                              dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const json j = json::parse(read_text(file));
    const json& s = j["scenes"][0];
    EXPECT_EQ(s.value("checked_ticks", -1L), 0);
    const std::vector<std::string> lines = split(read_text(ticks / "paper_cavity_1mm_ticks.csv"), '\n');
    ASSERT_EQ(long(lines.size()), s.value("steps", 0L) + 1);
    const std::vector<std::string> header = split(lines[0], ',');
    for (const char* col : {"tick", "status", "step_us", "detect_us", "triangles_near", "candidates", "passes", "px_m",
                            "qw", "fz_N"})
        EXPECT_NE(std::find(header.begin(), header.end(), col), header.end()) << col;
    // Every row has every column, its tick index first, and the contact ticks the JSON counts.
    long contact = 0;
    for (size_t i = 1; i < lines.size(); ++i) {
        const std::vector<std::string> row = split(lines[i], ',');
        ASSERT_EQ(row.size(), header.size()) << lines[i];
        EXPECT_EQ(row[0], std::to_string(i - 1));
        contact += row[1] == "contact";
    }
    EXPECT_EQ(contact, s.value("contact_steps", -1L));
}

TEST_F(Bench, RunsGiveTheLeastTimePerTickAndTheMachineInterruptions) {
    const fs::path ticks = dir / "ticks", file = dir / "bench.json";
    const Outcome o = run_cli("bench paper/sharp_corner --runs 3 --check-every 0 --ticks " + ticks.string() + " --json " +
                                  file.string(),
                              dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const json j = json::parse(read_text(file));
    // The machine's own interruptions, measured by a spin before the scenes.
    ASSERT_TRUE(j["machine"].contains("interruptions"));
    const json& in = j["machine"]["interruptions"];
    EXPECT_GE(in.value("probe_s", 0.0), 0.5);
    EXPECT_GE(in.value("per_second", -1.0), 0.0);
    EXPECT_GE(in.value("lost_fraction", -1.0), 0.0);
    EXPECT_LE(in.value("lost_fraction", 2.0), 1.0);
    ASSERT_TRUE(in.contains("length_us"));
    if (in.value("per_second", 0.0) > 0.0) {  // a quiet machine may have none
        expect_percentiles(in["length_us"], "length_us");
        EXPECT_GE(in["length_us"].value("median", 0.0), 5.0);
    }
    // Per tick the least of three runs: no more than the first run's time at any tick, and so
    // at every percentile.
    const json& s = j["scenes"][0];
    ASSERT_TRUE(s.contains("least_of_runs"));
    EXPECT_EQ(s["least_of_runs"].value("runs", 0), 3);
    const json& least = s["least_of_runs"]["step_time_us"];
    expect_percentiles(least, "least_of_runs");
    for (const char* p : {"median", "p99", "p999", "max"})
        EXPECT_LE(least.value(p, 1e9), s["step_time_us"].value(p, -1.0)) << p;
    const std::vector<std::string> lines = split(read_text(ticks / "paper_sharp_corner_ticks.csv"), '\n');
    ASSERT_EQ(long(lines.size()), s.value("steps", 0L) + 1);
    const std::vector<std::string> header = split(lines[0], ',');
    const auto col = [&](const char* name) { return size_t(std::find(header.begin(), header.end(), name) - header.begin()); };
    const size_t first = col("step_us"), least_col = col("least_step_us");
    ASSERT_LT(least_col, header.size());
    for (size_t i = 1; i < lines.size(); ++i) {
        const std::vector<std::string> row = split(lines[i], ',');
        ASSERT_EQ(row.size(), header.size()) << lines[i];
        EXPECT_GT(std::stod(row[least_col]), 0.0) << lines[i];
        EXPECT_LE(std::stod(row[least_col]), std::stod(row[first])) << lines[i];
    }
    // One run, as before: no least_of_runs.
    const Outcome one = run_cli("bench paper/sharp_corner --check-every 0 --json " + file.string(), dir);
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_FALSE(json::parse(read_text(file))["scenes"][0].contains("least_of_runs"));
}

TEST_F(Bench, ListNamesTheFixedScenes) {
    const Outcome o = run_cli("bench --list", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const std::vector<std::string> lines = split(o.out, '\n');
    for (const char* name : {"paper/cavity_0mm", "paper/cavity_1mm", "paper/free_motion", "paper/line_tool",
                             "paper/sharp_corner", "paper/thin_plate", "paper/thin_plate_fast", "quadrant_44_47",
                             "quadrant_two_regions", "dense_wedge_250k"})
        EXPECT_NE(std::find(lines.begin(), lines.end(), name), lines.end()) << name << " not in:\n" << o.out;
    EXPECT_EQ(lines.size(), 10u) << o.out;
}

TEST_F(Bench, BadArgumentsExitTwoWithOneLine) {
    expect_bad("bench paper/no_such_scene", "no_such_scene");
    expect_bad("bench paper/cavity_0mm --max-ticks 0", "--max-ticks");
    expect_bad("bench paper/cavity_0mm --frobnicate", "--frobnicate");
    expect_bad("bench paper/cavity_0mm --peer nope", "nope");
    expect_bad("bench paper/cavity_0mm --check-every x", "--check-every");
    expect_bad("bench paper/cavity_0mm --runs 0", "--runs");
    // A directory that cannot be made (under a file) is refused before any scene runs.
    const fs::path file = dir / "a_file";
    std::ofstream(file) << "x";
    expect_bad("bench paper/cavity_0mm --ticks " + (file / "ticks").string(), "cannot create");
}

TEST_F(Bench, PeerFclReportsARatio) {
    const fs::path file = dir / "peer.json";
    const Outcome o = run_cli("bench paper/cavity_0mm --peer fcl --json " + file.string(), dir);
    if (o.status == 2 && o.err.find("no FCL") != std::string::npos) GTEST_SKIP() << "this build has no FCL";
    ASSERT_EQ(o.status, 0) << o.err;
    const json j = json::parse(read_text(file));
    ASSERT_TRUE(j.contains("peer") && j["peer"].is_object());
    EXPECT_EQ(j["peer"].value("name", ""), "fcl");
    ASSERT_TRUE(j["peer"].contains("scenes") && j["peer"]["scenes"].is_array());
    ASSERT_EQ(j["peer"]["scenes"].size(), 1u);
    const json& s = j["peer"]["scenes"][0];
    EXPECT_EQ(s.value("scene", ""), "paper/cavity_0mm");
    EXPECT_FALSE(s.contains("error")) << s.dump();
    std::map<std::string, json> by_query;
    for (const json& q : s["queries"]) by_query[q.value("query", "")] = q;
    for (const char* name : {"distance", "collision"}) {
        SCOPED_TRACE(name);
        ASSERT_TRUE(by_query.count(name)) << s.dump();
        const json& q = by_query[name];
        EXPECT_GT(q.value("queries", 0L), 0);
        EXPECT_GT(q.value("ratio", 0.0), 0.0);
        ASSERT_TRUE(q.contains("ours_us"));
        EXPECT_GT(q["ours_us"].value("median", 0.0), 0.0);
        EXPECT_GT(q["peer_us"].value("median", 0.0), 0.0);
        EXPECT_EQ(q.value("disagreements", -1L), 0);
    }
}

namespace {

// The setting values swept by wpd (wpd_cmd.cpp, knobs()), each knob alone about the defaults.
const std::map<std::string, std::vector<double>>& swept_values() {
    static const std::map<std::string, std::vector<double>> v = {
        {"constraint_tol_m", {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}},
        {"max_relinearizations", {1, 2, 4, 12, 32, 64}},
        {"qp_feasibility_tol", {1e-6, 1e-9, 1e-12, 1e-14, 1e-15}},
        {"max_candidates", {1, 2, 4, 8, 16, 32}},
        {"tie_tol_m", {1e-9, 1e-7, 1e-6, 1e-5, 1e-4}},
    };
    return v;
}

struct WpdRow {
    std::string setting;
    double value = 0;
    bool is_default = false;
    double pose_error = 0, force_error = 0;
};

}  // namespace

TEST_F(Wpd, WritesCsvAndLogLogPlotPerScene) {
    const fs::path out = dir / "wpd";
    const Outcome o = run_cli("wpd paper/sharp_corner --out " + out.string() + "", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const fs::path scene_dir = out / "paper_sharp_corner";
    const std::string csv = read_text(scene_dir / "wpd.csv");
    const std::vector<std::string> lines = split(csv, '\n');
    ASSERT_FALSE(lines.empty()) << (scene_dir / "wpd.csv");
    const std::string header =
        "scene,setting,value,is_default,step_median_us,step_p99_us,max_penetration_m,max_gap_in_contact_m,"
        "pose_error_m,rotation_error_rad,force_error_N";
    ASSERT_EQ(lines[0], header);
    size_t sweep = 0;
    for (const auto& [k, v] : swept_values()) sweep += v.size();
    ASSERT_EQ(lines.size(), 2 + sweep) << csv;  // the header, the defaults row, one row per value

    std::vector<WpdRow> rows;
    for (size_t i = 1; i < lines.size(); ++i) {
        const std::vector<std::string> c = split(lines[i], ',');
        ASSERT_EQ(c.size(), 11u) << lines[i];
        EXPECT_EQ(c[0], "paper/sharp_corner");
        WpdRow r;
        r.setting = c[1];
        r.value = std::stod(c[2]);
        r.is_default = c[3] == "1";
        r.pose_error = std::stod(c[8]);
        r.force_error = std::stod(c[10]);
        rows.push_back(r);
    }
    EXPECT_EQ(rows[0].setting, "defaults");
    int defaults = 0;
    for (const WpdRow& r : rows)
        if (r.is_default) {
            ++defaults;
            EXPECT_TRUE(std::isfinite(r.pose_error) && r.pose_error >= 0.0) << r.setting << " " << r.value;
            EXPECT_TRUE(std::isfinite(r.force_error) && r.force_error >= 0.0) << r.setting << " " << r.value;
        }
    EXPECT_GE(defaults, 1);
    auto find = [&](const std::string& setting, double value) -> const WpdRow* {
        for (const WpdRow& r : rows)
            if (r.setting == setting && std::abs(r.value - value) <= 1e-9 * std::abs(value)) return &r;
        return nullptr;
    };
    // Every swept value of every setting has its row, the tightest of each among them.
    for (const auto& [k, values] : swept_values())
        for (double v : values) EXPECT_NE(find(k, v), nullptr) << k << " = " << v;

    // Tightening the constraint tolerance does not make the pose worse.
    const WpdRow* tight = find("constraint_tol_m", 1e-10);
    const WpdRow* loose = find("constraint_tol_m", 1e-5);
    ASSERT_TRUE(tight && loose);
    EXPECT_LE(tight->pose_error, loose->pose_error);

    const std::string svg = read_text(scene_dir / "wpd.svg");
    EXPECT_EQ(svg.rfind("<svg", 0), 0u) << svg.substr(0, 80);
    EXPECT_NE(svg.find("<circle"), std::string::npos);
}

TEST_F(Wpd, NeedsOutAndAScene) {
    Outcome o = run_cli("wpd paper/sharp_corner", dir);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_NE(o.err.find("--out"), std::string::npos) << o.err;
    o = run_cli("wpd --out " + (dir / "w").string(), dir);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_NE(o.err.find("no scene"), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(dir / "w"));
}
