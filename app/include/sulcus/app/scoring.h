// Scoring a lesson from its rubric (docs/lessons.md, "Scoring"): per site and overall, each row a
// score from 0 to 1, pass or not, and a sentence a trainee understands. Pure arithmetic on what
// the lesson runtime measured, so a replay recomputes every score bit for bit.
#pragma once

#include "sulcus/app/lesson.h"
#include "sulcus/app/lesson_runtime.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace sulcus {

// How a site's charted depth compares with the reference.
enum class DepthGrade { NotCharted, Exact, Pass, Fail };
// How firm the probe was at the deepest point of a site.
enum class ForceGrade { NotProbed, Light, Target, Firm, Warning, Trauma };
const char* depth_grade_name(DepthGrade g);  // "not charted", "exact", "within 1 mm" style names
const char* force_grade_name(ForceGrade g);

struct SiteScore {
    SiteRef ref;
    bool interproximal = false;
    // Depth: charted against the reference.
    double reference_pd_mm = 0.0;
    std::optional<double> charted_pd_mm;
    std::optional<double> error_mm;  // charted - reference
    DepthGrade depth = DepthGrade::NotCharted;
    double depth_score = 0.0;        // exact 1, pass 0.5, otherwise 0
    // Probing: the deepest insertion and the force and angle there.
    bool probed = false;
    double deepest_mm = 0.0;
    double force_N = 0.0;            // at the deepest point
    ForceGrade force = ForceGrade::NotProbed;
    double force_score = 0.0;        // target 1, firm 0.75, light or warning 0.5, trauma 0
    double max_force_N = 0.0;
    double time_above_warning_s = 0.0, time_at_trauma_s = 0.0;
    double angle_deg = 0.0;          // to the long axis
    double tilt_deg = 0.0;           // toward the contact (interproximal sites)
    bool angle_ok = false;
    // Walking stroke.
    double advance_mm = 0.0;
    double walk_score = 0.0;         // min(1, advance / walk_advance_mm)
    int withdrawals = 0;
    std::string feedback;            // one sentence for this site
};

struct RowScore {
    std::string name;      // "depth", "force", "angulation", "walking", "withdrawals", "completeness", "time"
    double score = 0.0;    // 0..1
    bool passed = false;
    double weight = 0.0;   // in the overall score (0: reported, not scored)
    std::string feedback;  // what the trainee should know
};

struct LessonScores {
    std::vector<SiteScore> sites;  // the target sites, in the runtime's (case) order
    std::vector<RowScore> rows;    // depth, force, angulation, walking, withdrawals, completeness, time
    double overall = 0.0;          // weighted mean of the rows with a weight
    bool passed = false;           // overall >= rubric.pass_score
    int sites_target = 0, sites_charted = 0, sites_probed = 0;
    int steps_completed = 0, steps_skipped = 0, steps_total = 0;
    double time_s = 0.0;           // first tick to the end of the lesson
    double max_force_N = 0.0, time_above_warning_s = 0.0, time_at_trauma_s = 0.0;
};

// What scoring reads: the runtime's per-site measurements and session totals.
struct SessionMeasures {
    std::vector<SiteMeasure> sites;  // every measured site; the target ones are scored
    double time_s = 0.0;             // first tick to the end of the lesson
    double max_force_N = 0.0, time_above_warning_s = 0.0, time_at_trauma_s = 0.0;
    int steps_total = 0, steps_completed = 0, steps_skipped = 0;
};
SessionMeasures session_measures(const LessonRuntime& runtime);

LessonScores score_measures(const Rubric& rubric, const SessionMeasures& measures);
inline LessonScores score_lesson(const LessonRuntime& runtime) {
    return score_measures(runtime.lesson().rubric, session_measures(runtime));
}

// The scores as JSON (keys sorted, numbers as shortest round-trip text), the form stored in a
// recording's "scores" annex and compared by `sulcus-cli replay --check`.
nlohmann::json scores_to_json(const LessonScores& scores);

// The first difference between two JSON documents, as "JSON path: stored X, recomputed Y"
// (`a` is the stored one); empty when they are equal.
std::string first_json_difference(const nlohmann::json& stored, const nlohmann::json& recomputed);

}  // namespace sulcus
