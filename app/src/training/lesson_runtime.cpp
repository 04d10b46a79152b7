// The lesson runtime: steps, rules and per-site measurements from servo snapshots and UI events.
#include "sulcus/app/lesson_runtime.h"
#include "sulcus/app/text.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace sulcus {

namespace {

bool is_interproximal(Site s) { return s != Site::B && s != Site::L; }

}  // namespace

bool is_lingual_site(Site s) { return s == Site::ML || s == Site::L || s == Site::DL; }

std::string chart_depth_event(const SiteRef& site, double pd_mm) {
    nlohmann::json j;
    j["site"] = site_ref_name(site);
    j["pd_mm"] = pd_mm;
    return j.dump();
}

std::string chart_bop_event(const SiteRef& site, bool bop) {
    nlohmann::json j;
    j["site"] = site_ref_name(site);
    j["bop"] = bop;
    return j.dump();
}

const char* feedback_level_name(FeedbackLevel l) {
    switch (l) {
        case FeedbackLevel::Hint: return "hint";
        case FeedbackLevel::Note: return "note";
        case FeedbackLevel::Warning: return "warning";
        case FeedbackLevel::Step: return "step";
    }
    return "note";
}

LessonRuntime::LessonRuntime(const Lesson& lesson, const std::vector<SiteFrame>& sites, const Chart& reference)
    : lesson_(lesson) {
    const std::vector<SiteRef> targets = lesson_.target_sites();
    auto in_lesson = [&](int fdi) { return std::find(lesson_.teeth.begin(), lesson_.teeth.end(), fdi) != lesson_.teeth.end(); };
    for (const SiteFrame& f : sites) {
        if (!in_lesson(f.fdi)) continue;
        SiteMeasure m;
        m.ref = {f.fdi, f.site};
        m.target = std::find(targets.begin(), targets.end(), m.ref) != targets.end();
        m.interproximal = is_interproximal(f.site);
        if (const auto t = reference.teeth.find(f.fdi); t != reference.teeth.end()) {
            if (const auto& rec = t->second.sites[static_cast<std::size_t>(f.site)]) {
                m.reference_pd_mm = rec->pd_mm;
                m.reference_gm_mm = rec->gm_mm;
                m.reference_bop = rec->bop;
            }
        }
        frames_.push_back(f);
        measures_.push_back(m);
        const Vec3 axis = glm::normalize(f.axis);
        tangent_.push_back(glm::normalize(glm::cross(axis, f.outward)));
    }
    // Toward the contact: each tooth's mesial direction from its own sites (margin of MB minus DB,
    // ML minus DL, across the long axis), so mirrored quadrants need no special case.
    contact_dir_.assign(frames_.size(), Vec3(0.0));
    for (std::size_t i = 0; i < frames_.size(); ++i) {
        if (!measures_[i].interproximal) continue;
        Vec3 mesial(0.0);
        for (std::size_t j = 0; j < frames_.size(); ++j) {
            if (frames_[j].fdi != frames_[i].fdi) continue;
            const Site s = frames_[j].site;
            if (s == Site::MB || s == Site::ML) mesial += frames_[j].margin_point;
            if (s == Site::DB || s == Site::DL) mesial -= frames_[j].margin_point;
        }
        const Vec3 axis = glm::normalize(frames_[i].axis);
        mesial -= glm::dot(mesial, axis) * axis;
        const double len = glm::length(mesial);
        if (!(len > 0.0)) continue;
        const bool mesial_site = frames_[i].site == Site::MB || frames_[i].site == Site::ML;
        contact_dir_[i] = (mesial_site ? 1.0 : -1.0) * mesial / len;
    }
    progress_.resize(lesson_.steps.size());
    for (std::size_t k = 0; k < progress_.size(); ++k) {
        progress_[k].satisfied.assign(lesson_.steps[k].sites.size(), false);
        progress_[k].hint_shown.assign(lesson_.steps[k].hints.size(), false);
    }
    rule_last_s_.assign(lesson_.rules.size(), -std::numeric_limits<double>::infinity());
    rule_active_.assign(lesson_.rules.size(), false);
}

int LessonRuntime::measure_index(const SiteRef& ref) const {
    for (std::size_t i = 0; i < measures_.size(); ++i)
        if (measures_[i].ref == ref) return static_cast<int>(i);
    return -1;
}

