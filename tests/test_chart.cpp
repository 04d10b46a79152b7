// The periodontal chart format: reading, every fault reported with its place, writing back.
#include "sulcus/content/chart.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace sulcus {
namespace {

using json = nlohmann::json;

json valid() {
    return json::parse(R"({"format": "sulcus.chart/1", "teeth": {
        "36": {"sites": {"MB": {"pd_mm": 6, "gm_mm": -1, "bop": true}, "B": {"pd_mm": 7, "gm_mm": -1.5},
                         "DB": {"pd_mm": 6}, "ML": {"pd_mm": 5}, "L": {"pd_mm": 5, "calculus": true},
                         "DL": {"pd_mm": 6}},
               "mobility": 1, "furcation": {"B": 2, "L": 1}},
        "11": {"sites": {"B": {"pd_mm": 1.5, "gm_mm": 0.5}}}}})");
}

bool any_error_has(const ChartLoad& l, const std::string& a, const std::string& b) {
    for (const std::string& e : l.errors)
        if (e.find(a) != std::string::npos && e.find(b) != std::string::npos) return true;
    return false;
}

TEST(Chart, ReadsEveryField) {
    const ChartLoad l = parse_chart(valid(), "c.json");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    const ToothRecord& t = l.chart.teeth.at(36);
    EXPECT_EQ(t.mobility, 1);
    EXPECT_EQ(t.furcation.at(FurcationSide::B), 2);
    EXPECT_EQ(t.furcation.at(FurcationSide::L), 1);
    const SiteRecord& mb = *t.sites[size_t(Site::MB)];
    EXPECT_DOUBLE_EQ(mb.pd_mm, 6.0);
    EXPECT_DOUBLE_EQ(mb.gm_mm, -1.0);
    EXPECT_DOUBLE_EQ(mb.cal_mm(), 7.0);
    EXPECT_TRUE(mb.bop);
    EXPECT_TRUE(t.sites[size_t(Site::L)]->calculus);
    EXPECT_FALSE(l.chart.teeth.at(11).sites[size_t(Site::MB)].has_value());
}

TEST(Chart, WritesWhatItReads) {
    const ChartLoad l = parse_chart(valid(), "c.json");
    ASSERT_TRUE(l.ok());
    const ChartLoad again = parse_chart(chart_to_json(l.chart), "again.json");
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again.chart, l.chart);
}

TEST(Chart, ReportsEveryFaultWithItsPlace) {
    json j = valid();
    j["teeth"]["36"]["sites"]["MB"]["pd_mm"] = -1;
    j["teeth"]["36"]["sites"]["XX"] = {{"pd_mm", 2}};
    j["teeth"]["36"]["furcation"]["M"] = 2;  // lower molars have no mesial entrance
    j["teeth"]["36"]["mobility"] = 7;
    j["teeth"]["11"]["sites"]["B"]["bop"] = "yes";
    j["teeth"]["11"]["furcation"] = {{"B", 1}};  // single root
    j["teeth"]["19"] = {{"sites", json::object()}};
    j["teeth"]["36"]["sites"]["L"].erase("pd_mm");
    const ChartLoad l = parse_chart(j, "c.json");
    EXPECT_FALSE(l.ok());
    EXPECT_TRUE(any_error_has(l, "c.json: /teeth/36/sites/MB/pd_mm", "[0, 15]"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/XX", "unknown site"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/furcation/M", "no M furcation"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/mobility", "0-3"));
    EXPECT_TRUE(any_error_has(l, "/teeth/11/sites/B/bop", "true or false"));
    EXPECT_TRUE(any_error_has(l, "/teeth/11/furcation/B", "single root"));
    EXPECT_TRUE(any_error_has(l, "/teeth/19", "FDI"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/L/pd_mm", "missing"));
    EXPECT_EQ(l.errors.size(), 8u);
    for (const std::string& e : l.errors) EXPECT_EQ(e.find('\n'), std::string::npos);
}

TEST(Chart, RejectsOtherFormatsAndWarnsOnUnknownKeys) {
    json j = valid();
    j["format"] = "sulcus.chart/2";
    EXPECT_TRUE(any_error_has(parse_chart(j, "c.json"), "/format", "unknown format"));
    j = valid();
    j["teeth"]["36"]["colour"] = "red";
    const ChartLoad l = parse_chart(j, "c.json");
    EXPECT_TRUE(l.ok());
    ASSERT_EQ(l.warnings.size(), 1u);
    EXPECT_NE(l.warnings[0].find("/teeth/36/colour"), std::string::npos);
}

TEST(Chart, SyntaxErrorsNameTheLine) {
    const std::string path = (std::filesystem::temp_directory_path() / "sulcus_bad_chart.json").string();
    {
        std::ofstream f(path);
        f << "{\n  \"format\": \"sulcus.chart/1\",\n  \"teeth\": {,}\n}\n";
    }
    const ChartLoad l = load_chart(path);
    ASSERT_EQ(l.errors.size(), 1u);
    EXPECT_NE(l.errors[0].find(path + ": line 3"), std::string::npos) << l.errors[0];
    std::filesystem::remove(path);
    const ChartLoad missing = load_chart(path);
    ASSERT_EQ(missing.errors.size(), 1u);
    EXPECT_NE(missing.errors[0].find("file not found"), std::string::npos);
}

TEST(Chart, CaseNeedsSupportedTeethAndAllSites) {
    const ChartLoad l = parse_chart(valid(), "c.json");
    std::vector<std::string> errors;
    check_chart_for_case(l.chart, "c.json", errors);
    // Tooth 11 charts one site only: five missing.
    EXPECT_EQ(errors.size(), 5u);
    Chart c = l.chart;
    c.teeth.erase(11);
    ToothRecord t18 = c.teeth.at(36);
    t18.fdi = 18;
    c.teeth[18] = t18;
    errors.clear();
    check_chart_for_case(c, "c.json", errors);
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("/teeth/18"), std::string::npos);
}

TEST(Chart, BundledCasesAreValidAndBuildable) {
    for (const char* name : {"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        const std::string path = std::string(SULCUS_SOURCE_DIR) + "/content/assets/cases/" + name + "/chart.json";
        const ChartLoad l = load_chart(path);
        ASSERT_TRUE(l.ok()) << l.errors.front();
        EXPECT_TRUE(l.warnings.empty()) << l.warnings.front();
        std::vector<std::string> errors;
        check_chart_for_case(l.chart, path, errors);
        EXPECT_TRUE(errors.empty()) << errors.front();
    }
}

}  // namespace
}  // namespace sulcus
