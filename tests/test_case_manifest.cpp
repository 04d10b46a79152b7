// Reading a built case's manifest (case.json, sulcus.case/1): the three bundled cases the build
// makes read back with every site frame and pass, in agreement with their charts; damaged
// manifests give one line per fault naming the file and the place.
#include "sulcus/content/case_manifest.h"
#include "sulcus/engine/json_text.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

namespace sulcus {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string case_dir(const std::string& name) { return std::string(SULCUS_BINARY_DIR) + "/cases/" + name; }

json read_json(const std::string& path) {
    std::string text, why;
    json j;
    EXPECT_TRUE(textio::read_file(path, text, why)) << why;
    EXPECT_TRUE(textio::parse_json(path, text, j, why)) << why;
    return j;
}

Vec3 vec(const json& j) { return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }
bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }

class BundledManifest : public ::testing::TestWithParam<const char*> {};

TEST_P(BundledManifest, ReadsEverySiteAndPassInAgreementWithTheChart) {
    const std::string dir = case_dir(GetParam());
    const CaseManifestLoad l = load_case_manifest(dir);
    ASSERT_TRUE(l.ok()) << l.errors.front();
    const CaseManifest& m = l.manifest;
    EXPECT_EQ(m.dir, dir);
    EXPECT_EQ(m.scene, "scene.json");
    EXPECT_EQ(m.visual, "case.glb");
    EXPECT_EQ(m.probe, "williams");

    // The chart is the one the case was built from.
    const ChartLoad source =
        load_chart(std::string(SULCUS_SOURCE_DIR) + "/content/assets/cases/" + GetParam() + "/chart.json");
    ASSERT_TRUE(source.ok());
    EXPECT_EQ(m.chart, source.chart);

    // Six frames and six passes per tooth, one per charted site.
    ASSERT_EQ(m.sites.size(), 6 * m.chart.teeth.size());
    ASSERT_EQ(m.passes.size(), m.sites.size());
    std::set<std::pair<int, Site>> frames, passes;
    const json raw = read_json(dir + "/case.json");
    for (std::size_t i = 0; i < m.sites.size(); ++i) {
        const SiteFrame& f = m.sites[i];
        const json& r = raw["sites"][i];
        SCOPED_TRACE(std::to_string(f.fdi) + " " + site_name(f.site));
        frames.insert({f.fdi, f.site});
        const SiteRecord& rec = *m.chart.teeth.at(f.fdi).sites[std::size_t(f.site)];
        // Millimetres became metres; the values are the chart's.
        EXPECT_NEAR(f.pd_m, rec.pd_mm * 1e-3, 1e-15);
        EXPECT_NEAR(f.gm_m, rec.gm_mm * 1e-3, 1e-15);
        EXPECT_EQ(f.tissue, site_tissue(rec));
        // Points come back to the bit as written.
        EXPECT_TRUE(same_bits(f.margin_point, vec(r["margin_point"])));
        EXPECT_TRUE(same_bits(f.floor_point, vec(r["floor_point"])));
        EXPECT_TRUE(same_bits(f.onset_point, vec(r["onset_point"])));
        EXPECT_EQ(f.theta_rad, r["theta_rad"].get<double>());
        EXPECT_EQ(f.floor_half_width_m, r["floor_half_width_m"].get<double>());
        EXPECT_GT(f.floor_half_width_m, 0.0);
        // The frame's geometry: the charted floor pd below the margin on the axis, the onset
        // between them, outward across the axis, and the tip resting at least pd deep.
        EXPECT_NEAR(glm::dot(f.margin_point - f.floor_point, f.axis), f.pd_m, 1e-9);
        EXPECT_NEAR(glm::length(glm::cross(f.margin_point - f.floor_point, f.axis)), 0.0, 1e-9);
        const double onset = glm::dot(f.margin_point - f.onset_point, f.axis);
        EXPECT_GE(onset, -1e-12);
        EXPECT_LE(onset, f.pd_m + 1e-12);
        EXPECT_NEAR(glm::dot(f.outward, f.axis), 0.0, 1e-9);
        EXPECT_NEAR(f.rest_depth_m, r["depth_at_0_25_N_mm"].get<double>() * 1e-3, 1e-15);
        EXPECT_GE(f.rest_depth_m, f.pd_m - 1e-12);
    }
    EXPECT_EQ(frames.size(), m.sites.size());  // no site twice
    double last_end = 0.0;
    for (const ProbingPass& p : m.passes) {
        passes.insert({p.fdi, p.site});
        EXPECT_LE(p.t_start, p.t_floor);
        EXPECT_LE(p.t_floor, p.t_end);
        EXPECT_GE(p.t_start, last_end);  // one after another
        last_end = p.t_end;
        EXPECT_GT(p.past_floor_m, 0.0);
        EXPECT_LT(p.past_floor_m, 3e-3);
    }
    EXPECT_EQ(passes, frames);

    // The manifest's own path reads the same.
    const CaseManifestLoad by_file = load_case_manifest(dir + "/case.json");
    ASSERT_TRUE(by_file.ok());
    EXPECT_EQ(by_file.manifest.chart, m.chart);
    EXPECT_EQ(by_file.manifest.sites.size(), m.sites.size());
}

