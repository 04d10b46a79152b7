// Reading a built case back: `case.json` (sulcus.case/1, written by write_case) with its site
// frames and probing passes, and the chart it names (docs/cases.md). What the desktop app and the
// lesson runtime need to know where each site is without rebuilding the case.
#pragma once

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace sulcus {

inline constexpr const char* kCaseFormat = "sulcus.case/1";

struct CaseManifest {
    std::string dir;                  // the case's folder (the manifest's own folder)
    Chart chart;                      // the chart the manifest names, read with the chart reader
    std::vector<SiteFrame> sites;     // in file order (six per tooth, kAllSites order)
    std::vector<ProbingPass> passes;  // in file order (the trajectory's order)
    // The other files the manifest names, as written (relative to `dir`), and the probe's name.
    std::string scene, visual, probe;
};

struct CaseManifestLoad {
    CaseManifest manifest;
    // One line each: "file: JSON path: what is wrong", the path written as `sites[3].axis`
    // (the chart's own faults come in the chart reader's form, naming chart.json).
    std::vector<std::string> errors;
    bool ok() const { return errors.empty(); }
};

// `case_dir_or_json_path`: a case folder (its case.json is read) or the manifest file itself.
// Every fault is reported, not only the first. Site values come back in SI: pd_mm and gm_mm as
// pd_m and gm_m; rest_depth_m from depth_at_0_25_N_mm, or pd_m when the file has none.
CaseManifestLoad load_case_manifest(const std::string& case_dir_or_json_path);
// The same for a parsed document: `source` names it in messages, `dir` is where the chart is.
CaseManifestLoad parse_case_manifest(const nlohmann::json& doc, const std::string& source, const std::string& dir);

}  // namespace sulcus
