// The app's panels (Dear ImGui): lesson, periodontal chart, force, device, settings and the
// magnified pocket. They read the App's state and change only UiState, the chart (through posted
// events) and the view. The running lesson's panel and instructor mode are in lesson_ui.cpp.
#include "desktop/app.h"

#include "sulcus/content/tooth.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

namespace sulcus::desktop {

namespace {

constexpr double kTargetLow_N = 0.20, kTargetHigh_N = 0.25, kTrauma_N = 0.5;
constexpr double kGramsPerNewton = 1000.0 / 9.80665;
const ImVec4 kGreen(0.35f, 0.85f, 0.45f, 1.0f), kOrange(1.0f, 0.65f, 0.2f, 1.0f), kRed(1.0f, 0.3f, 0.3f, 1.0f),
    kGrey(0.6f, 0.6f, 0.6f, 1.0f);

// ImGui::TextColored that wraps at the panel's edge.
template <class... Args>
void say(const ImVec4& colour, const char* fmt, Args... args) {
    ImGui::PushStyleColor(ImGuiCol_Text, colour);
    ImGui::TextWrapped(fmt, args...);
    ImGui::PopStyleColor();
}

bool interproximal(Site s) { return s != Site::B && s != Site::L; }

// Sites of a tooth as a chart row shows them: buccal row MB B DB, lingual row ML L DL.
constexpr Site kBuccalRow[3] = {Site::MB, Site::B, Site::DB};
constexpr Site kLingualRow[3] = {Site::ML, Site::L, Site::DL};

}  // namespace

void App::draw_panels() {
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    const float left_w = 340.0f, right_w = 500.0f, pad = 8.0f;
    ImGui::SetNextWindowPos(ImVec2(pad, pad), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(left_w, 300), ImGuiCond_FirstUseEver);
    panel_lesson();
    ImGui::SetNextWindowPos(ImVec2(pad, 316), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(left_w, 230), ImGuiCond_FirstUseEver);
    panel_device();
    ImGui::SetNextWindowPos(ImVec2(pad, 554), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(left_w, std::max(200.0f, size.y - 562)), ImGuiCond_FirstUseEver);
    panel_settings();
    // The chart is as wide as its teeth need (84 px labels, 34 px a site), within reason.
    const float chart_w = std::clamp(84.0f + 34.0f * 3.0f * float(manifest_.chart.teeth.size()) + 40.0f, right_w,
                                     0.55f * size.x);
    ImGui::SetNextWindowPos(ImVec2(size.x - chart_w - pad, pad), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(chart_w, 420), ImGuiCond_FirstUseEver);
    panel_chart();
    ImGui::SetNextWindowPos(ImVec2(size.x - 380 - pad, 436), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(380, 420), ImGuiCond_FirstUseEver);
    panel_inset();
    ImGui::SetNextWindowPos(ImVec2(left_w + 2 * pad, size.y - 250 - pad), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(std::max(300.0f, size.x - left_w - 380 - 4 * pad), 250), ImGuiCond_FirstUseEver);
    panel_force();
}

void App::panel_lesson() {
    if (!ImGui::Begin("Lesson")) {
        ImGui::End();
        return;
    }
    if (lesson_ && lesson_->runtime) {
        panel_lesson_steps();
    } else {
        ImGui::Text("Case: %s", case_name_.c_str());
        ImGui::TextWrapped("Chart six sites on every tooth. Slide the probe into the sulcus parallel to the long axis, "
                           "walk it along the pocket floor at 0.20-0.25 N, read the marking at the gingival margin and "
                           "press Space to chart the depth.");
        const int done = chart_ ? chart_->sites_charted() : 0, total = chart_ ? chart_->sites_total() : 0;
        char label[64];
        std::snprintf(label, sizeof label, "%d / %d sites charted", done, total);
        ImGui::ProgressBar(total ? float(done) / float(total) : 0.0f, ImVec2(-1, 0), label);
    }
    ImGui::Separator();

    const double force = live_.has_snapshot ? glm::length(live_.snapshot.rendered_force_N) : 0.0;
    if (reading_.site_index >= 0) {
        const SiteFrame& s = manifest_.sites[size_t(reading_.site_index)];
        const double angle_deg = reading_.angle_rad * 180.0 / std::numbers::pi;
        ImGui::Text("Probing %d %s (Universal %d)", s.fdi, site_name(s.site), universal_number(s.fdi));
        ImGui::TextWrapped("Depth %.1f mm below the margin, %.0f deg to the long axis", reading_.depth_m * 1e3, angle_deg);
        // Feedback a trainee can act on, most important first.
        if (force >= kTrauma_N)
            say(kRed, "Trauma: %.2f N. Ease off; 0.5 N and more tears the attachment.", force);
        else if (force > kTargetHigh_N)
            say(kOrange, "Too firm: %.2f N. Aim for 0.20-0.25 N; more hurts.", force);
        else if (reading_.in_sulcus && force < kTargetLow_N)
            say(kGrey, "Walk down to the floor: %.2f N, aim for 0.20-0.25 N.", force);
        else if (reading_.in_sulcus)
            say(kGreen, "Good pressure: %.2f N. Read the marking and chart it.", force);
        const double tolerance_deg = interproximal(s.site) ? 30.0 : 20.0;
        if (reading_.in_sulcus && angle_deg > tolerance_deg)
            say(kOrange, interproximal(s.site) ? "Tilt only slightly under the contact (now %.0f deg)."
                                                              : "Keep the probe parallel to the long axis (now %.0f deg).",
                               angle_deg);
    } else {
        say(kGrey, "Not at a site. Bring the tip to the gingival margin of a tooth.");
        if (force > kTargetHigh_N) say(kOrange, "Force %.2f N: you are pressing on the tooth or gum.", force);
    }
    ImGui::Separator();
    ImGui::TextWrapped("Highest force %.2f N; above 0.25 N for %.1f s, above 0.5 N for %.1f s", max_force_N_,
                time_above_025_s_, time_above_05_s_);
    ImGui::End();
}

void App::panel_chart() {
    if (instructor_) {
        panel_instructor();
        return;
    }
    if (!ImGui::Begin("Periodontal chart") || !chart_) {
        ImGui::End();
        return;
    }
    ImGui::Checkbox("Show the reference chart (instructor)", &ui_.show_reference);
    const Chart& ref = manifest_.chart;
    const int n_teeth = int(ref.teeth.size());
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_ScrollX;
    if (ImGui::BeginTable("chart", 1 + 3 * n_teeth, flags)) {
        ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 84.0f);
        for (int i = 0; i < 3 * n_teeth; ++i) ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 26.0f);
        // Header: FDI with Universal beside it, then the site names.
        ImGui::TableNextRow(ImGuiTableRowFlags_Headers);
        ImGui::TableSetColumnIndex(0);
        ImGui::TextUnformatted("FDI (Univ.)");
        int col = 1;
        for (const auto& [fdi, tooth] : ref.teeth) {
            ImGui::TableSetColumnIndex(col);
            ImGui::Text("%d", fdi);
            ImGui::TableSetColumnIndex(col + 1);
            ImGui::TextColored(kGrey, "(%d)", universal_number(fdi));
            col += 3;
        }
        auto site_row = [&](const char* what, const Site* row, int kind) {
            ImGui::TableNextRow();
            ImGui::TableSetColumnIndex(0);
            ImGui::TextUnformatted(what);
            int c = 1;
            for (const auto& [fdi, tooth] : ref.teeth) {
                for (int k = 0; k < 3; ++k, ++c) {
                    ImGui::TableSetColumnIndex(c);
                    const Site site = row[k];
                    const std::optional<SiteRecord>& r = tooth.sites[size_t(site)];
                    char text[32] = "";
                    ImVec4 colour = ImGui::GetStyleColorVec4(ImGuiCol_Text);
                    const std::optional<double> pd = chart_->pd_mm(fdi, site);
                    switch (kind) {
                        case 0:  // site names
                            std::snprintf(text, sizeof text, "%s", site_name(site));
                            colour = kGrey;
                            break;
                        case 1:  // PD
                            if (pd) std::snprintf(text, sizeof text, "%.0f", *pd);
                            if (ui_.show_reference && r) {
                                if (pd) colour = std::abs(*pd - r->pd_mm) <= 1.0 ? kGreen : kRed;
                                std::snprintf(text + std::strlen(text), sizeof text - std::strlen(text), "%s%.0f%s",
                                              pd ? "/" : "(", r->pd_mm, pd ? "" : ")");
                            }
                            if (pd && *pd >= 4.0 && !ui_.show_reference) colour = kOrange;
                            break;
                        case 2:  // GM
                            if (pd || chart_->gm_mm(fdi, site) != 0.0)
                                std::snprintf(text, sizeof text, "%.0f", chart_->gm_mm(fdi, site));
                            break;
                        case 3:  // CAL
                            if (const std::optional<double> cal = chart_->cal_mm(fdi, site))
                                std::snprintf(text, sizeof text, "%.0f", *cal);
                            break;
                        default:  // BOP
                            if (chart_->bop(fdi, site)) {
                                std::snprintf(text, sizeof text, "+");
                                colour = kRed;
                            } else if (pd) {
                                std::snprintf(text, sizeof text, "-");
                            }
                            break;
                    }
                    const bool selected = ui_.selected_fdi == fdi && ui_.selected_site == int(site);
                    ImGui::PushID(fdi * 100 + int(site) * 10 + kind);
                    ImGui::PushStyleColor(ImGuiCol_Text, colour);
                    if (ImGui::Selectable(text[0] ? text : " ", selected)) {
                        ui_.selected_fdi = fdi;
                        ui_.selected_site = int(site);
                        ui_.draw.highlight_fdi = fdi;
                    }
                    ImGui::PopStyleColor();
                    ImGui::PopID();
                }
            }
        };
        site_row("Buccal", kBuccalRow, 0);
        site_row("PD", kBuccalRow, 1);
        site_row("GM", kBuccalRow, 2);
        site_row("CAL", kBuccalRow, 3);
        site_row("BOP", kBuccalRow, 4);
        site_row("Lingual", kLingualRow, 0);
        site_row("PD", kLingualRow, 1);
        site_row("GM", kLingualRow, 2);
        site_row("CAL", kLingualRow, 3);
        site_row("BOP", kLingualRow, 4);
        ImGui::EndTable();
    }
    // The selected site's entries, editable.
    if (ui_.selected_fdi != 0 && ui_.selected_site >= 0) {
        const int fdi = ui_.selected_fdi;
        const Site site = kAllSites[size_t(ui_.selected_site)];
        ImGui::Separator();
        ImGui::Text("%d %s (Universal %d)", fdi, site_name(site), universal_number(fdi));
        int pd = int(std::lround(chart_->pd_mm(fdi, site).value_or(0.0)));
        int gm = int(std::lround(chart_->gm_mm(fdi, site)));
        bool bop = chart_->bop(fdi, site);
        ImGui::SetNextItemWidth(110);
        // Each entry is posted to the servo loop (recorded, and read by a running lesson).
        if (ImGui::InputInt("PD mm", &pd)) chart_depth(fdi, site, std::clamp(pd, 0, 15));
        ImGui::SameLine();
        ImGui::SetNextItemWidth(110);
        if (ImGui::InputInt("GM mm", &gm)) chart_gm(fdi, site, std::clamp(gm, -12, 8));
        ImGui::SameLine();
        if (ImGui::Checkbox("BOP", &bop)) chart_bop(fdi, site, bop);
        if (const std::optional<double> cal = chart_->cal_mm(fdi, site)) ImGui::Text("CAL %.0f mm (PD - GM)", *cal);
    }
    ImGui::End();
}

