// The lesson script reader, `sulcus.lesson/1`: the bundled lessons load; malformed lessons are
// rejected with one line per fault naming the file and the JSON path; paths stay in the content
// root; the writer's output reads back equal.
#include "sulcus/app/lesson.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace sulcus {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kRoot = SULCUS_SOURCE_DIR "/content/assets";
const char* kSource = "bad.json";

std::string join(const std::vector<std::string>& lines) {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
}

// True when some error line contains every one of `parts`.
bool has_error(const LessonLoad& load, std::initializer_list<std::string> parts) {
    for (const std::string& e : load.errors) {
        bool all = true;
        for (const std::string& p : parts) all = all && e.find(p) != std::string::npos;
        if (all) return true;
    }
    return false;
}

// Every fault is one line that starts with the file's name.
void expect_one_line_each(const LessonLoad& load, const std::string& source) {
    for (const std::string& e : load.errors) {
        EXPECT_EQ(e.rfind(source + ": ", 0), 0u) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
}

// A small valid lesson on the bundled healthy_11 chart.
json good_doc() {
    return json::parse(R"({
      "format": "sulcus.lesson/1",
      "title": "t",
      "case": {"chart": "cases/healthy_11/chart.json", "teeth": [11]},
      "steps": [
        {"id": "a", "instruction": "probe", "sites": ["11MB", "11B", "11DB"]},
        {"id": "b", "instruction": "probe", "sites": ["11DL", "11L", "11ML"], "hints": ["keep parallel"]}
      ],
      "rules": [
        {"id": "firm", "when": "force_above", "threshold_N": 0.25, "message": "too firm"},
        {"id": "out", "when": "left_sulcus", "level": "note", "message": "stay in"}
      ]
    })");
}

LessonLoad parse(const json& doc, const std::string& root = kRoot) {
    LessonLoad l = parse_lesson(doc.dump(2), kSource, root);
    expect_one_line_each(l, kSource);
    return l;
}

// A scratch folder of its own for each test, removed afterwards.
class LessonFiles : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() / ("sulcus_lesson_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    // A content root holding a copy of a bundled chart and an empty lessons/ folder.
    fs::path make_root(const std::string& name = "root") {
        const fs::path root = dir_ / name;
        fs::create_directories(root / "cases/healthy_11");
        fs::create_directories(root / "lessons");
        fs::copy_file(kRoot + "/cases/healthy_11/chart.json", root / "cases/healthy_11/chart.json");
        return root;
    }
    static void write(const fs::path& p, const std::string& text) {
        fs::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
    }
    fs::path dir_;
};

TEST(Lesson, SiteRefsParseAndName) {
    SiteRef r;
    ASSERT_TRUE(parse_site_ref("36MB", &r));
    EXPECT_EQ(r, (SiteRef{36, Site::MB}));
    ASSERT_TRUE(parse_site_ref("11DL", &r));
    EXPECT_EQ(r, (SiteRef{11, Site::DL}));
    ASSERT_TRUE(parse_site_ref("48L", &r));
    EXPECT_EQ(r, (SiteRef{48, Site::L}));
    for (const char* bad : {"36XY", "99MB", "19B", "10B", "50MB", "3MB", "36", "36mb", "036MB", "36MB ", " 36MB", ""})
        EXPECT_FALSE(parse_site_ref(bad, &r)) << bad;
    for (int fdi : {11, 27, 36, 47})
        for (Site s : kAllSites) {
            SiteRef back;
            ASSERT_TRUE(parse_site_ref(site_ref_name({fdi, s}), &back));
            EXPECT_EQ(back, (SiteRef{fdi, s}));
        }
    EXPECT_EQ(site_ref_name({36, Site::MB}), "36MB");
}

