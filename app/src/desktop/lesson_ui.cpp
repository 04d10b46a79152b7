// The app's lessons, UI events, session recording and instructor mode. Every trainee action that
// a lesson scores goes to the servo loop as a posted event, so the recording holds it at the tick
// that took it; the live runtime is fed those events from the telemetry at the same ticks, so a
// replay of the recording (`sulcus-cli replay --check`) recomputes the live scores bit for bit.
#include "desktop/app.h"

#include "sulcus/content/case.h"
#include "sulcus/content/chart.h"
#include "sulcus/content/probes.h"
#include "sulcus/content/tooth.h"

#include <imgui.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace sulcus::desktop {

namespace fs = std::filesystem;

namespace {

const ImVec4 kGreen(0.35f, 0.85f, 0.45f, 1.0f), kRed(1.0f, 0.35f, 0.35f, 1.0f), kGrey(0.6f, 0.6f, 0.6f, 1.0f),
    kYellow(0.95f, 0.85f, 0.4f, 1.0f);

// How many of the latest hints and feedback lines the lesson panel shows.
constexpr std::size_t kFeedbackShown = 5;

void wrapped(const ImVec4& colour, const std::string& text) {
    ImGui::PushStyleColor(ImGuiCol_Text, colour);
    ImGui::TextWrapped("%s", text.c_str());
    ImGui::PopStyleColor();
}

ImVec4 feedback_colour(FeedbackLevel l) {
    switch (l) {
        case FeedbackLevel::Warning: return kRed;
        case FeedbackLevel::Hint: return kYellow;
        case FeedbackLevel::Step: return kGreen;
        default: return kGrey;
    }
}

// Sites of a tooth as the chart rows show them.
constexpr Site kBuccalRow[3] = {Site::MB, Site::B, Site::DB};
constexpr Site kLingualRow[3] = {Site::ML, Site::L, Site::DL};

}  // namespace

std::string sessions_dir() {
    if (const char* d = std::getenv("SULCUS_SESSIONS_DIR"); d && *d) return d;
    if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return (fs::path(x) / "sulcus" / "sessions").string();
    const char* home = std::getenv("HOME");
    return (fs::path(home && *home ? home : ".") / ".local" / "share" / "sulcus" / "sessions").string();
}

std::string session_file_name(const std::string& lesson_path, std::time_t now) {
    std::tm utc{};
    gmtime_r(&now, &utc);
    char stamp[32];
    std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
    return fs::path(lesson_path).stem().string() + "-" + stamp + ".rec";
}

std::string App::load_lesson_file() {
    content_root_ = options_.content_root.empty() ? default_content_root() : options_.content_root;
    LiveLesson l;
    l.path = options_.lesson;
    l.load = load_lesson(options_.lesson, options_.content_root);
    if (!l.load.ok()) {
        const size_t more = l.load.errors.size() - 1;
        return l.load.errors.front() + (more ? " (and " + std::to_string(more) + " more)" : "");
    }
    LessonCase lc = load_lesson_case(l.load, default_cases_dir());
    if (!lc.ok()) return lc.error;
    // The lesson's case replaces --case; its scene and model are already loaded.
    options_.case_dir = lc.dir;
    scene_ = std::move(lc.scene);
    model_ = std::move(lc.model);
    // The path the recording names, relative to the content root as the headless recorder writes it.
    std::error_code ec;
    const fs::path rel =
        fs::relative(fs::weakly_canonical(options_.lesson, ec), fs::weakly_canonical(content_root_, ec), ec);
    l.relative = ec ? options_.lesson : rel.generic_string();
    lesson_.emplace(std::move(l));
    return "";
}

std::string App::open_recorder(const std::string& device_name) {
    if (record_path_.empty()) return "";
    if (recorder_) (void)recorder_->close();
    recorder_ = std::make_unique<RecordingWriter>();
    record_meta_ = RecordingMetadata{};
    record_meta_.case_path = options_.case_dir;
    record_meta_.device = device_name;
    record_meta_.rate_hz = scene_.scene.rate_hz;
    record_meta_.lesson = lesson_ ? lesson_->relative : "";
    RecordingOptions ropt;
    ropt.sync = SyncPolicy::DataSync;
    if (std::string err = recorder_->open(record_path_, record_meta_, ropt); !err.empty()) {
        recorder_.reset();
        return err;
    }
    if (std::string err = recorder_->start_writer_thread(); !err.empty()) {
        (void)recorder_->close();
        recorder_.reset();
        return record_path_ + ": " + err;
    }
    return "";
}

