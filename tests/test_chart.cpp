// The periodontal chart format: reading, every fault reported with its place, writing back.
#include "sulcus/content/chart.h"
#include "sulcus/content/tissue.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cmath>
#include <set>

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

TEST(Tissue, PresetsAreTheDocumentedCurves) {
    using Pts = std::vector<std::array<double, 2>>;
    EXPECT_EQ(tissue_preset_curve(TissuePreset::Healthy).points_N_mm, (Pts{{0, 0}, {0.25, 0.05}, {0.5, 0.08}, {1.0, 0.12}}));
    EXPECT_EQ(tissue_preset_curve(TissuePreset::Inflamed).points_N_mm, (Pts{{0, 0}, {0.25, 0.5}, {0.5, 1.0}, {1.0, 1.25}}));
    for (TissuePreset p : kAllTissuePresets) {
        EXPECT_EQ(validate_yield_curve(tissue_preset_curve(p)), "") << tissue_preset_name(p);
        TissuePreset back = p == TissuePreset::Healthy ? TissuePreset::Inflamed : TissuePreset::Healthy;
        ASSERT_TRUE(parse_tissue_preset(tissue_preset_name(p), &back));
        EXPECT_EQ(back, p);
    }
    TissuePreset out = TissuePreset::Inflamed;
    for (const char* bad : {"", "Healthy", "inflammed", "custom"}) EXPECT_FALSE(parse_tissue_preset(bad, &out)) << bad;
    EXPECT_EQ(out, TissuePreset::Inflamed);
    // Reference §1.3: the healthy tip barely moves past its resting depth; inflamed tissue lets it
    // on by about 0.5 mm between 0.25 and 0.5 N (Fowler: 0.45 mm into connective tissue).
    const YieldCurve& h = tissue_preset_curve(TissuePreset::Healthy);
    const YieldCurve& i = tissue_preset_curve(TissuePreset::Inflamed);
    EXPECT_LT(h.depth_mm_at(0.5) - h.depth_mm_at(0.25), 0.05);
    EXPECT_NEAR(i.depth_mm_at(0.5) - i.depth_mm_at(0.25), 0.5, 1e-12);
}

TEST(Tissue, DepthInterpolatesAndExtrapolatesWithTheLastSlope) {
    const YieldCurve& i = tissue_preset_curve(TissuePreset::Inflamed);
    EXPECT_EQ(i.depth_mm_at(0.0), 0.0);
    EXPECT_EQ(i.depth_mm_at(-1.0), 0.0);
    EXPECT_NEAR(i.depth_mm_at(0.125), 0.25, 1e-15);
    EXPECT_NEAR(i.depth_mm_at(0.25), 0.5, 1e-15);
    EXPECT_NEAR(i.depth_mm_at(0.75), 1.125, 1e-15);
    EXPECT_NEAR(i.depth_mm_at(1.0), 1.25, 1e-15);
    EXPECT_NEAR(i.depth_mm_at(2.0), 1.75, 1e-12);  // last slope 2 N/mm
    EXPECT_NEAR(i.depth_m_at(0.5), 1.0e-3, 1e-18);
    const YieldCurve& h = tissue_preset_curve(TissuePreset::Healthy);
    EXPECT_NEAR(h.depth_mm_at(0.375), 0.065, 1e-15);
    EXPECT_NEAR(h.depth_mm_at(1.5), 0.16, 1e-12);  // last slope 12.5 N/mm
    // Monotone and continuous.
    double last = 0.0;
    for (double f = 0.0; f <= 3.0; f += 0.01) {
        EXPECT_GE(h.depth_mm_at(f), last - 1e-15);
        EXPECT_LT(h.depth_mm_at(f) - last, 0.01 / 5.0 + 1e-12);  // never softer than the first slope
        last = h.depth_mm_at(f);
    }
}