void App::panel_force() {
    if (!ImGui::Begin("Force")) {
        ImGui::End();
        return;
    }
    const double force = live_.has_snapshot ? glm::length(live_.snapshot.rendered_force_N) : 0.0;
    const double torque = live_.has_snapshot ? glm::length(live_.snapshot.rendered_torque_Nm) : 0.0;
    const double t1 = live_.has_snapshot ? live_.snapshot.time_s : 0.0;
    ImDrawList* dl = ImGui::GetWindowDrawList();

    // The gauge: 0 .. 0.6 N with the target band, the value in N and in grams.
    {
        const float w = ImGui::GetContentRegionAvail().x, h = 22.0f;
        const ImVec2 p = ImGui::GetCursorScreenPos();
        const double full = 0.6;
        auto x_of = [&](double f) { return p.x + float(std::clamp(f / full, 0.0, 1.0)) * w; };
        dl->AddRectFilled(p, ImVec2(p.x + w, p.y + h), IM_COL32(40, 42, 48, 255));
        dl->AddRectFilled(ImVec2(x_of(kTargetLow_N), p.y), ImVec2(x_of(kTargetHigh_N), p.y + h), IM_COL32(60, 140, 80, 255));
        const ImU32 bar = force >= kTrauma_N ? IM_COL32(230, 70, 70, 255)
                          : force > kTargetHigh_N ? IM_COL32(240, 160, 50, 255)
                                                  : IM_COL32(200, 200, 210, 255);
        dl->AddRectFilled(ImVec2(p.x, p.y + 6), ImVec2(x_of(force), p.y + h - 6), bar);
        dl->AddLine(ImVec2(x_of(kTrauma_N), p.y), ImVec2(x_of(kTrauma_N), p.y + h), IM_COL32(230, 70, 70, 255), 2.0f);
        ImGui::Dummy(ImVec2(w, h));
        ImGui::Text("%.3f N  =  %.1f g      torque %.2f N mm", force, force * kGramsPerNewton, torque * 1e3);
    }

    // Force over the last seconds: the per-pixel envelope of every servo tick.
    auto plot = [&](const char* title, bool is_torque, float height, double full_scale, double unit) {
        const float w = ImGui::GetContentRegionAvail().x;
        const ImVec2 p = ImGui::GetCursorScreenPos();
        const float left = 46.0f;
        const float pw = std::max(10.0f, w - left);
        std::vector<float> lo, hi;
        history_.envelope(t1, ui_.plot_window_s, size_t(pw), is_torque, lo, hi);
        double top = full_scale;
        for (float v : hi)
            if (!std::isnan(v)) top = std::max(top, double(v) * 1.1);
        auto y_of = [&](double v) { return p.y + height - float(std::clamp(v / top, 0.0, 1.0)) * height; };
        const ImVec2 a(p.x + left, p.y), b(p.x + left + pw, p.y + height);
        dl->AddRectFilled(a, b, IM_COL32(30, 32, 36, 255));
        if (!is_torque) {
            dl->AddRectFilled(ImVec2(a.x, y_of(kTargetHigh_N)), ImVec2(b.x, y_of(kTargetLow_N)), IM_COL32(60, 140, 80, 110));
            dl->AddLine(ImVec2(a.x, y_of(kTargetHigh_N)), ImVec2(b.x, y_of(kTargetHigh_N)), IM_COL32(240, 160, 50, 200));
            dl->AddLine(ImVec2(a.x, y_of(kTrauma_N)), ImVec2(b.x, y_of(kTrauma_N)), IM_COL32(230, 70, 70, 200));
        }
        for (size_t i = 0; i < lo.size(); ++i) {
            if (std::isnan(lo[i])) continue;
            const float x = a.x + float(i) + 0.5f;
            dl->AddLine(ImVec2(x, y_of(lo[i])), ImVec2(x, y_of(hi[i]) - 1.0f), IM_COL32(120, 190, 255, 255), 1.0f);
        }
        char text[48];
        for (double v : {0.0, 0.5 * top, top}) {
            std::snprintf(text, sizeof text, "%.2f", v * unit);
            dl->AddText(ImVec2(p.x, y_of(v) - 7), IM_COL32(170, 170, 170, 255), text);
        }
        std::snprintf(text, sizeof text, "%s, last %.0f s", title, ui_.plot_window_s);
        dl->AddText(ImVec2(a.x + 6, a.y + 2), IM_COL32(200, 200, 200, 255), text);
        ImGui::Dummy(ImVec2(w, height + 4));
    };
    const float avail = ImGui::GetContentRegionAvail().y;
    plot("force N (band 0.20-0.25 N)", false, std::max(60.0f, avail * 0.62f), 0.6, 1.0);
    plot("torque N mm", true, std::max(40.0f, ImGui::GetContentRegionAvail().y - 6), 0.001, 1e3);
    ImGui::End();
}