bool App::post(const std::string& kind, const std::string& json) {
    if (std::string err = loop_.post_event(kind, json); !err.empty()) {
        std::fprintf(stderr, "sulcus: %s not taken: %s\n", kind.c_str(), err.c_str());
        return false;
    }
    if (lesson_) {
        lesson_->posted.emplace_back(kind, json);
    }
    return true;
}

// A lesson is about some of the case's teeth; charting the others is shown, not posted (the lesson
// would only note it as input it ignores).
bool App::lesson_site(int fdi) const {
    if (!lesson_) return true;
    const std::vector<int>& teeth = lesson_->load.lesson.teeth;
    return std::find(teeth.begin(), teeth.end(), fdi) != teeth.end();
}

void App::chart_depth(int fdi, Site site, double pd_mm) {
    if (!chart_ || !std::isfinite(pd_mm)) return;
    pd_mm = std::clamp(pd_mm, 0.0, kMaxProbingDepthMm);
    if (lesson_site(fdi) && !post(kEventChartDepth, chart_depth_event({fdi, site}, pd_mm))) return;
    chart_->record_depth(fdi, site, pd_mm * 1e-3);
}

void App::chart_bop(int fdi, Site site, bool bop) {
    if (!chart_) return;
    if (lesson_site(fdi) && !post(kEventChartBop, chart_bop_event({fdi, site}, bop))) return;
    chart_->set_bop(fdi, site, bop);
}

void App::chart_gm(int fdi, Site site, double gm_mm) {
    if (!chart_) return;
    gm_mm = std::clamp(gm_mm, kMinGingivalMarginMm, kMaxGingivalMarginMm);
    const nlohmann::json j = {{"site", site_ref_name({fdi, site})}, {"gm_mm", gm_mm}};
    if (lesson_site(fdi) && !post(kEventChartGm, j.dump())) return;
    chart_->set_gm(fdi, site, gm_mm);
}

// Before a tick's snapshot, the events the loop took up to and at that tick, in the order posted.
void App::feed_lesson(const ServoSnapshot& s) {
    LiveLesson& l = *lesson_;
    for (; l.fed < s.events_taken && !l.posted.empty(); ++l.fed) {
        l.runtime->on_event(l.posted.front().first, l.posted.front().second);
        l.posted.pop_front();
    }
    l.runtime->on_tick(s);
    if (l.runtime->ended() && !l.scores) l.scores = score_lesson(*l.runtime);
}

