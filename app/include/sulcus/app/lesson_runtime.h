// The lesson runtime: drives a lesson's steps from the servo loop's per-tick snapshots and the
// trainee's UI events, and measures, per site, what the rubric scores: the deepest insertion of
// the tip below the gingival margin, the force on the tissue there, the probe's angle to the
// tooth's long axis (and its tilt toward the contact at interproximal sites), the walking-stroke
// advance along the sulcus and the withdrawals from it. Headless and deterministic: the same
// snapshots and events, in the same order, give the same state bit for bit, so a replayed session
// scores exactly as the live one did.
//
// Feed it every tick's snapshot (on_tick) and, before a tick's snapshot, the UI events the servo
// loop took at that tick (on_event). Live, the events come back through the telemetry stream
// (ServoSnapshot::events_taken); in a replay, from the recording.
#pragma once

#include "sulcus/app/lesson.h"
#include "sulcus/app/probing_readout.h"
#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/haptics/servo_loop.h"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sulcus {

// UI events the runtime reads (kind, JSON payload). Other kinds are ignored.
inline constexpr const char* kEventChartDepth = "chart.depth";  // {"site":"36MB","pd_mm":5}
inline constexpr const char* kEventChartBop = "chart.bop";      // {"site":"36MB","bop":true}
inline constexpr const char* kEventChartGm = "chart.gm";        // {"site":"36MB","gm_mm":-1}
inline constexpr const char* kEventChartClear = "chart.clear";  // {"site":"36MB"}
inline constexpr const char* kEventLessonNext = "lesson.next";  // {} the trainee moves on
inline constexpr const char* kEventLessonEnd = "lesson.end";    // {} the trainee ends the lesson

// Sides of a tooth: ML, L, DL are lingual (palatal on upper teeth), the others facial.
bool is_lingual_site(Site s);

// Builds the JSON payload of a chart.depth event (whole or half millimetres as charted).
std::string chart_depth_event(const SiteRef& site, double pd_mm);
std::string chart_bop_event(const SiteRef& site, bool bop);

// What the runtime has measured at one site.
struct SiteMeasure {
    SiteRef ref;
    bool target = false;        // a target site of some step
    bool interproximal = false; // MB, DB, ML, DL
    double reference_pd_mm = 0.0, reference_gm_mm = 0.0;
    bool reference_bop = false;

    bool visited = false;       // the tip was in this site's sulcus at least once
    double deepest_m = 0.0;     // deepest insertion of the tip end below the margin
    double deepest_time_s = 0.0;
    double force_at_deepest_N = 0.0;  // force on the tissue at that tick
    double angle_at_deepest_rad = 0.0;  // probe to the tooth's long axis
    double tilt_at_deepest_rad = 0.0;   // interproximal: toward the contact (tip under it) > 0
    double max_force_N = 0.0;           // while in this site's sulcus
    double time_above_warning_s = 0.0;  // while in this site's sulcus
    double time_at_trauma_s = 0.0;
    // Walking stroke: the range of the tip's position along the sulcus (m) while in it.
    double walk_min_m = 0.0, walk_max_m = 0.0;
    int withdrawals = 0;        // times the tip left this sulcus upward, above the margin

    std::optional<double> charted_pd_mm;  // the trainee's chart
    bool charted_bop = false;
    double charted_gm_mm = 0.0;
    double charted_time_s = 0.0;  // when the depth was (last) charted

    double advance_m() const { return visited ? walk_max_m - walk_min_m : 0.0; }
};

enum class FeedbackLevel { Hint, Note, Warning, Step };
const char* feedback_level_name(FeedbackLevel l);  // "hint", "note", "warning", "step"

// A message to the trainee, when it was given.
struct Feedback {
    uint64_t tick = 0;
    double time_s = 0.0;
    FeedbackLevel level = FeedbackLevel::Note;
    std::string source;   // rule id, step id, or "input"
    std::string message;
};

struct StepProgress {
    bool started = false, completed = false, skipped = false;
    double start_s = 0.0, end_s = 0.0;
    std::size_t next_site = 0;        // listed order: the next site that may count
    std::vector<bool> satisfied;      // per target site of the step
    int order_violations = 0;         // sites satisfied before their turn (listed order)
    std::vector<bool> hint_shown;
};

class LessonRuntime {
public:
    // `sites`: the case's site frames (case.json); `reference`: the case's chart. Sites of the
    // lesson's teeth are measured; steps name sites among them (the lesson reader checks that).
    LessonRuntime(const Lesson& lesson, const std::vector<SiteFrame>& sites, const Chart& reference);

    // A UI event taken by the servo loop before the next tick's work. Malformed payloads are noted
    // (Feedback source "input") and otherwise ignored; never throws.
    void on_event(std::string_view kind, std::string_view json);
    // One servo tick (in order, every tick).
    void on_tick(const ServoSnapshot& s);
    // Ends the lesson at the last tick seen (when no lesson.end came). Idempotent.
    void finish();

    bool ended() const { return ended_; }
    bool complete() const;                 // every step completed (or skipped)
    int current_step() const { return current_; }  // index into lesson().steps; == size when done
    const Lesson& lesson() const { return lesson_; }
    const std::vector<SiteMeasure>& sites() const { return measures_; }
    const std::vector<StepProgress>& steps() const { return progress_; }
    const std::vector<Feedback>& feedback() const { return feedback_; }
    // The live reading at the last tick (-1 site when none), index into sites().
    const ProbeReading& reading() const { return reading_; }
    int reading_site() const { return reading_site_; }

    uint64_t ticks() const { return ticks_; }
    double start_s() const { return start_s_; }
    double end_s() const { return end_s_; }
    double max_force_N() const { return max_force_N_; }
    double time_above_warning_s() const { return time_above_warning_s_; }
    double time_at_trauma_s() const { return time_at_trauma_s_; }
    // Withdrawals per side of a tooth: [fdi] -> {buccal, lingual}.
    int withdrawals(int fdi, bool lingual) const;
    int bad_events() const { return bad_events_; }

    // The trainee's chart so far (sulcus.chart/1 shape: teeth of the lesson, charted sites only).
    Chart trainee_chart() const;

private:
    int measure_index(const SiteRef& ref) const;
    void note(FeedbackLevel level, const std::string& source, const std::string& message);
    void advance_steps();
    bool site_satisfied(const SiteMeasure& m, StepCondition c) const;
    void satisfy(int step, std::size_t k);

    Lesson lesson_;
    std::vector<SiteFrame> frames_;      // the measured sites' frames, same order as measures_
    std::vector<SiteMeasure> measures_;
    std::vector<Vec3> tangent_;          // along the sulcus at each site
    std::vector<Vec3> contact_dir_;      // toward the contact at interproximal sites, else 0
    std::vector<StepProgress> progress_;
    std::vector<Feedback> feedback_;
    std::vector<double> rule_last_s_;    // last firing time per rule (-inf: never)
    std::vector<bool> rule_active_;      // force rules: above the threshold at the last tick

    int current_ = 0;
    bool ended_ = false;
    bool end_note_ = false;              // "every step is done" given
    uint64_t ticks_ = 0;
    uint64_t last_tick_ = 0;
    double start_s_ = 0.0, end_s_ = 0.0, last_s_ = 0.0;
    double max_force_N_ = 0.0, time_above_warning_s_ = 0.0, time_at_trauma_s_ = 0.0;
    int in_site_ = -1;                   // the sulcus the tip is in (index), -1 none
    ProbeReading reading_;
    int reading_site_ = -1;
    int bad_events_ = 0;
};

}  // namespace sulcus
