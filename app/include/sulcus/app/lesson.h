// A lesson script, `sulcus.lesson/1` (docs/lessons.md): the case a lesson runs on (a chart from
// the content root and the teeth it is about), the probe, a sequence of steps (instruction,
// target sites and their order, the condition that completes the step, hints), event rules
// (force above a threshold -> a warning; the tip leaving the sulcus during a walking stroke -> a
// note) and the rubric with its thresholds.
//
// Lessons are data: nothing in one is executed, every path names a file inside the content root,
// the file and its lists are size-limited, and every fault is reported as one line
// "FILE: JSON path: what is wrong" (the JSON path written as `steps[2].sites[0]`).
#pragma once

#include "sulcus/content/probes.h"
#include "sulcus/content/tooth.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace sulcus {

inline constexpr const char* kLessonFormat = "sulcus.lesson/1";
// Limits a lesson must respect.
inline constexpr std::size_t kMaxLessonBytes = 256 * 1024;  // the whole file
inline constexpr std::size_t kMaxLessonDepth = 16;           // nesting of JSON arrays and objects
inline constexpr std::size_t kMaxLessonSteps = 200;
inline constexpr std::size_t kMaxLessonRules = 32;
inline constexpr std::size_t kMaxStepSites = 192;             // 32 teeth x 6 sites
inline constexpr std::size_t kMaxStepHints = 8;
inline constexpr std::size_t kMaxLessonText = 2000;          // characters of one string

// A site of a tooth, written "36MB" in a lesson (FDI number, then the site's name).
struct SiteRef {
    int fdi = 0;
    Site site = Site::MB;
    bool operator==(const SiteRef&) const = default;
};
// "36MB" -> {36, MB}; false when the text is not a two-digit FDI number followed by a site name.
bool parse_site_ref(const std::string& text, SiteRef* out);
std::string site_ref_name(const SiteRef& ref);  // "36MB"

// How the target sites of a step may be taken.
enum class StepOrder {
    Any,     // in any order
    Listed,  // in the order listed: a site counts only once every site before it has
};

// What completes a step.
enum class StepCondition {
    Charted,       // every target site has a charted probing depth
    Probed,        // the tip reached the pocket floor at every target site (within the rubric's
                   // depth_pass_mm of the reference depth)
    Walked,        // a walking stroke covered every target site (advance >= walk_advance_mm)
    Acknowledged,  // the trainee moved on (the `lesson.next` UI event); for instruction-only steps
};

struct LessonHint {
    std::string text;
    double after_s = 20.0;  // shown once the step has run this long without completing
};

struct LessonStep {
    std::string id;           // unique within the lesson
    std::string instruction;  // shown while the step runs
    std::vector<SiteRef> sites;  // target sites; empty only for an Acknowledged step
    StepOrder order = StepOrder::Any;
    StepCondition complete = StepCondition::Charted;
    std::vector<LessonHint> hints;
};

// What an event rule watches.
enum class RuleTrigger {
    ForceAbove,    // the force on the tissue rises above threshold_N
    ForceAtLeast,  // the force on the tissue reaches threshold_N or more
    LeftSulcus,    // the tip leaves a sulcus it was walking in (a withdrawal above the margin)
};

enum class RuleLevel { Note, Warning };

struct LessonRule {
    std::string id;           // unique within the lesson
    RuleTrigger when = RuleTrigger::ForceAbove;
    double threshold_N = 0.25;  // ForceAbove / ForceAtLeast only
    RuleLevel level = RuleLevel::Warning;
    std::string message;      // shown to the trainee when the rule fires
    double cooldown_s = 1.0;  // the rule does not fire again within this time
};