TEST(Tissue, ValidationNamesTheOffendingPoint) {
    auto check = [](std::vector<std::array<double, 2>> pts, int expected_point, const std::string& words) {
        int bad = -2;
        const std::string why = validate_yield_curve(YieldCurve{std::move(pts)}, &bad);
        EXPECT_NE(why.find(words), std::string::npos) << why;
        EXPECT_EQ(bad, expected_point) << why;
        EXPECT_EQ(why.find('\n'), std::string::npos);
    };
    check({{0, 0}}, -1, "at least two");
    check({{0, 0.1}, {1, 1}}, 0, "[0, 0]");
    check({{0, 0}, {0.5, 0.5}, {0.5, 0.7}}, 2, "force must increase");
    check({{0, 0}, {0.5, 0.5}, {0.7, 0.5}}, 2, "depth must increase");
    check({{0, 0}, {0.5, 0.5}, {0.6, 1.0}}, 2, "stiffen");
    check({{0, 0}, {0.5, std::nan("")}}, 1, "finite");
    int bad = 5;
    EXPECT_EQ(validate_yield_curve(YieldCurve{{{0, 0}, {0.1, 0.1}, {0.2, 0.2}}}, &bad), "");  // equal slopes
    EXPECT_EQ(bad, -1);
}

TEST(ChartTissue, ReadsPresetsAndCurvesAndWritesThemBack) {
    json j = valid();
    j["teeth"]["36"]["sites"]["B"]["tissue"] = "inflamed";
    j["teeth"]["36"]["sites"]["DB"]["tissue"] = "healthy";
    j["teeth"]["36"]["sites"]["ML"]["tissue"] = {{"yield_curve_N_mm", {{0, 0}, {0.3, 0.2}, {1.0, 0.5}}}};
    const ChartLoad l = parse_chart(j, "c.json");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    EXPECT_TRUE(l.warnings.empty());
    const ToothRecord& t = l.chart.teeth.at(36);
    ASSERT_TRUE(t.sites[size_t(Site::B)]->tissue.has_value());
    EXPECT_EQ(*t.sites[size_t(Site::B)]->tissue, Tissue::of(TissuePreset::Inflamed));
    EXPECT_EQ(*t.sites[size_t(Site::DB)]->tissue, Tissue::of(TissuePreset::Healthy));
    const Tissue& ml = *t.sites[size_t(Site::ML)]->tissue;
    EXPECT_FALSE(ml.is_preset);
    EXPECT_EQ(ml.custom.points_N_mm, (std::vector<std::array<double, 2>>{{0, 0}, {0.3, 0.2}, {1.0, 0.5}}));
    EXPECT_FALSE(t.sites[size_t(Site::MB)]->tissue.has_value());

    // Written back: presets by name, curves as curves, an absent tissue stays absent.
    const json out = chart_to_json(l.chart);
    EXPECT_EQ(out["teeth"]["36"]["sites"]["B"]["tissue"], "inflamed");
    EXPECT_EQ(out["teeth"]["36"]["sites"]["DB"]["tissue"], "healthy");
    EXPECT_EQ(out["teeth"]["36"]["sites"]["ML"]["tissue"]["yield_curve_N_mm"], j["teeth"]["36"]["sites"]["ML"]["tissue"]["yield_curve_N_mm"]);
    EXPECT_FALSE(out["teeth"]["36"]["sites"]["MB"].contains("tissue"));
    EXPECT_FALSE(out["teeth"]["11"]["sites"]["B"].contains("tissue"));
    const ChartLoad again = parse_chart(out, "again.json");
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again.chart, l.chart);
}