void App::panel_device() {
    if (!ImGui::Begin("Device")) {
        ImGui::End();
        return;
    }
    ImGui::TextWrapped("%s", device_label_.c_str());
    const ServoSnapshot& s = live_.snapshot;
    const bool ok = live_.has_snapshot && s.device_ok;
    ImGui::TextColored(ok ? kGreen : kRed, "%s", ok ? "connected" : "no reading");
    ImGui::SameLine();
    ImGui::Text("safety: %s", to_string(loop_.safety_state()));
    ImGui::Text("servo %.0f Hz (nominal %.0f)%s", live_.rate_hz, servo_config_.rate_hz,
                loop_.realtime() ? ", SCHED_FIFO" : "");
    ImGui::Text("deadline misses %llu", static_cast<unsigned long long>(live_.has_snapshot ? s.deadline_misses : 0));
    ImGui::Text("step %.0f us (worst in the last second %.0f us)", live_.step_us, live_.step_us_max_1s);
    ImGui::Text("stiffness %.2f N/mm, %.3f N m/rad", scene_.scene.haptic.stiffness_N_per_m * 1e-3,
                scene_.scene.haptic.rotational_stiffness_Nm_per_rad);
    ImGui::Text("sent to the device %.3f N, %.2f N mm", live_.has_snapshot ? glm::length(s.force_N) : 0.0,
                live_.has_snapshot ? glm::length(s.torque_Nm) * 1e3 : 0.0);
    if (mouse_) ImGui::TextColored(kGrey, "No force reaches the mouse: watch the gauge.");
    if (live_.telemetry_drops) ImGui::TextColored(kOrange, "plot samples dropped: %llu",
                                                 static_cast<unsigned long long>(live_.telemetry_drops));
    if (ImGui::Button("Emergency stop (Esc)")) loop_.emergency_stop();
    ImGui::SameLine();
    if (ImGui::Button("Reset safety")) loop_.reset_safety();
    ImGui::End();
}

