// Headless lesson sessions: the lesson's built case, the simulated hand's recording, the replay.
#include "sulcus/app/lesson_session.h"

#include "sulcus/app/probing_readout.h"
#include "sulcus/content/chart.h"
#include "sulcus/haptics/replay_device.h"
#include "sulcus/haptics/servo_loop.h"
#include "sulcus/haptics/sim_device.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <unistd.h>
#include <utility>

namespace fs = std::filesystem;

namespace sulcus {

namespace {

std::string self_dir() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string(".") : exe.parent_path().string();
}

// The reference chart restricted to the lesson's teeth.
Chart lesson_chart(const Chart& chart, const std::vector<int>& teeth) {
    Chart out;
    for (int fdi : teeth)
        if (const auto it = chart.teeth.find(fdi); it != chart.teeth.end()) out.teeth[fdi] = it->second;
    return out;
}

void add_force(ForceTrace& trace, double t0, const ServoSnapshot& s) {
    const double t = s.time_s - t0;
    if (!(t >= 0.0)) return;
    const auto bin = static_cast<std::size_t>(t / trace.bin_s);
    if (bin >= trace.max_N.size()) trace.max_N.resize(bin + 1, 0.0);
    trace.max_N[bin] = std::max(trace.max_N[bin], glm::length(s.rendered_force_N));
}

}  // namespace

std::string default_cases_dir() { return (fs::path(self_dir()) / ".." / "cases").lexically_normal().string(); }

std::string default_content_root() {
    // A build tree's binary (build/bin) two levels under the sources, else $SULCUS_SOURCE_DIR,
    // else content/assets under the current folder.
    const fs::path from_build = (fs::path(self_dir()) / ".." / ".." / "content" / "assets").lexically_normal();
    std::error_code ec;
    if (fs::is_directory(from_build, ec)) return from_build.string();
    if (const char* src = std::getenv("SULCUS_SOURCE_DIR"))
        return (fs::path(src) / "content" / "assets").lexically_normal().string();
    return "content/assets";
}

LessonCase load_lesson_case(const LessonLoad& lesson, const std::string& cases_dir) {
    LessonCase c;
    const fs::path chart_path(lesson.chart_path);
    const std::string name = chart_path.parent_path().filename().string();
    c.dir = (fs::path(cases_dir) / name).string();
    const std::string build_hint = " (build it: sulcus-cli content case " + lesson.chart_path + " --out " + c.dir + " --probe " +
                                   probe_kind_name(lesson.lesson.probe) + ")";
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(c.dir) / "case.json", ec)) {
        c.error = c.dir + ": no built case for " + lesson.chart_path + build_hint;
        return c;
    }
    CaseManifestLoad m = load_case_manifest(c.dir);
    if (!m.ok()) {
        c.error = m.errors.front();
        return c;
    }
    c.manifest = std::move(m.manifest);
    const ChartLoad source = load_chart(lesson.chart_path);
    if (!source.ok()) {
        c.error = source.errors.front();
        return c;
    }
    if (!(source.chart == c.manifest.chart)) {
        c.error = c.dir + "/chart.json: differs from " + lesson.chart_path + ": the case is stale" + build_hint;
        return c;
    }
    if (c.manifest.probe != probe_kind_name(lesson.lesson.probe)) {
        c.error = c.dir + "/case.json: built for the " + c.manifest.probe + " probe, the lesson uses " +
                  probe_kind_name(lesson.lesson.probe) + build_hint;
        return c;
    }
    c.scene = load_scene((fs::path(c.dir) / c.manifest.scene).string());
    if (!c.scene.ok()) {
        c.error = c.scene.errors.front();
        return c;
    }
    ModelBuild b = build_model(c.scene.scene, RendererSettings{});
    if (!b.model) {
        c.error = c.dir + ": " + b.error;
        return c;
    }
    c.model = std::move(b.model);
    return c;
}