TEST(ChartTissue, DefaultsToInflamedWhereItBleedsAndHealthyWhereNot) {
    const ChartLoad l = parse_chart(valid(), "c.json");
    ASSERT_TRUE(l.ok());
    const ToothRecord& t = l.chart.teeth.at(36);
    EXPECT_TRUE(t.sites[size_t(Site::MB)]->bop);
    EXPECT_EQ(site_tissue(*t.sites[size_t(Site::MB)]), Tissue::of(TissuePreset::Inflamed));
    EXPECT_FALSE(t.sites[size_t(Site::B)]->bop);
    EXPECT_EQ(site_tissue(*t.sites[size_t(Site::B)]), Tissue::of(TissuePreset::Healthy));
    // An authored tissue wins over bleeding, both ways.
    SiteRecord bleeding = *t.sites[size_t(Site::MB)];
    bleeding.tissue = Tissue::of(TissuePreset::Healthy);
    EXPECT_EQ(site_tissue(bleeding), Tissue::of(TissuePreset::Healthy));
    SiteRecord dry = *t.sites[size_t(Site::B)];
    dry.tissue = Tissue::of(TissuePreset::Inflamed);
    EXPECT_EQ(site_tissue(dry), Tissue::of(TissuePreset::Inflamed));
}

TEST(ChartTissue, ReportsBadTissuesWithTheirPlace) {
    json j = valid();
    auto& sites = j["teeth"]["36"]["sites"];
    sites["MB"]["tissue"] = "swollen";
    sites["B"]["tissue"] = 3;
    sites["DB"]["tissue"] = {{"yield_curve_N_mm", {{0, 0}, {0.5, 0.4}, {0.4, 0.8}}}};   // force falls
    sites["ML"]["tissue"] = {{"yield_curve_N_mm", {{0, 0}, {0.5, 1.0}, {1.0, 1.1}, {1.5, 1.9}}}};  // softens
    sites["L"]["tissue"] = {{"yield_curve_N_mm", {{0.1, 0}, {0.5, 1.0}}}};  // not from [0, 0]
    sites["DL"]["tissue"] = {{"curve", {{0, 0}, {1, 1}}}};                    // key missing
    j["teeth"]["11"]["sites"]["B"]["tissue"] = {{"yield_curve_N_mm", {{0, 0}, {"a", 1}}}};
    const ChartLoad l = parse_chart(j, "c.json");
    EXPECT_TRUE(any_error_has(l, "c.json: /teeth/36/sites/MB/tissue", "unknown tissue"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/B/tissue", "expected \"healthy\""));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/DB/tissue/yield_curve_N_mm/2", "force must increase"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/ML/tissue/yield_curve_N_mm/3", "stiffen"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/L/tissue/yield_curve_N_mm/0", "[0, 0]"));
    EXPECT_TRUE(any_error_has(l, "/teeth/36/sites/DL/tissue/yield_curve_N_mm", "missing"));
    EXPECT_TRUE(any_error_has(l, "/teeth/11/sites/B/tissue/yield_curve_N_mm/1", "[force N, depth mm]"));
    EXPECT_EQ(l.errors.size(), 7u);
    ASSERT_EQ(l.warnings.size(), 1u);  // the unknown "curve" key
    EXPECT_NE(l.warnings[0].find("/teeth/36/sites/DL/tissue/curve"), std::string::npos);
    for (const std::string& e : l.errors) EXPECT_EQ(e.find('\n'), std::string::npos);
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
    // The bundled cases carry both floor tissues, and periodontitis_36 names some explicitly.
    std::set<std::string> tissues;
    int explicit_36 = 0;
    for (const char* name : {"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        const ChartLoad l = load_chart(std::string(SULCUS_SOURCE_DIR) + "/content/assets/cases/" + name + "/chart.json");
        for (const auto& [fdi, t] : l.chart.teeth)
            for (const auto& s : t.sites) {
                if (!s) continue;
                tissues.insert(site_tissue(*s).label());
                if (std::string(name) == "periodontitis_36") explicit_36 += s->tissue.has_value();
            }
    }
    EXPECT_TRUE(tissues.count("healthy") && tissues.count("inflamed"));
    EXPECT_GE(explicit_36, 3);
}

}  // namespace
}  // namespace sulcus