TEST(Lesson, BundledLessonsLoadWithoutErrors) {
    struct Expect {
        const char* file;
        std::vector<int> teeth;
        std::size_t steps;
        double time_limit_s;
    };
    for (const Expect& x : {Expect{"healthy_11", {11}, 2, 120}, Expect{"periodontitis_36", {36}, 3, 180},
                            Expect{"quadrant_44_47", {44, 45, 46, 47}, 4, 600}}) {
        // No content root given: the parent of lessons/ is the content root.
        const LessonLoad l = load_lesson(kRoot + "/lessons/" + x.file + ".json");
        EXPECT_TRUE(l.ok()) << x.file << "\n" << join(l.errors);
        EXPECT_EQ(l.lesson.teeth, x.teeth) << x.file;
        EXPECT_EQ(l.lesson.steps.size(), x.steps) << x.file;
        EXPECT_EQ(l.lesson.rubric.time_limit_s, x.time_limit_s) << x.file;
        EXPECT_EQ(l.lesson.probe, ProbeKind::Williams);
        EXPECT_EQ(l.lesson.rules.size(), 3u);
        EXPECT_TRUE(fs::path(l.chart_path).is_absolute());
        EXPECT_TRUE(fs::equivalent(l.chart_path, kRoot + "/cases/" + x.file + "/chart.json"));
        // The charting steps take each tooth's sites in the simulated hand's order.
        for (const LessonStep& s : l.lesson.steps) {
            if (s.complete == StepCondition::Acknowledged) continue;
            EXPECT_EQ(s.order, StepOrder::Listed);
            static const std::vector<Site> kHand{Site::MB, Site::B, Site::DB, Site::DL, Site::L, Site::ML};
            std::vector<Site> order;
            for (const SiteRef& r : s.sites) order.push_back(r.site);
            const auto at = std::search(kHand.begin(), kHand.end(), order.begin(), order.end());
            EXPECT_TRUE(at != kHand.end()) << x.file << " step " << s.id;
        }
        EXPECT_EQ(l.lesson.target_sites().size(), 6 * x.teeth.size()) << x.file;
    }
}

TEST(Lesson, PeriodontitisLessonStartsWithTheFurcation) {
    const LessonLoad l = load_lesson(kRoot + "/lessons/periodontitis_36.json", kRoot);
    ASSERT_TRUE(l.ok()) << join(l.errors);
    ASSERT_FALSE(l.lesson.steps.empty());
    EXPECT_EQ(l.lesson.steps[0].id, "furcation");
    EXPECT_EQ(l.lesson.steps[0].complete, StepCondition::Acknowledged);
    EXPECT_TRUE(l.lesson.steps[0].sites.empty());
}

TEST(Lesson, DefaultsAndShorthands) {
    json doc = good_doc();
    doc["case"].erase("teeth");
    const LessonLoad l = parse(doc);
    ASSERT_TRUE(l.ok()) << join(l.errors);
    EXPECT_EQ(l.lesson.teeth, std::vector<int>{11});  // every tooth of the chart
    EXPECT_EQ(l.lesson.probe, ProbeKind::Williams);
    EXPECT_EQ(l.lesson.steps[0].order, StepOrder::Any);
    EXPECT_EQ(l.lesson.steps[0].complete, StepCondition::Charted);
    ASSERT_EQ(l.lesson.steps[1].hints.size(), 1u);
    EXPECT_EQ(l.lesson.steps[1].hints[0].text, "keep parallel");
    EXPECT_EQ(l.lesson.steps[1].hints[0].after_s, 20.0);
    EXPECT_EQ(l.lesson.rules[0].level, RuleLevel::Warning);
    EXPECT_EQ(l.lesson.rules[0].cooldown_s, 1.0);
    EXPECT_EQ(l.lesson.rubric, Rubric{});
}

TEST(Lesson, TargetSitesAreUniqueInFirstListedOrder) {
    Lesson l;
    l.steps.resize(2);
    l.steps[0].sites = {{11, Site::B}, {11, Site::MB}};
    l.steps[1].sites = {{11, Site::MB}, {11, Site::L}, {11, Site::B}};
    EXPECT_EQ(l.target_sites(), (std::vector<SiteRef>{{11, Site::B}, {11, Site::MB}, {11, Site::L}}));
}

