// The periodontal chart `sulcus.chart/1` (DESIGN.md, docs/chart-format.md): per FDI tooth, the six
// sites with probing depth, gingival margin and bleeding, plus mobility and furcation grades.
// Authored (reference) and recorded (trainee) charts share this shape.
#pragma once

#include "sulcus/content/tissue.h"
#include "sulcus/content/tooth.h"

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sulcus {

struct SiteRecord {
    double pd_mm = 0.0;   // probing depth: gingival margin to the pocket floor
    double gm_mm = 0.0;   // gingival margin relative to the CEJ (negative = recession, apical)
    bool bop = false;     // bleeding on probing
    bool suppuration = false;
    bool plaque = false;
    bool calculus = false;
    // Tissue of the pocket floor as authored; absent = by bleeding (site_tissue).
    std::optional<Tissue> tissue;
    double cal_mm() const { return pd_mm - gm_mm; }  // clinical attachment level
    bool operator==(const SiteRecord&) const = default;
};

// The floor tissue of a site: as authored, else "inflamed" when it bleeds on probing and
// "healthy" when it does not.
Tissue site_tissue(const SiteRecord& site);

struct ToothRecord {
    int fdi = 0;
    std::array<std::optional<SiteRecord>, 6> sites;  // indexed by Site
    int mobility = 0;                                // 0-3 (Miller classes)
    std::map<FurcationSide, int> furcation;          // grade 0-4 (Glickman; Hamp I-III = 1-3)
    bool operator==(const ToothRecord&) const = default;
};

struct Chart {
    std::map<int, ToothRecord> teeth;  // keyed by FDI
    bool operator==(const Chart&) const = default;
};

struct ChartLoad {
    Chart chart;
    std::vector<std::string> errors;    // one line each: "file: place: what is wrong"
    std::vector<std::string> warnings;  // unknown keys
    bool ok() const { return errors.empty(); }
};

inline constexpr const char* kChartFormat = "sulcus.chart/1";
// Limits a chart value must respect, millimetres.
inline constexpr double kMaxProbingDepthMm = 15.0;
inline constexpr double kMinGingivalMarginMm = -12.0;  // recession
inline constexpr double kMaxGingivalMarginMm = 8.0;    // enlargement

ChartLoad load_chart(const std::string& path);
// `source` names the input in messages (a file name).
ChartLoad parse_chart(const nlohmann::json& doc, const std::string& source);
nlohmann::json chart_to_json(const Chart& chart);
const char* furcation_side_name(FurcationSide s);
// Furcation entrances a tooth has (empty for single-rooted teeth).
std::vector<FurcationSide> furcation_sides(int fdi);

// Checks that a chart can become a case: every tooth supported by the generator, all six sites
// charted. Appends "source: place: what" lines.
void check_chart_for_case(const Chart& chart, const std::string& source, std::vector<std::string>& errors);

}  // namespace sulcus