void LessonRuntime::note(FeedbackLevel level, const std::string& source, const std::string& message) {
    Feedback f;
    f.tick = ticks_ > 0 ? last_tick_ : 0;
    f.time_s = last_s_;
    f.level = level;
    f.source = source;
    f.message = message;
    feedback_.push_back(std::move(f));
}

int LessonRuntime::withdrawals(int fdi, bool lingual) const {
    int n = 0;
    for (const SiteMeasure& m : measures_)
        if (m.ref.fdi == fdi && is_lingual_site(m.ref.site) == lingual) n += m.withdrawals;
    return n;
}

bool LessonRuntime::complete() const { return current_ >= static_cast<int>(lesson_.steps.size()); }

bool LessonRuntime::site_satisfied(const SiteMeasure& m, StepCondition c) const {
    switch (c) {
        case StepCondition::Charted: return m.charted_pd_mm.has_value();
        case StepCondition::Probed:
            return m.visited && m.deepest_m * 1e3 >= m.reference_pd_mm - lesson_.rubric.depth_pass_mm;
        case StepCondition::Walked: return m.advance_m() * 1e3 >= lesson_.rubric.walk_advance_mm;
        case StepCondition::Acknowledged: return false;
    }
    return false;
}

void LessonRuntime::satisfy(int step, std::size_t k) {
    StepProgress& p = progress_[static_cast<std::size_t>(step)];
    const LessonStep& st = lesson_.steps[static_cast<std::size_t>(step)];
    if (st.order == StepOrder::Listed && k != p.next_site) {
        ++p.order_violations;
        note(FeedbackLevel::Note, st.id,
             site_ref_name(st.sites[k]) + " before " + site_ref_name(st.sites[p.next_site]) +
                 ": take the sites in the order listed");
    }
    p.satisfied[k] = true;
    while (p.next_site < p.satisfied.size() && p.satisfied[p.next_site]) ++p.next_site;
}

void LessonRuntime::advance_steps() {
    const int n = static_cast<int>(lesson_.steps.size());
    while (current_ < n && ticks_ > 0) {
        const LessonStep& st = lesson_.steps[static_cast<std::size_t>(current_)];
        StepProgress& p = progress_[static_cast<std::size_t>(current_)];
        if (!p.started) {
            p.started = true;
            p.start_s = last_s_;
            note(FeedbackLevel::Step, st.id,
                 "Step " + std::to_string(current_ + 1) + " of " + std::to_string(n) + ": " + st.instruction);
        }
        if (st.complete != StepCondition::Acknowledged) {
            for (std::size_t k = 0; k < st.sites.size(); ++k) {
                if (p.satisfied[k]) continue;
                const int mi = measure_index(st.sites[k]);
                if (mi >= 0 && site_satisfied(measures_[static_cast<std::size_t>(mi)], st.complete)) satisfy(current_, k);
            }
            if (p.next_site < p.satisfied.size()) return;
        } else if (!p.completed) {
            return;  // waits for lesson.next
        }
        p.completed = true;
        p.end_s = last_s_;
        note(FeedbackLevel::Step, st.id, "Step " + std::to_string(current_ + 1) + " done in " + format_text("%.1f", p.end_s - p.start_s) + " s");
        ++current_;
    }
    if (current_ >= n && ticks_ > 0 && !ended_ && n > 0 && progress_.back().completed && end_note_ == false) {
        end_note_ = true;
        note(FeedbackLevel::Step, "lesson", "Every step is done");
    }
}