TEST(Lesson, BadJsonIsReportedByLineAndColumn) {
    const std::string text = "{\n  \"format\": \"sulcus.lesson/1\",\n  \"title\": tru\n}\n";
    const LessonLoad l = parse_lesson(text, kSource, kRoot);
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_EQ(l.errors[0].rfind("bad.json: line 3, column ", 0), 0u) << l.errors[0];
    EXPECT_EQ(l.errors[0].find('\n'), std::string::npos);
}

TEST(Lesson, UnknownKeysAreErrorsAtEveryLevel) {
    json doc = good_doc();
    doc["colour"] = "red";
    doc["steps"][1]["sitez"] = json::array();
    doc["rubric"] = {{"depth_pass_m", 1.0}};
    doc["rules"][0]["treshold"] = 1;
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: unknown key \"colour\"", "allowed: format, title"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1]: unknown key \"sitez\"", "sites"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric: unknown key \"depth_pass_m\"", "depth_pass_mm"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[0]: unknown key \"treshold\"", "threshold_N"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 4u) << join(l.errors);
}

TEST(Lesson, KeysWrittenTwiceAreErrors) {
    const std::string text = R"({"format": "sulcus.lesson/1", "title": "t",
      "case": {"chart": "cases/healthy_11/chart.json"},
      "steps": [{"id": "a", "instruction": "i", "sites": ["11B"], "id": "b"}], "title": "u"})";
    const LessonLoad l = parse_lesson(text, kSource, kRoot);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].id: written twice"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: title: written twice"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 2u) << join(l.errors);
}

TEST(Lesson, WrongFormatIsRejected) {
    json doc = good_doc();
    doc["format"] = "sulcus.lesson/2";
    LessonLoad l = parse(doc);
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: format: expected \"sulcus.lesson/1\", found \"sulcus.lesson/2\""}));
    doc.erase("format");
    l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: format: missing"})) << join(l.errors);
}

TEST(Lesson, BadSiteRefsNameTheirPlace) {
    json doc = good_doc();
    doc["steps"][0]["sites"] = {"11MB", "36XY", "99MB", 11};
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites[1]: \"36XY\" is not a site"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites[2]: \"99MB\": 99 is not an FDI tooth number"}))
        << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites[3]: expected a site"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 3u) << join(l.errors);
}

TEST(Lesson, TeethMustBeInTheChartAndSitesInTheTeeth) {
    json doc = good_doc();
    doc["case"]["teeth"] = {11, 21};
    doc["steps"][0]["sites"] = {"11MB", "36B"};
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: case.teeth[1]: tooth 21 is not in the chart"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites[1]: \"36B\": tooth 36 is not one of the lesson's teeth"}))
        << join(l.errors);
    EXPECT_EQ(l.errors.size(), 2u) << join(l.errors);
}

TEST(Lesson, StepSitesAreRequiredAndUnique) {
    json doc = good_doc();
    doc["steps"][0].erase("sites");
    doc["steps"][1]["sites"] = {"11DL", "11L", "11DL"};
    doc["steps"].push_back({{"id", "c"}, {"instruction", "read"}, {"complete", "acknowledged"}});
    doc["steps"].push_back({{"id", "d"}, {"instruction", "walk"}, {"complete", "walked"}, {"sites", json::array()}});
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites: missing"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1].sites[2]: \"11DL\" is listed twice"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[3].sites: empty", "\"walked\" step needs target sites"}))
        << join(l.errors);
    EXPECT_EQ(l.errors.size(), 3u) << join(l.errors);  // the acknowledged step needs none
}

TEST(Lesson, DuplicateIdsAreErrors) {
    json doc = good_doc();
    doc["steps"][1]["id"] = "a";
    doc["rules"][1]["id"] = "firm";
    doc["rules"].push_back({{"id", ""}, {"when", "left_sulcus"}, {"message", "m"}});
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1].id: \"a\" is the id of an earlier step"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[1].id: \"firm\" is the id of an earlier rule"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[2].id: must not be empty"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 3u) << join(l.errors);
}

