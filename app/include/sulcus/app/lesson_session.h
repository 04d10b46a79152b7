// A lesson session without a window: finding the built case a lesson runs on, recording a session
// with the simulated hand, and replaying a recorded session to recompute its scores bit for bit
// (docs/lessons.md). What `sulcus-cli lesson` and `sulcus-cli replay` run, and what the app uses
// to load a lesson.
#pragma once

#include "sulcus/app/lesson.h"
#include "sulcus/app/lesson_runtime.h"
#include "sulcus/app/scoring.h"
#include "sulcus/app/write_file.h"
#include "sulcus/content/case_manifest.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"
#include "sulcus/haptics/recording.h"

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sulcus {

// Name of the recording annex holding the scores computed when the session ended.
inline constexpr const char* kScoresAnnex = "scores";
inline constexpr const char* kReportFormat = "sulcus.report/1";

// The built case of a lesson: <cases_dir>/<name of the chart's folder>/, whose chart.json must
// equal the lesson's chart and whose probe must be the lesson's.
struct LessonCase {
    std::string dir;
    CaseManifest manifest;
    SceneLoad scene;
    std::shared_ptr<Model> model;
    std::string error;  // one line naming the file; empty when loaded
    bool ok() const { return error.empty(); }
};
LessonCase load_lesson_case(const LessonLoad& lesson, const std::string& cases_dir);

// The content root and the built cases next to a running binary: <binary>/../../content/assets
// when the binary runs from a build tree of the sources, and <binary>/../cases.
std::string default_cases_dir();
std::string default_content_root();

// Force on the tissue over a session, as the maximum in each bin of `bin_s` (for plots).
struct ForceTrace {
    double bin_s = 0.05;
    std::vector<double> max_N;
};

// Everything a session's report holds.
struct LessonOutcome {
    std::string lesson_path;     // as given or as named by the recording
    Lesson lesson;
    std::string case_dir;
    RecordingMetadata metadata;
    uint64_t ticks = 0;
    int64_t first_mismatch = -1; // first tick whose replayed force differs from the recorded one
    bool truncated = false;      // the recording was cut short (crash): replayed up to its last chunk
    LessonScores scores;
    nlohmann::json scores_json;
    std::vector<Feedback> feedback;
    Chart reference;             // the case's chart, lesson teeth only
    Chart trainee;               // the trainee's chart
    ForceTrace force;
    std::optional<nlohmann::json> stored_scores;  // from the recording's annex
};

struct ReplayOptions {
    std::string lesson_path;    // empty: the lesson the recording names (metadata "lesson")
    std::string content_root;   // empty: default_content_root()
    std::string cases_dir;      // empty: default_cases_dir()
};

struct LessonReplay {
    std::string error;          // bad input (exit 2): one line naming the file
    LessonOutcome outcome;
    bool ok() const { return error.empty(); }
};

// Reads the recording, loads its lesson and case, replays every tick through the servo tick and
// the lesson runtime (UI events at the ticks they were taken), and scores the lesson.
LessonReplay replay_lesson(const std::string& recording_path, const ReplayOptions& options);

// --check: "" when the stored scores equal the recomputed ones bit for bit and the replayed forces
// match the recording; else the first difference, one line.
std::string check_outcome(const LessonOutcome& outcome);

// The report as JSON (sulcus.report/1): deterministic, nothing from the machine or the clock.
nlohmann::json report_json(const LessonOutcome& outcome);
// The report as one self-contained HTML page: the chart, per-site scores, force over time.
std::string report_html(const LessonOutcome& outcome);

// A starter lesson for a chart (a path relative to the content root): every tooth charted, its
// facial sites (MB, B, DB) then its lingual ones (DL, L, ML) as two steps taken in order, the
// three usual rules (firmer than 0.25 N, 0.5 N or more, leaving the sulcus) and the default
// rubric. What `sulcus-cli lesson new` writes and the app's instructor mode saves.
Lesson starter_lesson(const Chart& chart, const std::string& chart_path, const std::string& title);

// The chart path to write in a lesson for a case folder (holding chart.json): relative to the
// content root when the folder is inside it, else the content root's cases/<folder name>/chart.json
// when that chart is the same. "" and *error set when neither holds.
std::string lesson_chart_path(const std::string& case_dir, const std::string& content_root, std::string* error);

// Records a lesson session made by the simulated hand on the servo loop's manual clock: the hand
// follows the case's probing trajectory; at each pass, half way through the hold on the floor, it
// charts the depth the probe reads there (and bleeding where the case bleeds); it ends the lesson
// after the last pass. The scores go into the recording's "scores" annex. Returns "" or one line.
struct HandRecordOptions {
    std::string content_root;   // empty: default_content_root()
    std::string cases_dir;      // empty: default_cases_dir()
};
std::string record_lesson_with_hand(const std::string& lesson_path, const std::string& recording_path,
                                    const HandRecordOptions& options, LessonOutcome* outcome = nullptr);

}  // namespace sulcus

namespace sulcus {

// Instructor mode's save: writes <content_root>/cases/<name>/chart.json (chart_to_json of `chart`)
// and <content_root>/lessons/<name>.json (starter_lesson on "cases/<name>/chart.json" with
// `title`), each whole or not at all (write_file_atomic), the chart first. Refuses, writing
// nothing, a name that is not [a-z0-9_]{1,40}, the name of a bundled case (healthy_11,
// periodontitis_36, quadrant_44_47), an empty title and a chart that cannot become a case.
// Returns "" (and the two paths written) or one line saying why not.
std::string save_instructor_lesson(const Chart& chart, const std::string& name, const std::string& title,
                                   const std::string& content_root, std::string* chart_path, std::string* lesson_path);

// Whether `name` may name an instructor's case: [a-z0-9_]{1,40} and not a bundled case. "" or why not.
std::string instructor_name_error(const std::string& name);

}  // namespace sulcus