INSTANTIATE_TEST_SUITE_P(Cases, BundledManifest, ::testing::Values("healthy_11", "periodontitis_36", "quadrant_44_47"));

TEST(CaseManifest, ThePeriodontitisCaseHasItsDeepInflamedSites) {
    const CaseManifestLoad l = load_case_manifest(case_dir("periodontitis_36"));
    ASSERT_TRUE(l.ok()) << l.errors.front();
    int inflamed = 0;
    double deepest = 0.0;
    for (const SiteFrame& f : l.manifest.sites) {
        inflamed += f.tissue == Tissue::of(TissuePreset::Inflamed);
        deepest = std::max(deepest, f.pd_m);
    }
    EXPECT_GT(inflamed, 0);
    EXPECT_GE(deepest, 5e-3);
}

// A copy of healthy_11's manifest and chart in a folder of its own, to damage.
class DamagedManifest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = (fs::temp_directory_path() / ("test_case_manifest_" + std::to_string(::getpid()))).string();
        fs::create_directories(dir_);
        fs::copy_file(case_dir("healthy_11") + "/chart.json", dir_ + "/chart.json", fs::copy_options::overwrite_existing);
        doc_ = read_json(case_dir("healthy_11") + "/case.json");
        path_ = dir_ + "/case.json";
    }
    void TearDown() override { fs::remove_all(dir_); }
    void write(const std::string& text) const { std::ofstream(path_, std::ios::binary) << text; }
    CaseManifestLoad load(const json& doc) const {
        write(doc.dump(2));
        return load_case_manifest(dir_);
    }
    // The load failed with exactly these lines.
    static void expect_errors(const CaseManifestLoad& l, const std::vector<std::string>& lines) {
        EXPECT_FALSE(l.ok());
        EXPECT_EQ(l.errors, lines);
        for (const std::string& e : l.errors) EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    std::string dir_, path_;
    json doc_;
};

TEST_F(DamagedManifest, TheUndamagedCopyReads) {
    const CaseManifestLoad l = load(doc_);
    ASSERT_TRUE(l.ok()) << l.errors.front();
    EXPECT_EQ(l.manifest.sites.size(), 6u);
}

TEST_F(DamagedManifest, BadJsonGivesLineAndColumn) {
    write("{\"format\": \"sulcus.case/1\",\n  \"sites\": [1, 2,,]}");
    const CaseManifestLoad l = load_case_manifest(dir_);
    ASSERT_EQ(l.errors.size(), 1u);
    EXPECT_EQ(l.errors[0].rfind(path_ + ": line 2, column ", 0), 0u) << l.errors[0];
}