TEST(Lesson, BadEnumsListTheChoices) {
    json doc = good_doc();
    doc["probe"] = "explorer";
    doc["steps"][0]["order"] = "random";
    doc["steps"][0]["complete"] = "done";
    doc["rules"][0]["when"] = "force";
    doc["rules"][1]["level"] = "error";
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: probe: unknown probe \"explorer\"", "\"williams\""})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].order: unknown order \"random\"", "\"any\" or \"listed\""}));
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].complete: unknown condition \"done\"", "\"acknowledged\""}));
    EXPECT_TRUE(has_error(l, {"bad.json: rules[0].when: unknown trigger \"force\"", "\"left_sulcus\""}));
    EXPECT_TRUE(has_error(l, {"bad.json: rules[1].level: unknown level \"error\"", "\"note\" or \"warning\""}));
    EXPECT_EQ(l.errors.size(), 5u) << join(l.errors);
}

TEST(Lesson, RuleThresholdsBelongToForceRules) {
    json doc = good_doc();
    doc["rules"][0].erase("threshold_N");
    doc["rules"][1]["threshold_N"] = 0.3;
    doc["rules"].push_back({{"id", "neg"}, {"when", "force_at_least"}, {"threshold_N", -0.5}, {"message", "m"},
                            {"cooldown_s", -1}});
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[0].threshold_N: missing"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[1].threshold_N: not allowed"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[2].threshold_N: -0.5 is out of range"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules[2].cooldown_s: -1 is out of range"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 4u) << join(l.errors);
}

TEST(Lesson, OutOfRangeRubricValuesAreErrors) {
    json doc = good_doc();
    doc["rubric"] = {{"force_trauma_N", -0.1},
                     {"depth_pass_fraction", 1.5},
                     {"angle_interproximal_min_deg", 25.0},
                     {"max_withdrawals_per_side", 1.5},
                     {"time_limit_s", "long"}};
    doc["steps"][1]["hints"] = {{{"text", "late"}, {"after_s", -3}}};
    LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.force_trauma_N: -0.1 is out of range"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.depth_pass_fraction: 1.5 is out of range (expected from 0 to 1)"}));
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.angle_interproximal_min_deg: 25 is greater than "
                              "angle_interproximal_max_deg (20)"}))
        << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.max_withdrawals_per_side: expected a whole number"}));
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.time_limit_s: expected a number, found \"long\""}));
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1].hints[0].after_s: -3 is out of range"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 6u) << join(l.errors);

    doc = good_doc();
    doc["rubric"] = {{"force_target_min_N", 0.3}};  // above the default maximum 0.25
    l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.force_target_min_N: 0.3 is greater than force_target_max_N"}))
        << join(l.errors);

    doc = good_doc();
    doc["rubric"] = {{"weight_depth", 0}, {"weight_force", 0}, {"weight_angulation", 0}, {"weight_walking", 0},
                     {"weight_withdrawals", 0}, {"weight_completeness", 0}, {"weight_time", 0}};
    l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: rubric: the weights are all zero"})) << join(l.errors);
    doc["rubric"]["weight_time"] = 1;
    EXPECT_TRUE(parse(doc).ok());
}