// The rubric and its thresholds (docs/lessons.md gives each default's source). Every field may be
// set per lesson; absent fields keep these defaults.
struct Rubric {
    // Charted depth against the reference: a site passes within depth_pass_mm, is exact within
    // depth_exact_mm; the row passes when at least depth_pass_fraction of the charted sites pass.
    double depth_pass_mm = 1.0;
    double depth_exact_mm = 0.5;
    double depth_pass_fraction = 0.95;
    // Force on the tissue at the deepest point of each site: target band, a warning above
    // force_warning_N, trauma at force_trauma_N or more. The row passes with no tick at trauma
    // and no more than max_time_above_warning_s above the warning level.
    double force_target_min_N = 0.20;
    double force_target_max_N = 0.25;
    double force_warning_N = 0.25;
    double force_trauma_N = 0.50;
    double max_time_above_warning_s = 1.0;
    // Angulation at the deepest point: within angle_direct_max_deg of the long axis at direct
    // (B, L) sites; tilted toward the contact by angle_interproximal_min_deg ..
    // angle_interproximal_max_deg at interproximal (MB, DB, ML, DL) sites. The row passes when at
    // least angle_pass_fraction of the probed sites do.
    double angle_direct_max_deg = 10.0;
    double angle_interproximal_min_deg = 5.0;
    double angle_interproximal_max_deg = 20.0;
    double angle_pass_fraction = 0.8;
    // Walking stroke: each site's advance along the sulcus (mm) while the tip stays in it; a site
    // is covered at walk_advance_mm. Withdrawals from the sulcus: at most max_withdrawals_per_side
    // for each side (buccal, lingual) of each tooth before each extra one costs.
    double walk_advance_mm = 1.0;
    double walk_pass_fraction = 0.8;
    int max_withdrawals_per_side = 1;
    // Completeness: the fraction of target sites charted for the row to pass.
    double completeness_pass_fraction = 1.0;
    // Time: the lesson's time limit (s); 0 = no limit (time is reported, not scored).
    double time_limit_s = 0.0;
    // Weights of the rows in the overall score, and the overall score needed to pass (0..1).
    double weight_depth = 0.35;
    double weight_force = 0.20;
    double weight_angulation = 0.15;
    double weight_walking = 0.10;
    double weight_withdrawals = 0.05;
    double weight_completeness = 0.10;
    double weight_time = 0.05;
    double pass_score = 0.7;
    bool operator==(const Rubric&) const = default;
};

struct Lesson {
    std::string format = kLessonFormat;
    std::string title;
    std::string description;
    // The case: a chart (a path relative to the content root; its folder names the built case) and
    // the teeth the lesson is about (every tooth of the chart when the file lists none).
    std::string chart;
    std::vector<int> teeth;
    ProbeKind probe = ProbeKind::Williams;  // the bundled cases are built for the Williams probe
    std::vector<LessonStep> steps;
    std::vector<LessonRule> rules;
    Rubric rubric;

    // Every target site of the steps, without repeats, in first-listed order.
    std::vector<SiteRef> target_sites() const;
};

struct LessonLoad {
    Lesson lesson;
    std::string source;                 // the file as named to the loader
    std::string chart_path;             // the chart, resolved inside the content root (absolute)
    std::vector<std::string> errors;    // one line each: "FILE: JSON path: what is wrong"
    bool ok() const { return errors.empty(); }
};

// Reads a lesson file. `content_root`: the folder every path in the lesson is relative to and
// must stay inside (after resolving `..` and symbolic links); empty = the parent of the folder
// holding the lesson (lessons live in <content root>/lessons/). Checks the size (kMaxLessonBytes)
// before parsing, the nesting depth, the format, unknown keys (an error), types, ranges, the
// teeth against the chart, and that the chart exists and reads. Every fault is reported.
LessonLoad load_lesson(const std::string& path, const std::string& content_root = "");
// The same for text already read: `source` names it in messages.
LessonLoad parse_lesson(const std::string& text, const std::string& source, const std::string& content_root);

// The lesson as a document parse_lesson reads back equal (every rubric field written).
nlohmann::json lesson_to_json(const Lesson& lesson);

const char* step_order_name(StepOrder o);          // "any", "listed"
const char* step_condition_name(StepCondition c);  // "charted", "probed", "walked", "acknowledged"
const char* rule_trigger_name(RuleTrigger t);      // "force_above", "force_at_least", "left_sulcus"
const char* rule_level_name(RuleLevel l);          // "note", "warning"

}  // namespace sulcus