void App::panel_settings() {
    if (!ImGui::Begin("View and settings")) {
        ImGui::End();
        return;
    }
    ImGui::Checkbox("See-through gingiva (G)", &ui_.translucent_gingiva);
    float alpha = float(ui_.translucent_alpha);
    if (ImGui::SliderFloat("opacity", &alpha, 0.1f, 0.9f, "%.2f")) ui_.translucent_alpha = alpha;
    ImGui::Checkbox("Bone", &ui_.draw.show_bone);
    ImGui::SameLine();
    ImGui::Checkbox("Haptic ghost", &ui_.draw.show_ghost);
    ImGui::SameLine();
    ImGui::Checkbox("Pocket inset", &ui_.show_inset);
    float field_mm = float(ui_.inset_field_m * 1e3);
    if (ImGui::SliderFloat("inset field mm", &field_mm, 3.0f, 20.0f, "%.0f")) ui_.inset_field_m = field_mm * 1e-3;
    float window = float(ui_.plot_window_s);
    if (ImGui::SliderFloat("plot seconds", &window, 1.0f, 15.0f, "%.0f")) ui_.plot_window_s = window;
    ImGui::Separator();
    ImGui::TextUnformatted("Views (keys 1-6, Shift: lingual; 0: whole case)");
    if (ImGui::Button("Whole case")) set_view(0, false);
    for (int s = 1; s <= 6; ++s) {
        bool present = false;
        for (const ToothSpot& t : view_->teeth()) present |= sextant_of(t.fdi) == s;
        if (!present) continue;
        ImGui::PushID(s);
        if (ImGui::Button(sextant_label(s))) set_view(s, false);
        ImGui::SameLine();
        if (ImGui::Button("lingual")) set_view(s, true);
        ImGui::PopID();
    }
    ImGui::Separator();
    ImGui::TextColored(kGrey, "Mouse: left-drag moves the probe, wheel moves it in depth, right-drag tilts it,\n"
                              "Ctrl for fine motion; middle-drag orbits, Shift+middle pans, Ctrl+wheel zooms.\n"
                              "Keys: W/S insert/withdraw, A/D turn, R reset, Space chart the reading.");
    ImGui::End();
}

void App::panel_inset() {
    if (!ui_.show_inset) return;
    if (!ImGui::Begin("Pocket (magnified)")) {
        ImGui::End();
        return;
    }
    if (inset_texture_) {
        const float side = std::min(ImGui::GetContentRegionAvail().x, ImGui::GetContentRegionAvail().y - 24);
        ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(inset_texture_)), ImVec2(side, side),
                     ImVec2(0, 1), ImVec2(1, 0));
    }
    if (reading_.site_index >= 0) {
        const SiteFrame& s = manifest_.sites[size_t(reading_.site_index)];
        ImGui::Text("%d %s: %.1f mm below the margin", s.fdi, site_name(s.site), reading_.depth_m * 1e3);
    } else {
        ImGui::TextColored(kGrey, "field %.0f mm around the tip", ui_.inset_field_m * 1e3);
    }
    ImGui::End();
}

}  // namespace sulcus::desktop