TEST(Lesson, ListsAndStringsAreSizeLimited) {
    json doc = good_doc();
    doc["title"] = std::string(kMaxLessonText + 1, 'x');
    doc["steps"][1]["hints"] = json::array();
    for (std::size_t i = 0; i <= kMaxStepHints; ++i) doc["steps"][1]["hints"].push_back("h");
    json rules = json::array();
    for (std::size_t i = 0; i <= kMaxLessonRules; ++i)
        rules.push_back({{"id", "r" + std::to_string(i)}, {"when", "left_sulcus"}, {"message", "m"}});
    doc["rules"] = rules;
    LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: title: 2001 characters, longer than the 2000 allowed"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1].hints: 9 hints, more than the 8 allowed"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: rules: 33 rules, more than the 32 allowed"})) << join(l.errors);
    EXPECT_EQ(l.errors.size(), 3u) << join(l.errors);

    doc = good_doc();
    json steps = json::array();
    for (std::size_t i = 0; i <= kMaxLessonSteps; ++i)
        steps.push_back({{"id", "s" + std::to_string(i)}, {"instruction", "i"}, {"sites", {"11B"}}});
    doc["steps"] = steps;
    l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: steps: 201 steps, more than the 200 allowed"})) << join(l.errors);
    doc["steps"] = json::array();
    EXPECT_TRUE(has_error(parse(doc), {"bad.json: steps: empty"}));
}

TEST(Lesson, SeveralFaultsAreReportedTogether) {
    json doc = good_doc();
    doc.erase("title");
    doc["probe"] = 3;
    doc["steps"][0]["sites"][1] = "11Q";
    doc["steps"][1]["order"] = "sideways";
    doc["rules"][0]["level"] = "loud";
    doc["rubric"] = {{"pass_score", 2}};
    const LessonLoad l = parse(doc);
    EXPECT_TRUE(has_error(l, {"bad.json: title: missing"})) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: probe: expected a string, found 3"}));
    EXPECT_TRUE(has_error(l, {"bad.json: steps[0].sites[1]"}));
    EXPECT_TRUE(has_error(l, {"bad.json: steps[1].order"}));
    EXPECT_TRUE(has_error(l, {"bad.json: rules[0].level"}));
    EXPECT_TRUE(has_error(l, {"bad.json: rubric.pass_score"}));
    EXPECT_EQ(l.errors.size(), 6u) << join(l.errors);
}

TEST_F(LessonFiles, MissingFileIsOneLineNamingIt) {
    const std::string path = (dir_ / "lessons/none.json").string();
    const LessonLoad l = load_lesson(path);
    ASSERT_EQ(l.errors.size(), 1u);
    EXPECT_EQ(l.errors[0], path + ": no such file");
}

TEST_F(LessonFiles, ChartPathWithDotDotCannotLeaveTheRoot) {
    const fs::path root = make_root();
    write(dir_ / "outside/chart.json", "{}");  // exists, so only the root rule can reject it
    fs::copy_file(root / "cases/healthy_11/chart.json", dir_ / "outside/chart.json",
                  fs::copy_options::overwrite_existing);
    json doc = good_doc();
    doc["case"]["chart"] = "cases/../../outside/chart.json";
    const LessonLoad l = parse(doc, root.string());
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: case.chart: \"cases/../../outside/chart.json\" is outside the content root " +
                              fs::weakly_canonical(root).string()}))
        << join(l.errors);
    EXPECT_TRUE(l.chart_path.empty());
    // `..` that stays inside is fine.
    doc["case"]["chart"] = "lessons/../cases/healthy_11/chart.json";
    const LessonLoad in = parse(doc, root.string());
    EXPECT_TRUE(in.ok()) << join(in.errors);
    EXPECT_EQ(in.chart_path, fs::weakly_canonical(root / "cases/healthy_11/chart.json").string());
}

TEST_F(LessonFiles, AbsoluteChartPathIsRejected) {
    const fs::path root = make_root();
    json doc = good_doc();
    doc["case"]["chart"] = (root / "cases/healthy_11/chart.json").string();  // even one inside the root
    const LessonLoad l = parse(doc, root.string());
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: case.chart: ", "is an absolute path"})) << join(l.errors);
}

