// Recorded lessons replayed headless with sulcus-cli: byte-identical reports, --check against the
// stored scores (passing on the bundled recordings, exit 1 on an edited one), batches in parallel
// and in shards with a JUnit summary, and the lesson subcommands.
#include "sulcus/app/lesson_session.h"
#include "sulcus/haptics/recording.h"

#include "cli_run.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

using namespace sulcus;
namespace fs = std::filesystem;
using test::Outcome;
using test::run_cli;

namespace {

const std::string kAssets = std::string(SULCUS_SOURCE_DIR) + "/content/assets";
const std::string kRecordings = kAssets + "/recordings";
const std::string kCases = std::string(SULCUS_BINARY_DIR) + "/cases";

std::string read_file(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

fs::path scratch(const std::string& name) {
    const fs::path d = fs::path(::testing::TempDir()) / ("sulcus_replay_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// The recording with its stored scores changed by `edit`, written to `out`.
void write_edited(const std::string& in, const fs::path& out, const std::function<void(nlohmann::json&)>& edit) {
    RecordingRead r = read_recording(in);
    ASSERT_TRUE(r.ok()) << r.error;
    bool found = false;
    for (RecordingAnnex& a : r.annexes) {
        if (a.name != kScoresAnnex) continue;
        nlohmann::json j = nlohmann::json::parse(a.json);
        edit(j);
        a.json = j.dump();
        found = true;
    }
    ASSERT_TRUE(found) << in << " has no scores annex";
    ASSERT_EQ(write_recording(out.string(), r), "");
}

// Replays a bundled recording twice (--out writes the JSON and the HTML report) with --check.
void replay_twice(const std::string& name) {
    const fs::path d = scratch(name);
    const std::string rec = kRecordings + "/" + name + ".rec";
    const std::string common = " --check --cases " + kCases + " --content-root " + kAssets;
    const Outcome a = run_cli("replay " + rec + " --out " + (d / "a").string() + common, d);
    const Outcome b = run_cli("replay " + rec + " --out " + (d / "b").string() + common, d);
    ASSERT_EQ(a.status, 0) << a.out << a.err;
    ASSERT_EQ(b.status, 0) << b.out << b.err;
    EXPECT_NE(a.out.find("check passed"), std::string::npos) << a.out;
    for (const char* ext : {".json", ".html"}) {
        const std::string x = read_file(d / "a" / (name + ext)), y = read_file(d / "b" / (name + ext));
        EXPECT_GT(x.size(), 1000u) << ext;
        EXPECT_EQ(x, y) << name << ext << " differs between two replays";
    }
    // The report's scores are the stored ones, and every target site was charted.
    const nlohmann::json j = nlohmann::json::parse(read_file(d / "a" / (name + ".json")));
    EXPECT_EQ(j["format"], kReportFormat);
    EXPECT_EQ(j["stored_scores_match"], true);
    EXPECT_EQ(j["recording"]["first_mismatch"], -1);
    EXPECT_EQ(j["scores"]["sites_charted"], j["scores"]["sites_target"]);
    const std::string html = read_file(d / "a" / (name + ".html"));
    EXPECT_NE(html.find("<svg"), std::string::npos);        // the force plot
    EXPECT_NE(html.find("<h2>Chart</h2>"), std::string::npos);
    EXPECT_NE(html.find("<h2>Sites</h2>"), std::string::npos);
}

}  // namespace

TEST(LessonReplay, Healthy11ReplaysTwiceToByteIdenticalReportsAndPassesTheCheck) { replay_twice("healthy_11"); }
TEST(LessonReplay, Periodontitis36ReplaysTwiceToByteIdenticalReportsAndPassesTheCheck) { replay_twice("periodontitis_36"); }
TEST(LessonReplay, Quadrant4447ReplaysTwiceToByteIdenticalReportsAndPassesTheCheck) { replay_twice("quadrant_44_47"); }

TEST(LessonReplay, CheckFailsWithExitOneOnEditedScoresNamingTheFirstDifference) {
    const fs::path d = scratch("edited");
    const fs::path edited = d / "edited.rec";
    write_edited(kRecordings + "/healthy_11.rec", edited, [](nlohmann::json& j) {
        j["sites"][2]["force_N"] = j["sites"][2]["force_N"].get<double>() + 0.01;
        j["overall"] = 0.99;  // a later key: the first difference in document order is named
    });
    const std::string common = " --cases " + kCases + " --content-root " + kAssets;
    const Outcome o = run_cli("replay " + edited.string() + " --check" + common, d);
    EXPECT_EQ(o.status, 1) << o.out << o.err;
    EXPECT_NE(o.err.find("scores differ at overall: stored 0.99, recomputed"), std::string::npos) << o.err;
    // Without --check the replay itself succeeds.
    EXPECT_EQ(run_cli("replay " + edited.string() + common, d).status, 0);
    // A site's value alone.
    write_edited(kRecordings + "/healthy_11.rec", edited,
                 [](nlohmann::json& j) { j["sites"][2]["force_N"] = j["sites"][2]["force_N"].get<double>() + 0.01; });
    const Outcome s = run_cli("replay " + edited.string() + " --check" + common, d);
    EXPECT_EQ(s.status, 1);
    EXPECT_NE(s.err.find("scores differ at sites[2].force_N: stored "), std::string::npos) << s.err;
}

TEST(LessonReplay, CheckFailsWhenARecordedPoseWasEditedNamingTheTick) {
    const fs::path d = scratch("pose");
    RecordingRead r = read_recording(kRecordings + "/healthy_11.rec");
    ASSERT_TRUE(r.ok());
    ASSERT_GT(r.ticks.size(), 2000u);
    for (std::size_t i = 1500; i < r.ticks.size(); ++i) r.ticks[i].device_pose.position.y -= 0.5e-3;
    ASSERT_EQ(write_recording((d / "pose.rec").string(), r), "");
    const Outcome o = run_cli("replay " + (d / "pose.rec").string() + " --check --cases " + kCases + " --content-root " + kAssets, d);
    EXPECT_EQ(o.status, 1);
    EXPECT_NE(o.err.find("tick "), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("the replayed force differs from the recorded one"), std::string::npos) << o.err;
}

TEST(LessonReplay, AFolderRunsInParallelAndInShardsWithAJUnitSummary) {
    const fs::path d = scratch("batch");
    const fs::path in = d / "in";
    fs::create_directories(in);
    for (const char* n : {"a.rec", "b.rec", "d.rec"}) fs::copy_file(kRecordings + "/healthy_11.rec", in / n);
    write_edited(kRecordings + "/healthy_11.rec", in / "c.rec", [](nlohmann::json& j) { j["time_s"] = 1.0; });
    fs::create_directories(in / "ignored");  // not a recording
    const std::string common = " --check --cases " + kCases + " --content-root " + kAssets;

    const Outcome all = run_cli("replay " + in.string() + " --jobs 2 --junit " + (d / "all.xml").string() + common, d);
    EXPECT_EQ(all.status, 1) << all.err;  // c.rec fails its check
    const std::string xml = read_file(d / "all.xml");
    EXPECT_NE(xml.find("<testsuite name=\"sulcus.replay\" tests=\"4\" failures=\"1\" errors=\"0\""), std::string::npos) << xml;
    EXPECT_NE(xml.find("c.rec\" time="), std::string::npos);
    EXPECT_NE(xml.find("<failure message=\"scores differ at time_s: stored 1.0"), std::string::npos) << xml;

    // Shards 1/2 and 2/2 take the sorted list's even and odd positions: a, c and b, d.
    const Outcome s1 = run_cli("replay " + in.string() + " --shard 1/2 --junit " + (d / "s1.xml").string() + common, d);
    const Outcome s2 = run_cli("replay " + in.string() + " --shard 2/2 --jobs 2 --junit " + (d / "s2.xml").string() + common, d);
    EXPECT_EQ(s1.status, 1);
    EXPECT_EQ(s2.status, 0) << s2.err;
    const std::string x1 = read_file(d / "s1.xml"), x2 = read_file(d / "s2.xml");
    EXPECT_NE(x1.find("tests=\"2\" failures=\"1\""), std::string::npos) << x1;
    EXPECT_NE(x1.find("a.rec"), std::string::npos);
    EXPECT_NE(x1.find("c.rec"), std::string::npos);
    EXPECT_EQ(x1.find("b.rec"), std::string::npos);
    EXPECT_NE(x2.find("tests=\"2\" failures=\"0\""), std::string::npos) << x2;
    EXPECT_NE(x2.find("b.rec"), std::string::npos);
    EXPECT_NE(x2.find("d.rec"), std::string::npos);
}

TEST(LessonReplay, BadInputExitsTwoWithOneLineNamingIt) {
    const fs::path d = scratch("bad");
    const std::string common = " --cases " + kCases + " --content-root " + kAssets;
    Outcome o = run_cli("replay " + (d / "missing.rec").string() + common, d);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find("missing.rec"), std::string::npos) << o.err;
    o = run_cli("replay " + kRecordings + "/healthy_11.rec --shard 3/2" + common, d);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find("--shard"), std::string::npos);
    o = run_cli("replay " + kRecordings + " --report " + (d / "x.json").string() + common, d);
    EXPECT_EQ(o.status, 2);  // one report file for three recordings
    // A recording that names no lesson needs --lesson.
    RecordingRead r = read_recording(kRecordings + "/healthy_11.rec");
    r.metadata.lesson.clear();
    ASSERT_EQ(write_recording((d / "nolesson.rec").string(), r), "");
    o = run_cli("replay " + (d / "nolesson.rec").string() + common, d);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find("names no lesson"), std::string::npos) << o.err;
    o = run_cli("replay " + (d / "nolesson.rec").string() + " --check --lesson " + kAssets + "/lessons/healthy_11.json" + common, d);
    EXPECT_EQ(o.status, 0) << o.err;
    // A case that was not built.
    o = run_cli("replay " + kRecordings + "/healthy_11.rec --cases " + d.string() + " --content-root " + kAssets, d);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find("no built case"), std::string::npos) << o.err;
}