LessonReplay replay_lesson(const std::string& recording_path, const ReplayOptions& options) {
    LessonReplay r;
    LessonOutcome& o = r.outcome;
    const RecordingRead rec = read_recording(recording_path);
    if (!rec.ok()) {
        r.error = rec.error;
        return r;
    }
    o.metadata = rec.metadata;
    o.truncated = rec.truncation.truncated;
    const std::string root = options.content_root.empty() ? default_content_root() : options.content_root;
    // The report names the lesson as the recording does (relative to the content root), so it
    // reads the same wherever the sources are.
    std::string lesson_file;
    if (!options.lesson_path.empty()) {
        lesson_file = o.lesson_path = options.lesson_path;
    } else if (!rec.metadata.lesson.empty()) {
        lesson_file = (fs::path(root) / rec.metadata.lesson).string();
        o.lesson_path = rec.metadata.lesson;
    } else {
        r.error = recording_path + ": the recording names no lesson (give one with --lesson FILE)";
        return r;
    }
    const LessonLoad lesson = load_lesson(lesson_file, options.content_root.empty() && options.lesson_path.empty() ? root : options.content_root);
    if (!lesson.ok()) {
        r.error = lesson.errors.front();
        return r;
    }
    o.lesson = lesson.lesson;
    const LessonCase lc = load_lesson_case(lesson, options.cases_dir.empty() ? default_cases_dir() : options.cases_dir);
    if (!lc.ok()) {
        r.error = lc.error;
        return r;
    }
    o.case_dir = lc.dir;

    LessonRuntime runtime(lesson.lesson, lc.manifest.sites, lc.manifest.chart);
    double t0 = NAN;
    ReplayObserver observer;
    observer.on_event = [&](const RecordingEvent& e) { runtime.on_event(e.kind, e.json); };
    observer.on_tick = [&](const ServoSnapshot& s) {
        if (std::isnan(t0)) t0 = s.time_s;
        runtime.on_tick(s);
        add_force(o.force, t0, s);
    };
    const ReplayResult result = replay_recording(rec, *lc.model, SafetyConfig{}, observer);
    if (!result.ok()) {
        r.error = recording_path + ": " + result.error;
        return r;
    }
    runtime.finish();
    o.ticks = rec.ticks.size();
    o.first_mismatch = result.first_mismatch;
    o.scores = score_lesson(runtime);
    o.scores_json = scores_to_json(o.scores);
    o.feedback = runtime.feedback();
    o.reference = lesson_chart(lc.manifest.chart, lesson.lesson.teeth);
    o.trainee = runtime.trainee_chart();
    for (const RecordingAnnex& a : rec.annexes) {
        if (a.name != kScoresAnnex) continue;
        nlohmann::json j = nlohmann::json::parse(a.json, nullptr, false);
        if (!j.is_discarded()) o.stored_scores = std::move(j);
    }
    return r;
}

std::string check_outcome(const LessonOutcome& o) {
    if (o.first_mismatch >= 0)
        return "tick " + std::to_string(o.first_mismatch) + ": the replayed force differs from the recorded one";
    if (!o.stored_scores) return "the recording holds no stored scores";
    const std::string d = first_json_difference(*o.stored_scores, o.scores_json);
    return d.empty() ? "" : "scores differ at " + d;
}