TEST_F(LessonFiles, SymlinkOutOfTheRootIsRejected) {
    const fs::path root = make_root();
    fs::create_directories(dir_ / "elsewhere");
    fs::copy_file(root / "cases/healthy_11/chart.json", dir_ / "elsewhere/chart.json");
    fs::create_directory_symlink(dir_ / "elsewhere", root / "cases/link_out");
    fs::create_directory_symlink(root / "cases/healthy_11", root / "cases/link_in");
    json doc = good_doc();
    doc["case"]["chart"] = "cases/link_out/chart.json";
    const LessonLoad l = parse(doc, root.string());
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: case.chart: \"cases/link_out/chart.json\" is outside the content root"}));
    // A link that stays inside the root is followed.
    doc["case"]["chart"] = "cases/link_in/chart.json";
    const LessonLoad in = parse(doc, root.string());
    EXPECT_TRUE(in.ok()) << join(in.errors);
    EXPECT_EQ(in.chart_path, fs::weakly_canonical(root / "cases/healthy_11/chart.json").string());
}

TEST_F(LessonFiles, MissingOrBrokenChartIsReported) {
    const fs::path root = make_root();
    write(root / "cases/broken/chart.json", R"({"format": "sulcus.chart/1", "teeth": {"11": {"mobility": 9}}})");
    json doc = good_doc();
    doc["case"]["chart"] = "cases/none/chart.json";
    LessonLoad l = parse(doc, root.string());
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_TRUE(has_error(l, {"bad.json: case.chart: \"cases/none/chart.json\" is not a file"}));
    doc["case"]["chart"] = "cases/broken/chart.json";
    l = parse_lesson(doc.dump(), kSource, root.string());
    EXPECT_FALSE(l.ok());
    EXPECT_TRUE(has_error(l, {"cases/broken/chart.json", "mobility"})) << join(l.errors);
}

TEST_F(LessonFiles, DefaultContentRootIsTheParentOfTheLessonsFolder) {
    const fs::path root = make_root();
    write(root / "lessons/mine.json", good_doc().dump(2));
    const LessonLoad l = load_lesson((root / "lessons/mine.json").string());
    EXPECT_TRUE(l.ok()) << join(l.errors);
    EXPECT_EQ(l.chart_path, fs::weakly_canonical(root / "cases/healthy_11/chart.json").string());
    // Moved out of its content root, the same lesson no longer finds its chart.
    write(dir_ / "loose/mine.json", good_doc().dump(2));
    EXPECT_FALSE(load_lesson((dir_ / "loose/mine.json").string()).ok());
}

TEST_F(LessonFiles, HugeFileIsRejectedBeforeParsing) {
    const fs::path root = make_root();
    // A valid lesson padded with whitespace past the limit: only the size can reject it.
    std::string text = good_doc().dump(2);
    text += std::string(kMaxLessonBytes + 1000 - text.size(), ' ');
    const fs::path path = root / "lessons/huge.json";
    write(path, text);
    const LessonLoad l = load_lesson(path.string());
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);
    EXPECT_EQ(l.errors[0], path.string() + ": " + std::to_string(kMaxLessonBytes + 1000) +
                               " bytes, larger than the 262144 allowed for a lesson");
    EXPECT_TRUE(l.lesson.title.empty());
    EXPECT_TRUE(l.lesson.steps.empty());
    EXPECT_TRUE(l.chart_path.empty());
    // Just under the limit it reads.
    text.resize(kMaxLessonBytes);
    write(path, text);
    const LessonLoad fits = load_lesson(path.string());
    EXPECT_TRUE(fits.ok()) << join(fits.errors);
    // parse_lesson holds text to the same limit.
    EXPECT_TRUE(has_error(parse_lesson(text + "  ", kSource, root.string()), {"bytes, larger than the 262144"}));
}