TEST_F(DamagedManifest, MissingFileAndMissingKeys) {
    EXPECT_EQ(load_case_manifest(dir_ + "/nowhere").errors,
              std::vector<std::string>{dir_ + "/nowhere: file not found"});
    doc_["sites"][0].erase("floor_point");
    doc_["passes"][5].erase("t_floor");
    doc_.erase("chart");
    expect_errors(load(doc_), {path_ + ": chart: missing (the chart file's name)",
                               path_ + ": sites[0].floor_point: missing",
                               path_ + ": passes[5].t_floor: missing"});
    doc_.erase("format");
    expect_errors(load(doc_), {path_ + ": format: missing (expected \"sulcus.case/1\")"});
}

TEST_F(DamagedManifest, WrongTypesNameThePlace) {
    doc_["sites"][3]["axis"] = {0.0, 1.0};
    doc_["sites"][1]["pd_mm"] = "2";
    doc_["sites"][4]["outward"] = {0.0, 2.0, 0.0};
    doc_["sites"][5]["tissue"] = "soggy";
    doc_["passes"][2]["t_end"] = nullptr;
    expect_errors(load(doc_), {path_ + ": sites[1].pd_mm: expected a number in [0, 15], found '\"2\"'",
                               path_ + ": sites[3].axis: expected 3 numbers, found '[0.0,1.0]'",
                               path_ + ": sites[4].outward: expected a unit vector, its length is 2",
                               path_ + ": sites[5].tissue: unknown tissue 'soggy' (expected \"healthy\" or \"inflamed\")",
                               path_ + ": passes[2].t_end: expected a number >= 0, found 'null'"});
    json d = doc_;
    d["sites"] = json::object();
    d["passes"][0] = 7;
    const CaseManifestLoad l = load(d);
    EXPECT_EQ(l.errors.at(0), path_ + ": sites: expected an array, found '{}'");
    EXPECT_EQ(l.errors.at(1), path_ + ": passes[0]: expected an object (a probing pass), found '7'");
}

TEST_F(DamagedManifest, UnknownSiteNameAndSitesNotInTheChart) {
    doc_["sites"][2]["site"] = "XB";
    doc_["passes"][1]["site"] = "MX";
    expect_errors(load(doc_), {path_ + ": sites[2].site: unknown site 'XB' (expected MB, B, DB, ML, L or DL)",
                               path_ + ": passes[1].site: unknown site 'MX' (expected MB, B, DB, ML, L or DL)"});
    json d = doc_;
    d["sites"][2]["site"] = "B";  // B twice, DB lost
    d["passes"][1]["site"] = "B";
    d["sites"][0]["fdi"] = 21;    // a tooth the chart does not have
    expect_errors(load(d), {path_ + ": sites[0]: site 21 MB is not in the chart",
                            path_ + ": sites[2]: site 11 B appears twice",
                            path_ + ": passes[0]: site 11 MB has no frame in sites",
                            path_ + ": passes[2]: site 11 DB has no frame in sites"});
}

TEST_F(DamagedManifest, ChartMissingOrDamaged) {
    fs::remove(dir_ + "/chart.json");
    const std::string chart = (fs::path(dir_) / "chart.json").string();
    expect_errors(load(doc_), {path_ + ": chart: cannot read '" + chart + "': file not found"});
    // The chart's own faults come from the chart reader, naming chart.json and its place.
    std::ofstream(chart) << R"({"format": "sulcus.chart/1", "teeth": {"11": {"sites": {"MB": {"pd_mm": -2}}}}})";
    const CaseManifestLoad l = load(doc_);
    ASSERT_EQ(l.errors.size(), 1u);
    EXPECT_EQ(l.errors[0], chart + ": /teeth/11/sites/MB/pd_mm: expected a number in [0, 15] mm, found '-2'");
}

}  // namespace
}  // namespace sulcus