int App::finish_session() {
    int exit_code = 0;
    if (lesson_ && loop_.running()) {
        // The end goes through the loop like every other event, so the recording holds it; wait
        // (briefly) until a tick has taken it.
        if (post(kEventLessonEnd, "{}")) {
            for (int k = 0; k < 200; ++k) {
                ServoSnapshot s;
                if (loop_.latest(s) && s.events_taken >= lesson_->fed + lesson_->posted.size()) break;
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
        }
    }
    loop_.stop();
    drain_telemetry();
    const uint64_t drops = std::max(live_.telemetry_drops, loop_.stats().telemetry_drops);
    if (lesson_) {
        lesson_->runtime->finish();
        lesson_->scores = score_lesson(*lesson_->runtime);
    }
    if (!recorder_) {
        if (lesson_ && drops > 0)
            std::fprintf(stderr, "sulcus: %llu telemetry samples dropped: the lesson's scores miss those ticks (record the "
                                 "session to have them scored from the recording)\n",
                         static_cast<unsigned long long>(drops));
        return exit_code;
    }
    std::string err;
    if (lesson_ && drops == 0) err = recorder_->add_annex(kScoresAnnex, scores_to_json(*lesson_->scores).dump());
    if (std::string e = recorder_->close(); err.empty()) err = e;
    if (err.empty() && lesson_ && drops > 0) {
        // The live runtime missed the dropped ticks: the scores come from a replay of the recording,
        // which saw every tick, and the recording is rewritten with them.
        std::fprintf(stderr, "sulcus: %llu telemetry samples dropped: scoring the session from its recording\n",
                     static_cast<unsigned long long>(drops));
        ReplayOptions ro;
        ro.lesson_path = lesson_->path;
        ro.content_root = options_.content_root;
        ro.cases_dir = default_cases_dir();
        const LessonReplay replay = replay_lesson(record_path_, ro);
        if (!replay.ok()) {
            err = replay.error;
        } else {
            lesson_->scores = replay.outcome.scores;
            lesson_->scores_replayed = true;
            RecordingRead rec = read_recording(record_path_);
            if (!rec.ok()) {
                err = rec.error;
            } else {
                rec.annexes.push_back({rec.ticks.size(), kScoresAnnex, replay.outcome.scores_json.dump()});
                err = write_recording(record_path_, rec, SyncPolicy::DataSync);
            }
        }
    }
    if (!err.empty()) {
        std::fprintf(stderr, "sulcus: %s\n", err.c_str());
        exit_code = 1;
    }
    const RecordingStats rs = recorder_->stats();
    std::printf("sulcus: session recorded to %s (%llu ticks, %llu events%s)\n", record_path_.c_str(),
                static_cast<unsigned long long>(rs.ticks_written), static_cast<unsigned long long>(rs.events_written),
                rs.ticks_dropped || rs.events_dropped ? ", some dropped: the replay will differ" : "");
    return exit_code;
}

// The lesson panel while a lesson runs: the step, its sites, hints and feedback, Next and End;
// after the end, the rubric.
void App::panel_lesson_steps() {
    LiveLesson& l = *lesson_;
    const Lesson& lesson = l.load.lesson;
    const LessonRuntime& rt = *l.runtime;
    ImGui::TextWrapped("%s", lesson.title.c_str());
    ImGui::TextColored(kGrey, "Case: %s", case_name_.c_str());
    ImGui::Separator();
    if (l.scores) {
        const LessonScores& sc = *l.scores;
        ImGui::Text("Lesson ended: %d of %d sites charted", sc.sites_charted, sc.sites_target);
        if (ImGui::BeginTable("rubric", 3, ImGuiTableFlags_Borders | ImGuiTableFlags_SizingStretchProp)) {
            ImGui::TableSetupColumn("row");
            ImGui::TableSetupColumn("score");
            ImGui::TableSetupColumn("pass");
            ImGui::TableHeadersRow();
            for (const RowScore& r : sc.rows) {
                ImGui::TableNextRow();
                ImGui::TableSetColumnIndex(0);
                ImGui::TextUnformatted(r.name.c_str());
                if (!r.feedback.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", r.feedback.c_str());
                ImGui::TableSetColumnIndex(1);
                ImGui::Text("%.0f %%", r.score * 100.0);
                ImGui::TableSetColumnIndex(2);
                if (r.weight <= 0.0) ImGui::TextColored(kGrey, "-");
                else ImGui::TextColored(r.passed ? kGreen : kRed, "%s", r.passed ? "pass" : "fail");
            }
            ImGui::EndTable();
        }
        ImGui::TextColored(sc.passed ? kGreen : kRed, "Overall %.0f %%: %s", sc.overall * 100.0,
                           sc.passed ? "passed" : "not passed");
        if (l.scores_replayed) ImGui::TextColored(kGrey, "(scored from the recording)");
        return;
    }
    const int n = int(lesson.steps.size()), k = rt.current_step();
    if (k < n) {
        const LessonStep& step = lesson.steps[size_t(k)];
        const StepProgress& p = rt.steps()[size_t(k)];
        ImGui::Text("Step %d of %d", k + 1, n);
        ImGui::TextWrapped("%s", step.instruction.c_str());
        for (size_t i = 0; i < step.sites.size(); ++i) {
            const bool done = i < p.satisfied.size() && p.satisfied[i];
            if (i % 6) ImGui::SameLine();
            ImGui::TextColored(done ? kGreen : kGrey, "%s %s", done ? "[x]" : "[ ]", site_ref_name(step.sites[i]).c_str());
        }
        if (step.complete == StepCondition::Acknowledged) ImGui::TextColored(kGrey, "Press Next when ready.");
    } else {
        ImGui::TextColored(kGreen, "Every step is done: press End for the scores.");
    }
    // Hints and feedback so far, the latest last.
    const std::vector<Feedback>& fb = rt.feedback();
    const size_t first = fb.size() > kFeedbackShown ? fb.size() - kFeedbackShown : 0;
    if (!fb.empty()) ImGui::Separator();
    for (size_t i = first; i < fb.size(); ++i) wrapped(feedback_colour(fb[i].level), fb[i].message);
    ImGui::Separator();
    ImGui::BeginDisabled(k >= n);
    if (ImGui::Button("Next")) post(kEventLessonNext, "{}");
    ImGui::EndDisabled();
    ImGui::SameLine();
    if (ImGui::Button("End")) post(kEventLessonEnd, "{}");
}

// Instructor mode's chart: the case's reference chart, editable, and the save.
void App::panel_instructor() {
    Instructor& in = *instructor_;
    if (!ImGui::Begin("Periodontal chart")) {
        ImGui::End();
        return;
    }
    ImGui::TextColored(kYellow, "Instructor: the case's reference chart (PD 0-15 mm in 0.5 mm, GM -12..8 mm, BOP)");
    const int n_teeth = int(in.chart.teeth.size());
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_ScrollX;
    // Eight rows and the header, so the revert button stays in view below them.
    const float table_h = 9.0f * (ImGui::GetFrameHeight() + 2.0f * ImGui::GetStyle().CellPadding.y) + 18.0f;
    if (ImGui::BeginTable("reference", 1 + 3 * n_teeth, flags, ImVec2(0.0f, table_h))) {
        ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 60.0f);
        for (int i = 0; i < 3 * n_teeth; ++i) ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 38.0f);
        ImGui::TableNextRow(ImGuiTableRowFlags_Headers);
        ImGui::TableSetColumnIndex(0);
        ImGui::TextUnformatted("FDI");
        int col = 1;
        for (const auto& [fdi, tooth] : in.chart.teeth) {
            ImGui::TableSetColumnIndex(col);
            ImGui::Text("%d", fdi);
            col += 3;
        }
        auto row = [&](const char* what, const Site* sites, int kind) {
            ImGui::TableNextRow();
            ImGui::TableSetColumnIndex(0);
            ImGui::TextUnformatted(what);
            int c = 1;
            for (auto& [fdi, tooth] : in.chart.teeth) {
                for (int k = 0; k < 3; ++k, ++c) {
                    ImGui::TableSetColumnIndex(c);
                    std::optional<SiteRecord>& r = tooth.sites[size_t(sites[k])];
                    ImGui::PushID(fdi * 100 + int(sites[k]) * 10 + kind);
                    ImGui::SetNextItemWidth(-1);
                    if (kind == 0) {
                        ImGui::TextColored(kGrey, "%s", site_name(sites[k]));
                    } else if (!r) {
                        ImGui::TextColored(kGrey, "-");
                    } else if (kind == 1) {
                        float pd = float(r->pd_mm);
                        if (ImGui::DragFloat("##pd", &pd, 0.05f, 0.0f, 15.0f, "%.1f"))
                            r->pd_mm = std::clamp(std::round(double(pd) * 2.0) / 2.0, 0.0, kMaxProbingDepthMm);
                    } else if (kind == 2) {
                        int gm = int(std::lround(r->gm_mm));
                        if (ImGui::DragInt("##gm", &gm, 0.1f, -12, 8))
                            r->gm_mm = std::clamp(double(gm), kMinGingivalMarginMm, kMaxGingivalMarginMm);
                    } else {
                        ImGui::Checkbox("##bop", &r->bop);
                    }
                    ImGui::PopID();
                }
            }
        };
        row("Buccal", kBuccalRow, 0);
        row("PD", kBuccalRow, 1);
        row("GM", kBuccalRow, 2);
        row("BOP", kBuccalRow, 3);
        row("Lingual", kLingualRow, 0);
        row("PD", kLingualRow, 1);
        row("GM", kLingualRow, 2);
        row("BOP", kLingualRow, 3);
        ImGui::EndTable();
    }
    if (ImGui::Button("Revert to the case's chart")) in.chart = manifest_.chart;
    ImGui::End();

    // The save: a case chart and a starter lesson in the content root, then the case built.
    ImGui::SetNextWindowPos(ImVec2(356.0f, 8.0f), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(460, 220), ImGuiCond_FirstUseEver);
    if (!ImGui::Begin("Save case and lesson")) {
        ImGui::End();
        return;
    }
    ImGui::InputText("name", in.name, sizeof in.name);
    ImGui::SameLine();
    ImGui::TextColored(kGrey, "(a-z 0-9 _)");
    ImGui::InputText("title", in.title, sizeof in.title);
    const int state = in.build_state.load();
    ImGui::BeginDisabled(state == 1);
    if (ImGui::Button("Save")) instructor_save();
    ImGui::EndDisabled();
    ImGui::TextColored(kGrey, "into %s", content_root_.c_str());
    if (!in.message.empty()) wrapped(in.message_error ? kRed : kGreen, in.message);
    if (state != 0) {
        std::string msg;
        {
            std::lock_guard<std::mutex> lock(in.build_mutex);
            msg = in.build_message;
        }
        if (state == 1) {
            const double t = ImGui::GetTime();
            ImGui::TextColored(kYellow, "Building the case%s", std::string(size_t(t * 2.0) % 4, '.').c_str());
        }
        wrapped(state == 3 ? kRed : (state == 2 ? kGreen : kGrey), msg);
        if (state == 3) {
            ImGui::TextColored(kGrey, "Build it by hand:");
            ImGui::TextWrapped("%s", in.build_command.c_str());
        }
    }
    ImGui::End();
}