TEST(Lesson, DeepNestingIsRejectedBeforeParsing) {
    json doc = good_doc();
    std::string text = doc.dump();
    text.pop_back();  // the closing brace
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const LessonLoad l = parse_lesson(text + ", \"x\": " + deep + "}", kSource, kRoot);
    ASSERT_EQ(l.errors.size(), 1u) << join(l.errors);  // not the unknown key: nothing was parsed
    EXPECT_TRUE(has_error(l, {"bad.json: line 1, column ", "(byte ", "nested deeper than the 16 levels allowed"}))
        << join(l.errors);
    EXPECT_TRUE(l.lesson.title.empty());
    // Brackets inside strings are text, not nesting.
    doc["description"] = std::string(100, '[') + "\\\"{{{{{{{{{{{{{{{{{{{{";
    const LessonLoad ok = parse(doc);
    EXPECT_TRUE(ok.ok()) << join(ok.errors);
    EXPECT_EQ(ok.lesson.description, doc["description"].get<std::string>());
}

TEST(Lesson, TopLevelMustBeAnObject) {
    const LessonLoad l = parse_lesson("[1, 2]", kSource, kRoot);
    ASSERT_EQ(l.errors.size(), 1u);
    EXPECT_EQ(l.errors[0], "bad.json: expected a JSON object at the top level, found an array");
}

TEST(Lesson, TextThatIsNotJsonIsOneLine) {
    for (const std::string& text : {std::string(""), std::string("{} {}"), std::string("{\"title\": 1e999}"),
                                   std::string("{\"title\": \"\xff\"}"), std::string("{\"a\": 1,}")}) {
        const LessonLoad l = parse_lesson(text, kSource, kRoot);
        ASSERT_EQ(l.errors.size(), 1u) << text << "\n" << join(l.errors);
        expect_one_line_each(l, kSource);
        for (char c : l.errors[0]) EXPECT_LT(static_cast<unsigned char>(c), 0x80u) << l.errors[0];
    }
}

TEST(Lesson, NameFunctionsMatchTheFile) {
    EXPECT_STREQ(step_order_name(StepOrder::Any), "any");
    EXPECT_STREQ(step_order_name(StepOrder::Listed), "listed");
    EXPECT_STREQ(step_condition_name(StepCondition::Charted), "charted");
    EXPECT_STREQ(step_condition_name(StepCondition::Probed), "probed");
    EXPECT_STREQ(step_condition_name(StepCondition::Walked), "walked");
    EXPECT_STREQ(step_condition_name(StepCondition::Acknowledged), "acknowledged");
    EXPECT_STREQ(rule_trigger_name(RuleTrigger::ForceAbove), "force_above");
    EXPECT_STREQ(rule_trigger_name(RuleTrigger::ForceAtLeast), "force_at_least");
    EXPECT_STREQ(rule_trigger_name(RuleTrigger::LeftSulcus), "left_sulcus");
    EXPECT_STREQ(rule_level_name(RuleLevel::Note), "note");
    EXPECT_STREQ(rule_level_name(RuleLevel::Warning), "warning");
}

void expect_equal(const Lesson& a, const Lesson& b) {
    EXPECT_EQ(a.format, b.format);
    EXPECT_EQ(a.title, b.title);
    EXPECT_EQ(a.description, b.description);
    EXPECT_EQ(a.chart, b.chart);
    EXPECT_EQ(a.teeth, b.teeth);
    EXPECT_EQ(a.probe, b.probe);
    ASSERT_EQ(a.steps.size(), b.steps.size());
    for (std::size_t i = 0; i < a.steps.size(); ++i) {
        const LessonStep &s = a.steps[i], &t = b.steps[i];
        EXPECT_EQ(s.id, t.id);
        EXPECT_EQ(s.instruction, t.instruction);
        EXPECT_EQ(s.sites, t.sites);
        EXPECT_EQ(s.order, t.order);
        EXPECT_EQ(s.complete, t.complete);
        ASSERT_EQ(s.hints.size(), t.hints.size());
        for (std::size_t k = 0; k < s.hints.size(); ++k) {
            EXPECT_EQ(s.hints[k].text, t.hints[k].text);
            EXPECT_EQ(s.hints[k].after_s, t.hints[k].after_s);
        }
    }
    ASSERT_EQ(a.rules.size(), b.rules.size());
    for (std::size_t i = 0; i < a.rules.size(); ++i) {
        const LessonRule &r = a.rules[i], &q = b.rules[i];
        EXPECT_EQ(r.id, q.id);
        EXPECT_EQ(r.when, q.when);
        EXPECT_EQ(r.threshold_N, q.threshold_N);
        EXPECT_EQ(r.level, q.level);
        EXPECT_EQ(r.message, q.message);
        EXPECT_EQ(r.cooldown_s, q.cooldown_s);
    }
    EXPECT_EQ(a.rubric, b.rubric);
}