void LessonRuntime::on_event(std::string_view kind, std::string_view text) {
    if (ended_) return;
    const bool chart_event = kind == kEventChartDepth || kind == kEventChartBop || kind == kEventChartGm || kind == kEventChartClear;
    if (!chart_event && kind != kEventLessonNext && kind != kEventLessonEnd) return;
    const std::string kind_s(kind);
    auto bad = [&](const std::string& why) {
        ++bad_events_;
        note(FeedbackLevel::Note, "input", "ignored " + kind_s + " event: " + why);
    };
    const nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
    if (j.is_discarded() || !j.is_object()) return bad("its payload is not a JSON object");

    if (kind == kEventLessonEnd) {
        ended_ = true;
        end_s_ = last_s_;
        return;
    }
    if (kind == kEventLessonNext) {
        if (complete()) return;
        StepProgress& p = progress_[static_cast<std::size_t>(current_)];
        const LessonStep& st = lesson_.steps[static_cast<std::size_t>(current_)];
        if (!p.started) {
            p.started = true;
            p.start_s = last_s_;
        }
        if (st.complete != StepCondition::Acknowledged) {
            // Moving on before the step's condition holds skips it; the sites stay unscored by it.
            p.skipped = true;
            p.end_s = last_s_;
            note(FeedbackLevel::Note, st.id, "Step " + std::to_string(current_ + 1) + " skipped");
            ++current_;
        } else {
            p.completed = true;
        }
        advance_steps();
        return;
    }

    const auto site_it = j.find("site");
    SiteRef ref;
    if (site_it == j.end() || !site_it->is_string() || !parse_site_ref(site_it->get<std::string>(), &ref))
        return bad("no valid \"site\"");
    const int mi = measure_index(ref);
    if (mi < 0) return bad(site_ref_name(ref) + " is not a site of this lesson's teeth");
    SiteMeasure& m = measures_[static_cast<std::size_t>(mi)];
    if (kind == kEventChartDepth) {
        const auto v = j.find("pd_mm");
        if (v == j.end() || !v->is_number() || !std::isfinite(v->get<double>()) || v->get<double>() < 0.0 ||
            v->get<double>() > kMaxProbingDepthMm)
            return bad("\"pd_mm\" must be a number from 0 to 15");
        m.charted_pd_mm = v->get<double>();
        m.charted_time_s = last_s_;
    } else if (kind == kEventChartBop) {
        const auto v = j.find("bop");
        if (v == j.end() || !v->is_boolean()) return bad("\"bop\" must be true or false");
        m.charted_bop = v->get<bool>();
    } else if (kind == kEventChartGm) {
        const auto v = j.find("gm_mm");
        if (v == j.end() || !v->is_number() || !(v->get<double>() >= kMinGingivalMarginMm && v->get<double>() <= kMaxGingivalMarginMm))
            return bad("\"gm_mm\" must be a number from -12 to 8");
        m.charted_gm_mm = v->get<double>();
    } else {  // chart.clear
        m.charted_pd_mm.reset();
        m.charted_bop = false;
        m.charted_gm_mm = 0.0;
    }
    advance_steps();
}