void App::instructor_save() {
    Instructor& in = *instructor_;
    const std::string name = in.name, title = in.title;
    std::string chart_path, lesson_path;
    const std::string err = save_instructor_lesson(in.chart, name, title, content_root_, &chart_path, &lesson_path);
    in.message_error = !err.empty();
    if (!err.empty()) {
        in.message = err;
        return;
    }
    const std::string out = (fs::path(default_cases_dir()) / name).lexically_normal().string();
    in.message = "Saved " + chart_path + " and " + lesson_path;
    in.build_command = "sulcus-cli content case " + chart_path + " --out " + out;
    if (in.builder.joinable()) in.builder.join();
    {
        std::lock_guard<std::mutex> lock(in.build_mutex);
        in.build_message = in.build_command;
    }
    in.build_state = 1;
    // The build takes seconds: on a thread of its own, the window stays live. It reads only copies.
    in.builder = std::thread([&in, chart = in.chart, out, lesson_path]() {
        std::string msg;
        bool ok = false;
        try {
            const ProbeKind kind = ProbeKind::Williams;  // the starter lesson's probe
            CaseSettings settings;
            settings.probe_profile_m = probe_radius_profile(make_probe_tip_collision(kind), settings.probe_profile_step_m);
            for (size_t i = 0; i < settings.probe_profile_m.size(); ++i)
                if (double(i) * settings.probe_profile_step_m >= settings.probe_profile_m[i]) {
                    settings.probe_radius_m = settings.probe_profile_m[i];
                    break;
                }
            const PatientCase pc = build_case(chart, settings);
            msg = write_case(pc, kind, out);
            ok = msg.empty();
            if (ok) msg = "Built " + out + ": run it with sulcus --lesson " + lesson_path;
        } catch (const std::exception& e) {
            msg = out + ": " + e.what();
        }
        {
            std::lock_guard<std::mutex> lock(in.build_mutex);
            in.build_message = msg;
        }
        in.build_state = ok ? 2 : 3;
    });
}

}  // namespace sulcus::desktop