nlohmann::json report_json(const LessonOutcome& o) {
    using nlohmann::json;
    json j;
    j["format"] = kReportFormat;
    j["lesson"] = {{"path", o.lesson_path}, {"title", o.lesson.title}};
    j["case"] = fs::path(o.case_dir).filename().string();
    j["recording"] = {{"device", o.metadata.device},
                      {"rate_hz", o.metadata.rate_hz},
                      {"start_time", o.metadata.start_time},
                      {"ticks", o.ticks},
                      {"truncated", o.truncated},
                      {"first_mismatch", o.first_mismatch}};
    j["scores"] = o.scores_json;
    j["stored_scores_match"] = o.stored_scores ? json(first_json_difference(*o.stored_scores, o.scores_json).empty()) : json(nullptr);
    json fb = json::array();
    for (const Feedback& f : o.feedback)
        fb.push_back({{"tick", f.tick}, {"time_s", f.time_s}, {"level", feedback_level_name(f.level)}, {"source", f.source},
                      {"message", f.message}});
    j["feedback"] = fb;
    j["chart"] = {{"reference", chart_to_json(o.reference)}, {"trainee", chart_to_json(o.trainee)}};
    j["force"] = {{"bin_s", o.force.bin_s}, {"max_N", o.force.max_N}};
    return j;
}

Lesson starter_lesson(const Chart& chart, const std::string& chart_path, const std::string& title) {
    Lesson l;
    l.title = title;
    l.description = "Chart every site: probing depth at a light force (0.20-0.25 N), the probe parallel to the "
                    "long axis, tilted under the contact at interproximal sites, walked along the sulcus.";
    l.chart = chart_path;
    for (const auto& [fdi, tooth] : chart.teeth) {
        l.teeth.push_back(fdi);
        LessonStep facial;
        facial.id = std::to_string(fdi) + "-facial";
        facial.instruction = "Probe " + std::to_string(fdi) + " from the facial, distal to mesial is fine: MB, B, DB. "
                             "Chart each depth.";
        facial.order = StepOrder::Listed;
        for (Site s : {Site::MB, Site::B, Site::DB}) facial.sites.push_back({fdi, s});
        facial.hints.push_back({"Keep the tip against the tooth and the probe parallel to the long axis.", 20.0});
        LessonStep lingual = facial;
        lingual.id = std::to_string(fdi) + "-lingual";
        lingual.instruction = "Probe " + std::to_string(fdi) + " from the lingual: DL, L, ML. Chart each depth.";
        lingual.sites.clear();
        for (Site s : {Site::DL, Site::L, Site::ML}) lingual.sites.push_back({fdi, s});
        l.steps.push_back(facial);
        l.steps.push_back(lingual);
    }
    l.rules.push_back({"too_firm", RuleTrigger::ForceAbove, 0.25, RuleLevel::Warning,
                       "Too firm: above 0.25 N healthy gingiva is traumatized and bleeds.", 1.0});
    l.rules.push_back({"trauma", RuleTrigger::ForceAtLeast, 0.5, RuleLevel::Warning,
                       "0.5 N or more: the tip passes the pocket floor into the connective tissue.", 1.0});
    l.rules.push_back({"left_sulcus", RuleTrigger::LeftSulcus, 0.0, RuleLevel::Note,
                       "Keep the tip in the sulcus: walk it, do not take it out between strokes.", 1.0});
    return l;
}

std::string lesson_chart_path(const std::string& case_dir, const std::string& content_root, std::string* error) {
    std::error_code ec;
    const fs::path chart = fs::weakly_canonical(fs::path(case_dir) / "chart.json", ec);
    const fs::path root = fs::weakly_canonical(content_root, ec);
    if (!fs::is_regular_file(chart, ec)) {
        if (error) *error = case_dir + ": no chart.json in this folder";
        return "";
    }
    const fs::path rel = chart.lexically_relative(root);
    if (!rel.empty() && *rel.begin() != "..") return rel.generic_string();
    fs::path dir = fs::path(case_dir).lexically_normal();
    if (dir.filename().empty()) dir = dir.parent_path();  // "cases/healthy_11/"
    const fs::path same = root / "cases" / dir.filename() / "chart.json";
    const ChartLoad a = load_chart(chart.string()), b = load_chart(same.string());
    if (a.ok() && b.ok() && a.chart == b.chart) return same.lexically_relative(root).generic_string();
    if (error)
        *error = chart.string() + ": not inside the content root " + root.string() +
                 " and no chart there matches it (copy it into " + (root / "cases").string() + ")";
    return "";
}