void LessonRuntime::on_tick(const ServoSnapshot& s) {
    if (ended_) return;
    const Rubric& rb = lesson_.rubric;
    const double dt = ticks_ > 0 ? s.time_s - last_s_ : 0.0;
    if (ticks_ == 0) start_s_ = s.time_s;
    last_s_ = s.time_s;
    end_s_ = s.time_s;
    last_tick_ = s.tick;
    ++ticks_;

    // The force on the tissue (the renderer's, whatever the device renders of it), held over the
    // interval since the previous tick.
    const double f = glm::length(s.rendered_force_N);
    max_force_N_ = std::max(max_force_N_, f);
    if (f > rb.force_warning_N) time_above_warning_s_ += dt;
    if (f >= rb.force_trauma_N) time_at_trauma_s_ += dt;

    reading_ = read_probe(frames_, s.graphic);
    reading_site_ = reading_.site_index;
    const Vec3 tip = s.graphic.position;

    // A withdrawal: the tip rises above the margin of the sulcus it was in.
    if (in_site_ >= 0) {
        const SiteFrame& fr = frames_[static_cast<std::size_t>(in_site_)];
        const double height = glm::dot(tip - fr.margin_point, glm::normalize(fr.axis));
        if (height > 0.0) {
            SiteMeasure& m = measures_[static_cast<std::size_t>(in_site_)];
            ++m.withdrawals;
            // A note while the current step still has sites to take on that side of that tooth.
            bool stroke_under_way = false;
            if (!complete()) {
                const LessonStep& st = lesson_.steps[static_cast<std::size_t>(current_)];
                const StepProgress& p = progress_[static_cast<std::size_t>(current_)];
                for (std::size_t k = 0; k < st.sites.size(); ++k)
                    if (!p.satisfied[k] && st.sites[k].fdi == m.ref.fdi && is_lingual_site(st.sites[k].site) == is_lingual_site(m.ref.site))
                        stroke_under_way = true;
            }
            for (std::size_t r = 0; r < lesson_.rules.size(); ++r) {
                const LessonRule& rule = lesson_.rules[r];
                if (rule.when != RuleTrigger::LeftSulcus || !stroke_under_way) continue;
                if (s.time_s - rule_last_s_[r] < rule.cooldown_s) continue;
                rule_last_s_[r] = s.time_s;
                note(rule.level == RuleLevel::Warning ? FeedbackLevel::Warning : FeedbackLevel::Note, rule.id,
                     rule.message + " (" + site_ref_name(m.ref) + ")");
            }
            in_site_ = -1;
        }
    }

    if (reading_.site_index >= 0 && reading_.in_sulcus) {
        const std::size_t i = static_cast<std::size_t>(reading_.site_index);
        in_site_ = reading_.site_index;
        SiteMeasure& m = measures_[i];
        const SiteFrame& fr = frames_[i];
        const double along = glm::dot(tip - fr.margin_point, tangent_[i]);
        if (!m.visited) {
            m.visited = true;
            m.walk_min_m = m.walk_max_m = along;
        }
        m.walk_min_m = std::min(m.walk_min_m, along);
        m.walk_max_m = std::max(m.walk_max_m, along);
        if (reading_.depth_m > m.deepest_m) {
            m.deepest_m = reading_.depth_m;
            m.deepest_time_s = s.time_s;
            m.force_at_deepest_N = f;
            m.angle_at_deepest_rad = reading_.angle_rad;
            if (m.interproximal) {
                // Tilt toward the contact: the probe's axis (toward the handle) leaning away from
                // the contact puts the tip under it.
                const Vec3 probe_axis = glm::normalize(s.graphic.rotate(Vec3(0.0, 1.0, 0.0)));
                const Vec3 axis = glm::normalize(fr.axis);
                m.tilt_at_deepest_rad = std::atan2(-glm::dot(probe_axis, contact_dir_[i]), glm::dot(probe_axis, axis));
            }
        }
        m.max_force_N = std::max(m.max_force_N, f);
        if (f > rb.force_warning_N) m.time_above_warning_s += dt;
        if (f >= rb.force_trauma_N) m.time_at_trauma_s += dt;
    }

    // Force rules fire when the force crosses their threshold, at most once per cooldown.
    for (std::size_t r = 0; r < lesson_.rules.size(); ++r) {
        const LessonRule& rule = lesson_.rules[r];
        if (rule.when == RuleTrigger::LeftSulcus) continue;
        const bool above = rule.when == RuleTrigger::ForceAbove ? f > rule.threshold_N : f >= rule.threshold_N;
        if (above && !rule_active_[r] && s.time_s - rule_last_s_[r] >= rule.cooldown_s) {
            rule_last_s_[r] = s.time_s;
            std::string where = reading_site_ >= 0 ? " at " + site_ref_name(measures_[static_cast<std::size_t>(reading_site_)].ref) : "";
            note(rule.level == RuleLevel::Warning ? FeedbackLevel::Warning : FeedbackLevel::Note, rule.id,
                 rule.message + " (" + format_text("%.3f", f) + " N" + where + ")");
        }
        rule_active_[r] = above;
    }

    advance_steps();

    // Hints of the running step, once it has run long enough.
    if (!complete()) {
        const LessonStep& st = lesson_.steps[static_cast<std::size_t>(current_)];
        StepProgress& p = progress_[static_cast<std::size_t>(current_)];
        for (std::size_t h = 0; h < st.hints.size(); ++h) {
            if (p.hint_shown[h] || s.time_s - p.start_s < st.hints[h].after_s) continue;
            p.hint_shown[h] = true;
            note(FeedbackLevel::Hint, st.id, st.hints[h].text);
        }
    }
}

void LessonRuntime::finish() {
    if (ended_) return;
    ended_ = true;
    end_s_ = last_s_;
}

Chart LessonRuntime::trainee_chart() const {
    Chart c;
    for (int fdi : lesson_.teeth) c.teeth[fdi].fdi = fdi;
    for (const SiteMeasure& m : measures_) {
        if (!m.charted_pd_mm) continue;
        SiteRecord r;
        r.pd_mm = *m.charted_pd_mm;
        r.gm_mm = m.charted_gm_mm;
        r.bop = m.charted_bop;
        c.teeth[m.ref.fdi].sites[static_cast<std::size_t>(m.ref.site)] = r;
    }
    return c;
}

}  // namespace sulcus