TEST(Lesson, WrittenLessonReadsBackEqual) {
    // Every field away from its default (the threshold of a left_sulcus rule has no meaning and is
    // not written).
    Lesson l;
    l.title = "Round trip \"quoted\" ü";
    l.description = "all fields set";
    l.chart = "cases/quadrant_44_47/chart.json";
    l.teeth = {46, 44};
    l.probe = ProbeKind::Unc15;
    LessonStep a;
    a.id = "one";
    a.instruction = "probe 46";
    a.sites = {{46, Site::DL}, {46, Site::MB}};
    a.order = StepOrder::Listed;
    a.complete = StepCondition::Walked;
    a.hints = {{"slowly", 7.25}, {"parallel", 0.1}};
    LessonStep b;
    b.id = "two";
    b.instruction = "read";
    b.complete = StepCondition::Acknowledged;
    LessonStep c;
    c.id = "three";
    c.instruction = "probe 44";
    c.sites = {{44, Site::L}};
    c.complete = StepCondition::Probed;
    l.steps = {a, b, c};
    l.rules = {{"firm", RuleTrigger::ForceAtLeast, 0.3125, RuleLevel::Note, "firm", 2.5},
               {"out", RuleTrigger::LeftSulcus, 0.25, RuleLevel::Note, "stay", 0.0}};
    Rubric& r = l.rubric;
    r.depth_pass_mm = 1.5;
    r.depth_exact_mm = 0.25;
    r.depth_pass_fraction = 0.9;
    r.force_target_min_N = 0.15;
    r.force_target_max_N = 0.3;
    r.force_warning_N = 0.35;
    r.force_trauma_N = 0.6;
    r.max_time_above_warning_s = 2.0;
    r.angle_direct_max_deg = 12.0;
    r.angle_interproximal_min_deg = 4.0;
    r.angle_interproximal_max_deg = 25.0;
    r.angle_pass_fraction = 0.75;
    r.walk_advance_mm = 1.25;
    r.walk_pass_fraction = 0.7;
    r.max_withdrawals_per_side = 3;
    r.completeness_pass_fraction = 0.9;
    r.time_limit_s = 300.0;
    r.weight_depth = 0.3;
    r.weight_force = 0.1;
    r.weight_angulation = 0.2;
    r.weight_walking = 0.15;
    r.weight_withdrawals = 0.1;
    r.weight_completeness = 0.05;
    r.weight_time = 0.1;
    r.pass_score = 0.1 + 0.2;  // not exactly representable: the writer keeps every bit
    ASSERT_FALSE(r == Rubric{});

    const json doc = lesson_to_json(l);
    EXPECT_EQ(doc["rubric"].size(), 25u);  // every rubric field
    const LessonLoad back = parse_lesson(doc.dump(2), "roundtrip.json", kRoot);
    ASSERT_TRUE(back.ok()) << join(back.errors);
    expect_equal(back.lesson, l);

    // And every bundled lesson survives the trip.
    for (const char* name : {"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        const LessonLoad first = load_lesson(kRoot + "/lessons/" + name + ".json");
        ASSERT_TRUE(first.ok()) << join(first.errors);
        const LessonLoad again = parse_lesson(lesson_to_json(first.lesson).dump(), name, kRoot);
        ASSERT_TRUE(again.ok()) << join(again.errors);
        expect_equal(again.lesson, first.lesson);
    }
}

}  // namespace
}  // namespace sulcus