std::string record_lesson_with_hand(const std::string& lesson_path, const std::string& recording_path,
                                    const HandRecordOptions& options, LessonOutcome* outcome) {
    const std::string root = options.content_root.empty() ? default_content_root() : options.content_root;
    const LessonLoad lesson = load_lesson(lesson_path, options.content_root);
    if (!lesson.ok()) return lesson.errors.front();
    const LessonCase lc = load_lesson_case(lesson, options.cases_dir.empty() ? default_cases_dir() : options.cases_dir);
    if (!lc.ok()) return lc.error;
    const std::vector<TrajectorySample>& script = lc.scene.scene.trajectory;
    if (script.size() < 2) return lc.dir + ": the case has no probing trajectory for the hand";

    ServoConfig config;
    config.rate_hz = lc.scene.scene.rate_hz;
    config.manual_clock = true;
    config.try_realtime = false;
    config.telemetry_queue = 1u << 16;
    HandParameters hand;
    hand.dt_s = 1.0 / config.rate_hz;
    SimulatedHand device(script, hand);

    RecordingWriter recorder;
    RecordingMetadata meta;
    meta.case_path = lc.dir;
    meta.device = "sim-hand";
    meta.rate_hz = config.rate_hz;
    std::error_code ec;
    const fs::path rel = fs::relative(fs::weakly_canonical(lesson_path, ec), fs::weakly_canonical(root, ec), ec);
    meta.lesson = ec ? lesson_path : rel.generic_string();
    RecordingOptions ropt;
    ropt.sync = SyncPolicy::None;
    if (std::string err = recorder.open(recording_path, meta, ropt); !err.empty()) return err;

    ServoLoop loop;
    if (std::string err = loop.start(config, device, *lc.model, &recorder); !err.empty()) {
        (void)recorder.close();
        return "servo loop: " + err;
    }

    LessonRuntime runtime(lesson.lesson, lc.manifest.sites, lc.manifest.chart);
    LessonOutcome o;
    std::deque<std::pair<std::string, std::string>> posted;  // events not yet taken by the loop
    uint64_t taken = 0;
    double t0 = NAN;
    std::string error;
    auto post = [&](const std::string& kind, const std::string& json) {
        if (std::string err = loop.post_event(kind, json); !err.empty()) {
            if (error.empty()) error = "posting " + kind + ": " + err;
            return;
        }
        posted.emplace_back(kind, json);
    };
    const std::vector<ProbingPass>& passes = lc.manifest.passes;
    std::size_t next_pass = 0;
    int acknowledged = -1;
    auto drain = [&]() {
        ServoSnapshot s;
        while (loop.pop_telemetry(s)) {
            for (; taken < s.events_taken && !posted.empty(); ++taken) {
                runtime.on_event(posted.front().first, posted.front().second);
                posted.pop_front();
            }
            if (std::isnan(t0)) t0 = s.time_s;
            runtime.on_tick(s);
            add_force(o.force, t0, s);
            // An instruction-only step is read and acknowledged (Next) once.
            const int step = runtime.current_step();
            if (step < static_cast<int>(lesson.lesson.steps.size()) && step != acknowledged &&
                lesson.lesson.steps[static_cast<std::size_t>(step)].complete == StepCondition::Acknowledged) {
                acknowledged = step;
                post(kEventLessonNext, "{}");
            }
            // The hand's trainee charts each pass half way through its hold on the floor, from the
            // reading of that tick, and notes bleeding where the case's chart has it.
            const double t = script.front().t + double(s.tick) / config.rate_hz;
            for (; next_pass < passes.size(); ++next_pass) {
                const ProbingPass& p = passes[next_pass];
                if (t < p.t_floor + 0.5 * (p.t_end - p.t_floor)) break;
                const int i = runtime.reading().site_index;
                if (i < 0) continue;
                const SiteMeasure& m = runtime.sites()[static_cast<std::size_t>(i)];
                if (m.ref.fdi != p.fdi || m.ref.site != p.site) continue;
                post(kEventChartDepth, chart_depth_event(m.ref, chart_depth_mm(runtime.reading().depth_m)));
                if (m.reference_bop) post(kEventChartBop, chart_bop_event(m.ref, true));
            }
        }
    };
    const uint64_t ticks = static_cast<uint64_t>(std::ceil((script.back().t - script.front().t) * config.rate_hz)) + 1;
    for (uint64_t k = 0; k < ticks && error.empty(); ++k) {
        loop.step_manual();
        drain();
        if (recorder.pending_ticks() >= kMaxTicksPerChunk) error = recorder.flush();
    }
    post(kEventLessonEnd, "{}");
    for (int k = 0; k < 2 && error.empty(); ++k) {  // the end is taken at the next tick
        loop.step_manual();
        drain();
    }
    loop.stop();
    if (!error.empty()) {
        (void)recorder.close();
        return recording_path + ": " + error;
    }
    runtime.finish();
    o.lesson_path = lesson_path;
    o.lesson = lesson.lesson;
    o.case_dir = lc.dir;
    o.metadata = meta;
    o.ticks = loop.stats().ticks;
    o.scores = score_lesson(runtime);
    o.scores_json = scores_to_json(o.scores);
    o.feedback = runtime.feedback();
    o.reference = lesson_chart(lc.manifest.chart, lesson.lesson.teeth);
    o.trainee = runtime.trainee_chart();
    o.stored_scores = o.scores_json;
    if (std::string err = recorder.add_annex(kScoresAnnex, o.scores_json.dump()); !err.empty()) {
        (void)recorder.close();
        return err;
    }
    if (std::string err = recorder.close(); !err.empty()) return err;
    if (outcome) *outcome = std::move(o);
    return "";
}

}  // namespace sulcus