TEST(LessonCommand, CheckAcceptsTheBundledLessonsAndRejectsABadOne) {
    const fs::path d = scratch("check");
    for (const char* n : {"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        const Outcome o = run_cli("lesson check " + kAssets + "/lessons/" + n + ".json --cases " + kCases, d);
        EXPECT_EQ(o.status, 0) << n << ": " << o.err;
        EXPECT_NE(o.out.find(": ok:"), std::string::npos);
    }
    // A lesson with an unknown key and a bad site, inside a scratch content root.
    fs::create_directories(d / "root" / "lessons");
    fs::create_directories(d / "root" / "cases" / "healthy_11");
    fs::copy_file(kAssets + "/cases/healthy_11/chart.json", d / "root" / "cases" / "healthy_11" / "chart.json");
    std::ofstream(d / "root" / "lessons" / "bad.json")
        << R"({"format":"sulcus.lesson/1","title":"t","case":{"chart":"cases/healthy_11/chart.json"},"colour":1,)"
        << R"("steps":[{"id":"a","instruction":"x","sites":["11XY"]}]})";
    const Outcome o = run_cli("lesson check " + (d / "root" / "lessons" / "bad.json").string() + " --no-case", d);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find("bad.json"), std::string::npos);
    EXPECT_NE(o.err.find("colour"), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("steps[0].sites[0]"), std::string::npos) << o.err;
}