namespace sulcus {

std::string instructor_name_error(const std::string& name) {
    if (name.empty() || name.size() > 40)
        return "the name must be 1 to 40 characters (a-z, 0-9, _), \"" + name + "\" has " + std::to_string(name.size());
    for (char c : name)
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'))
            return "\"" + name + "\": only a-z, 0-9 and _ may name a case";
    for (const char* bundled : {"healthy_11", "periodontitis_36", "quadrant_44_47"})
        if (name == bundled) return "\"" + name + "\" is a bundled case: choose another name";
    return "";
}

std::string save_instructor_lesson(const Chart& chart, const std::string& name, const std::string& title,
                                   const std::string& content_root, std::string* chart_path, std::string* lesson_path) {
    if (std::string err = instructor_name_error(name); !err.empty()) return err;
    if (title.empty()) return "the lesson needs a title";
    const std::string rel_chart = "cases/" + name + "/chart.json";
    std::vector<std::string> errors;
    check_chart_for_case(chart, rel_chart, errors);
    if (!errors.empty()) return errors.front();
    const fs::path root(content_root);
    const fs::path chart_file = root / "cases" / name / "chart.json";
    const fs::path lesson_file = root / "lessons" / (name + ".json");
    std::error_code ec;
    for (const fs::path& dir : {chart_file.parent_path(), lesson_file.parent_path()}) {
        fs::create_directories(dir, ec);
        if (ec) return dir.string() + ": cannot create the folder (" + ec.message() + ")";
    }
    if (std::string err = write_file_atomic(chart_file.string(), chart_to_json(chart).dump(2) + "\n"); !err.empty())
        return err;
    const Lesson lesson = starter_lesson(chart, rel_chart, title);
    if (std::string err = write_file_atomic(lesson_file.string(), lesson_to_json(lesson).dump(2) + "\n"); !err.empty())
        return err;
    if (chart_path) *chart_path = chart_file.string();
    if (lesson_path) *lesson_path = lesson_file.string();
    return "";
}

}  // namespace sulcus