TEST(LessonCommand, NewWritesAStarterLessonThatChecks) {
    const fs::path d = scratch("new");
    const fs::path out = d / "quadrant.json";
    const Outcome o = run_cli("lesson new --case " + kAssets + "/cases/quadrant_44_47 --title Quadrant --out " + out.string() +
                                  " --content-root " + kAssets,
                              d);
    ASSERT_EQ(o.status, 0) << o.err;
    // Its chart path is relative to the content root, so it checks from there.
    const LessonLoad l = load_lesson(out.string(), kAssets);
    ASSERT_TRUE(l.ok()) << l.errors.front();
    EXPECT_EQ(l.lesson.chart, "cases/quadrant_44_47/chart.json");
    EXPECT_EQ(l.lesson.teeth, (std::vector<int>{44, 45, 46, 47}));
    EXPECT_EQ(l.lesson.steps.size(), 8u);
    EXPECT_EQ(l.lesson.target_sites().size(), 24u);
    // From a built case folder outside the content root, the same chart is found under cases/.
    const Outcome b = run_cli("lesson new --case " + kCases + "/healthy_11 --content-root " + kAssets, d);
    ASSERT_EQ(b.status, 0) << b.err;
    EXPECT_NE(b.out.find("\"chart\": \"cases/healthy_11/chart.json\""), std::string::npos) << b.out;
    // A folder with no chart.
    const Outcome c = run_cli("lesson new --case " + d.string() + " --content-root " + kAssets, d);
    EXPECT_EQ(c.status, 2);
    EXPECT_NE(c.err.find("no chart.json"), std::string::npos) << c.err;
}

TEST(LessonCommand, RecordWithTheSimulatedHandStoresScoresThatReplayIdentically) {
    const fs::path d = scratch("record");
    const fs::path rec = d / "h.rec";
    const Outcome o = run_cli("lesson record " + kAssets + "/lessons/healthy_11.json --out " + rec.string() + " --cases " + kCases, d);
    ASSERT_EQ(o.status, 0) << o.err;
    const RecordingRead r = read_recording(rec.string());
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.metadata.lesson, "lessons/healthy_11.json");
    EXPECT_EQ(r.metadata.device, "sim-hand");
    ASSERT_EQ(r.annexes.size(), 1u);
    EXPECT_EQ(r.annexes[0].name, kScoresAnnex);
    // The chart events the hand posted are in the recording, one per site.
    int charted = 0;
    for (const RecordingEvent& e : r.events) charted += e.kind == kEventChartDepth;
    EXPECT_EQ(charted, 6);
    const Outcome c = run_cli("replay " + rec.string() + " --check --cases " + kCases + " --content-root " + kAssets, d);
    EXPECT_EQ(c.status, 0) << c.err;
    // Recorded again, the scores are the same (the manual clock makes the session reproducible).
    const fs::path again = d / "again.rec";
    ASSERT_EQ(run_cli("lesson record " + kAssets + "/lessons/healthy_11.json --out " + again.string() + " --cases " + kCases, d).status, 0);
    EXPECT_EQ(read_recording(again.string()).annexes.at(0).json, r.annexes[0].json);
}
