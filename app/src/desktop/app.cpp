#include "desktop/app.h"

#include "sulcus/content/gltf_io.h"
#include "sulcus/haptics/phantom_device.h"
#include "sulcus/haptics/sim_device.h"
#include "sulcus/haptics/spacemouse_device.h"

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui/backends/imgui_impl_glfw.h>
#include <imgui/backends/imgui_impl_opengl3.h>
#include <nlohmann/json.hpp>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

namespace sulcus::desktop {

namespace fs = std::filesystem;

namespace {

constexpr double kFrameCapHz = 60.0;  // no faster, so the UI leaves the servo thread its core
// Bleeding on probing shows within seconds of the probe reaching the pocket floor; charts record
// it for the whole sextant after about 30 s. The drop shows this long after the site was probed.
constexpr double kBleedDelay_s = 2.0;
// How far the mouse's target may lead the drawn probe (m): 0.6 N at 1 N/mm, past the 0.5 N
// trauma level so the feedback for it can still be seen.
constexpr double kMouseLead_m = 0.6e-3;

double now_s() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

void glfw_error(int code, const char* what) { std::fprintf(stderr, "sulcus: GLFW error %d: %s\n", code, what); }

}  // namespace

App::App(AppOptions options) : options_(std::move(options)) {
    ui_.draw.gingiva_alpha = 1.0;
    ui_.translucent_gingiva = options_.gingiva_alpha < 0.999;
    if (ui_.translucent_gingiva) ui_.translucent_alpha = options_.gingiva_alpha;
    ui_.show_reference = options_.reference;
}

App::~App() {
    if (loop_.running()) loop_.stop();
    if (recorder_) (void)recorder_->close();
    if (instructor_ && instructor_->builder.joinable()) instructor_->builder.join();
    if (imgui_ready_) {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    if (window_) {
        view_.reset();  // its GL objects go while the context is current
        glfwDestroyWindow(window_);
    }
    glfwTerminate();
}

std::string App::load_case() {
    namespace fs = std::filesystem;
    const fs::path dir(options_.case_dir);
    case_name_ = dir.filename().string();
    if (case_name_.empty()) case_name_ = dir.parent_path().filename().string();
    const std::string scene_path = (dir / "scene.json").string();
    if (!model_) {  // a lesson's case comes loaded
        scene_ = load_scene(scene_path);
        for (const std::string& w : scene_.scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
        if (!scene_.ok()) return scene_.errors.front();
        ModelBuild build = build_model(scene_.scene, RendererSettings{});
        if (!build.model) return scene_path + ": " + build.error;
        model_ = std::move(build.model);
    }
    start_pose_ = scene_.scene.trajectory.empty() ? Pose{} : scene_.scene.trajectory.front().pose;

    AssetLoad asset = read_glb((dir / "case.glb").string());
    if (!asset.ok()) return asset.error;
    asset_ = std::move(asset.asset);

    CaseManifestLoad manifest = load_case_manifest(dir.string());
    if (!manifest.ok()) return manifest.errors.front();
    manifest_ = std::move(manifest.manifest);
    chart_.emplace(manifest_.chart);
    probed_at_.assign(manifest_.sites.size(), -1.0);
    if (lesson_) lesson_->runtime = std::make_unique<LessonRuntime>(lesson_->load.lesson, manifest_.sites, manifest_.chart);
    if (options_.instructor) {
        instructor_ = std::make_unique<Instructor>();
        instructor_->chart = manifest_.chart;
        if (content_root_.empty()) content_root_ = options_.content_root.empty() ? default_content_root() : options_.content_root;
    }
    return "";
}

std::string App::start_servo() {
    servo_config_ = ServoConfig{};
    servo_config_.rate_hz = scene_.scene.rate_hz;
    // A lesson's runtime needs every tick: room for 65 s of them should frames stall.
    servo_config_.telemetry_queue = options_.telemetry_queue ? options_.telemetry_queue : lesson_ ? (1u << 16) : 8192;
    servo_config_.step_time_ring = 1u << 17;

    std::string why_not_phantom;
    if (options_.device == "phantom" || options_.device == "auto") {
        auto phantom = std::make_unique<PhantomDevice>(PhantomOptions{});
        // A Phantom is tried by starting the loop on it: no library or no device says why.
        servo_config_.anchor = true;
        servo_config_.anchor_position_m = start_pose_.position;
        if (std::string e = open_recorder("phantom"); !e.empty()) return e;
        const std::string err = loop_.start(servo_config_, *phantom, *model_, recorder_.get());
        if (err.empty()) {
            device_label_ = phantom->capabilities().name;
            device_ = std::move(phantom);
            return "";
        }
        if (options_.device == "phantom") return "phantom: " + err;
        why_not_phantom = err;
        servo_config_.anchor = false;
    }
    if (options_.device == "sim") {
        HandParameters hand;
        hand.dt_s = 1.0 / servo_config_.rate_hz;
        if (scene_.scene.trajectory.empty()) return options_.case_dir + ": the simulated hand needs a trajectory";
        std::vector<TrajectorySample> script = scene_.scene.trajectory;
        if (options_.ticks > 0) {
            // With a tick limit the hand's script ends there and the hand holds still, so the
            // last frame shows that moment however slowly frames are drawn.
            const double t_end = script.front().t + double(options_.ticks) / servo_config_.rate_hz;
            size_t cursor = 0;
            const Pose last = sample_trajectory(script, t_end, cursor);
            while (script.size() > 1 && script.back().t >= t_end) script.pop_back();
            if (script.back().t < t_end) script.push_back({t_end, last});
        }
        device_ = std::make_unique<SimulatedHand>(script, hand);
        device_label_ = "Simulated hand (" + device_->capabilities().name + ")";
        if (std::string e = open_recorder("sim-hand"); !e.empty()) return e;
    } else if (options_.device == "spacemouse") {
        SpaceMouseDeviceConfig sm;
        sm.rate_hz = servo_config_.rate_hz;
        sm.start_pose = start_pose_;
        sm.workspace_min_m = start_pose_.position - Vec3(0.05);
        sm.workspace_max_m = start_pose_.position + Vec3(0.05);
        device_ = std::make_unique<SpaceMouseDevice>(sm);
        device_label_ = "SpaceMouse";
        if (std::string e = open_recorder("spacemouse"); !e.empty()) return e;
    } else {
        MouseDeviceConfig mc;
        mc.rate_hz = servo_config_.rate_hz;
        mc.start_pose = start_pose_;
        mc.workspace_min_m = view_->box_min() - Vec3(0.02);
        mc.workspace_max_m = view_->box_max() + Vec3(0.04);
        auto mouse = std::make_unique<MouseDevice>(mc);
        mouse_ = mouse.get();
        device_ = std::move(mouse);
        device_label_ = "Mouse and keyboard";
        driver_.set_bounds(mc.workspace_min_m, mc.workspace_max_m);
        if (!why_not_phantom.empty())
            std::fprintf(stderr, "sulcus: no haptic device (%s); the mouse drives the probe\n", why_not_phantom.c_str());
        if (std::string e = open_recorder("mouse"); !e.empty()) return e;
    }
    driver_.reset(start_pose_);
    return loop_.start(servo_config_, *device_, *model_, recorder_.get());
}

void App::set_view(int sextant, bool lingual) {
    if (sextant == 0 || !sextant_view(view_->teeth(), sextant, lingual, camera_)) camera_ = overview(view_->teeth());
    ui_.draw.highlight_fdi = 0;
}

int App::run() {
    if (!options_.lesson.empty()) {
        if (std::string err = load_lesson_file(); !err.empty()) {
            std::fprintf(stderr, "sulcus: %s\n", err.c_str());
            return 2;
        }
    }
    if (std::string err = load_case(); !err.empty()) {
        std::fprintf(stderr, "sulcus: %s\n", err.c_str());
        return 2;
    }
    glfwSetErrorCallback(glfw_error);
    if (!glfwInit()) {
        std::fprintf(stderr, "sulcus: no display (GLFW cannot start): use sulcus-cli for headless runs\n");
        return 2;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    window_ = glfwCreateWindow(options_.width, options_.height, ("Sulcus — " + case_name_).c_str(), nullptr, nullptr);
    if (!window_) {
        std::fprintf(stderr, "sulcus: cannot open a %dx%d window with OpenGL 3.3 core\n", options_.width, options_.height);
        return 2;
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    std::fprintf(stderr, "sulcus: OpenGL %s on %s\n", reinterpret_cast<const char*>(glGetString(GL_VERSION)),
                 reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
    // Multisampling costs a software renderer (Mesa llvmpipe under Xvfb) most of its frame rate.
    const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const bool software = renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
    samples_ = options_.msaa >= 0 ? options_.msaa : (software ? 0 : 4);

    // Ours first: ImGui's GLFW backend chains to a callback installed before it.
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, &App::key_callback);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // the same layout at every start (and in screenshots)
    ImGui::StyleColorsDark();
    ImGui::GetStyle().WindowRounding = 4.0f;
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    imgui_ready_ = true;

    view_ = std::make_unique<SceneView>();
    if (std::string err = view_->init(asset_); !err.empty()) {
        std::fprintf(stderr, "sulcus: %s/case.glb: %s\n", options_.case_dir.c_str(), err.c_str());
        return 2;
    }
    set_view(options_.sextant, options_.lingual);

    // Where the session is recorded: as asked, else a lesson's in the sessions folder.
    if (options_.record != "none") record_path_ = options_.record;
    if (options_.record.empty() && lesson_) {
        const fs::path dir = sessions_dir();
        std::error_code ec;
        fs::create_directories(dir, ec);
        if (ec) {
            std::fprintf(stderr, "sulcus: %s: cannot create the sessions folder (%s); use --record FILE or --record none\n",
                         dir.string().c_str(), ec.message().c_str());
            return 2;
        }
        fs::path file = dir / session_file_name(options_.lesson, std::time(nullptr));
        const std::string stem = file.stem().string();
        for (int k = 2; fs::exists(file, ec); ++k) file = dir / (stem + "-" + std::to_string(k) + ".rec");
        record_path_ = file.string();
    }
    if (std::string err = start_servo(); !err.empty()) {
        std::fprintf(stderr, "sulcus: servo loop: %s\n", err.c_str());
        if (recorder_) {  // no session: no recording of it
            (void)recorder_->close();
            recorder_.reset();
            std::error_code ec;
            fs::remove(record_path_, ec);
        }
        return 2;
    }
    if (!loop_.realtime()) std::fprintf(stderr, "warning: %s\n", loop_.realtime_message().c_str());

    const double t_start = now_s();
    double next_frame = t_start;
    int exit_code = 0;
    bool done = false;
    while (!done) {
        glfwPollEvents();
        if (glfwWindowShouldClose(window_)) break;
        drain_telemetry();
        handle_input();
        update_readout();

        ++frames_;
        // Every limit given must be reached: frames drawn, servo seconds (wall clock), servo ticks.
        const bool limited = options_.frames > 0 || options_.seconds > 0.0 || options_.ticks > 0;
        const bool last = limited && (options_.frames <= 0 || frames_ >= options_.frames) &&
                          (options_.seconds <= 0.0 || (live_.has_snapshot && live_.snapshot.time_s >= options_.seconds)) &&
                          (options_.ticks == 0 || (live_.has_snapshot && live_.snapshot.tick + 1 >= options_.ticks));
        draw_frame();
        if (last) {
            int w = 0, h = 0;
            glfwGetFramebufferSize(window_, &w, &h);
            if (!options_.screenshot.empty() && !write_png(options_.screenshot, w, h, false)) exit_code = 1;
            if (!options_.ids.empty() && !write_png(options_.ids, w, h, true)) exit_code = 1;
            done = true;
        }
        glfwSwapBuffers(window_);

        next_frame += 1.0 / kFrameCapHz;
        const double now = now_s();
        if (next_frame > now) std::this_thread::sleep_for(std::chrono::duration<double>(next_frame - now));
        else next_frame = now;
    }
    if (int code = finish_session(); code != 0) exit_code = code;
    const ServoStats st = loop_.stats();
    const double wall = now_s() - t_start;
    std::printf("sulcus %s (%s): %d frames in %.1f s (%.1f fps); servo %llu ticks, %.1f Hz, deadline misses %llu, "
                "step p50/p99/max %.1f/%.1f/%.1f us, max force %.3f N, sites charted %d/%d\n",
                case_name_.c_str(), device_label_.c_str(), frames_, wall, wall > 0 ? frames_ / wall : 0.0,
                static_cast<unsigned long long>(st.ticks), st.achieved_rate_hz,
                static_cast<unsigned long long>(st.deadline_misses), st.step_us.p50, st.step_us.p99, st.step_us.max,
                st.max_force_sent_N, chart_ ? chart_->sites_charted() : 0, chart_ ? chart_->sites_total() : 0);
    if (lesson_ && lesson_->scores) {
        const LessonScores& sc = *lesson_->scores;
        std::printf("sulcus: lesson \"%s\": score %.3f (%s), charted %d/%d\n", lesson_->load.lesson.title.c_str(),
                    sc.overall, sc.passed ? "passed" : "not passed", sc.sites_charted, sc.sites_target);
    }
    if (!options_.report.empty()) write_report(wall);
    if (st.non_finite_sent) exit_code = 1;
    return exit_code;
}

void App::drain_telemetry() {
    ServoSnapshot s;
    while (loop_.pop_telemetry(s)) {
        // The force on the tooth or tissue (the renderer's), whatever the device renders of it.
        const double f = glm::length(s.rendered_force_N);
        history_.push({s.time_s, float(f), float(glm::length(s.rendered_torque_Nm))});
        max_force_N_ = std::max(max_force_N_, f);
        // Time above the thresholds over the whole session, tick by tick.
        if (history_.size() > 1) {
            const double dt = s.time_s - history_.at(history_.size() - 2).time_s;
            if (f > 0.25) time_above_025_s_ += dt;
            if (f >= 0.5) time_above_05_s_ += dt;
        }
        haptic_travel_m_ = std::max(haptic_travel_m_, glm::length(s.haptic.position - start_pose_.position));
        if (s.status == StepStatus::Contact) ++contact_ticks_;
        // A site is probed once the tip has gone 1 mm into its sulcus; one that bleeds on probing
        // (in the case's chart) shows a drop of blood kBleedDelay_s later.
        const ProbeReading r = read_probe(manifest_.sites, s.graphic);
        if (r.site_index >= 0 && r.in_sulcus && r.depth_m > 1e-3 && probed_at_[size_t(r.site_index)] < 0)
            probed_at_[size_t(r.site_index)] = s.time_s;
        if (lesson_) feed_lesson(s);
        if (options_.device == "sim") chart_pass(s, r);
        if (s.step_us > 0) step_max_window_ = std::max(step_max_window_, double(s.step_us));
        live_.step_us = s.step_us;
    }
    if (loop_.latest(live_.snapshot)) {
        live_.has_snapshot = true;
        live_.telemetry_drops = live_.snapshot.telemetry_drops;
        const double t = live_.snapshot.time_s;
        if (t - last_rate_time_ >= 1.0) {
            live_.rate_hz = double(live_.snapshot.tick - last_rate_tick_) / (t - last_rate_time_);
            live_.step_us_max_1s = step_max_window_;
            step_max_window_ = 0.0;
            last_rate_time_ = t;
            last_rate_tick_ = live_.snapshot.tick;
        }
    }
}

// The simulated hand charts each pass of its trajectory once it rests on the floor, half way
// through the hold, from the tick that reaches that time (the frame rate does not matter).
// The passes come in time order (case.json), so the next one to chart is an index.
void App::chart_pass(const ServoSnapshot& s, const ProbeReading& r) {
    if (!chart_) return;
    // The hand's trainee reads an instruction-only step and presses Next once, as the headless
    // recorder's does.
    if (lesson_ && lesson_->runtime) {
        const int step = lesson_->runtime->current_step();
        const std::vector<LessonStep>& steps = lesson_->load.lesson.steps;
        if (step < static_cast<int>(steps.size()) && step != acknowledged_step_ &&
            steps[static_cast<std::size_t>(step)].complete == StepCondition::Acknowledged) {
            acknowledged_step_ = step;
            post(kEventLessonNext, "{}");
        }
    }
    // The hand's script runs on ticks (one dt each), not on the wall clock.
    const double t = scene_.scene.trajectory.front().t + double(s.tick) / servo_config_.rate_hz;
    for (; next_pass_ < manifest_.passes.size(); ++next_pass_) {
        const ProbingPass& p = manifest_.passes[next_pass_];
        if (t < p.t_floor + 0.5 * (p.t_end - p.t_floor)) return;
        if (r.site_index < 0) continue;
        const SiteFrame& site = manifest_.sites[size_t(r.site_index)];
        if (site.fdi != p.fdi || site.site != p.site) continue;
        chart_reading(r);
        // The hand's trainee also notes bleeding, as the case's chart has it.
        if (const auto& rec = manifest_.chart.teeth.at(site.fdi).sites[size_t(site.site)]; rec && rec->bop)
            chart_bop(site.fdi, site.site, true);
    }
}

// Charts the depth of a reading at its site (a posted event, as every chart entry is) and selects
// that site in the chart.
void App::chart_reading(const ProbeReading& r) {
    const SiteFrame& site = manifest_.sites[size_t(r.site_index)];
    chart_depth(site.fdi, site.site, chart_depth_mm(r.depth_m));
    ui_.selected_fdi = site.fdi;
    ui_.selected_site = int(site.site);
}

void App::key_callback(GLFWwindow* window, int key, int, int action, int mods) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    // Keys that act once (view, chart, e-stop) take presses only; motion keys repeat.
    const bool motion = key == GLFW_KEY_W || key == GLFW_KEY_S || key == GLFW_KEY_A || key == GLFW_KEY_D;
    if (action == GLFW_REPEAT && !motion) return;
    if (auto* app = static_cast<App*>(glfwGetWindowUserPointer(window))) app->keys_.emplace_back(key, mods);
}

void App::handle_input() {
    ImGuiIO& io = ImGui::GetIO();
    double x = 0, y = 0;
    glfwGetCursorPos(window_, &x, &y);
    const double dx = x - mouse_x_, dy = y - mouse_y_;
    mouse_x_ = x;
    mouse_y_ = y;
    const bool over_ui = io.WantCaptureMouse;
    for (int b = 0; b < 3; ++b) {
        const bool down = glfwGetMouseButton(window_, b) == GLFW_PRESS;
        if (!down) dragging_[b] = false;
        else if (!dragging_[b] && !over_ui) dragging_[b] = true;
    }
    const bool shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                       glfwGetKey(window_, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    const bool ctrl = glfwGetKey(window_, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                      glfwGetKey(window_, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    int ww = 0, wh = 0;
    glfwGetWindowSize(window_, &ww, &wh);
    const double px = ww > 0 ? double(fw) / double(ww) : 1.0;  // framebuffer pixels per window unit

    ViewBasis basis;
    basis.right = camera_.right();
    basis.up = camera_.up();
    basis.forward = camera_.forward();
    basis.metres_per_pixel = camera_.metres_per_pixel(driver_.pose().position, double(fh)) * px;

    // Camera: middle-drag orbits, Shift+middle-drag pans, Ctrl+wheel zooms.
    if (dragging_[GLFW_MOUSE_BUTTON_MIDDLE] && (dx != 0 || dy != 0)) {
        if (shift) camera_.pan(dx * px, dy * px, double(fh));
        else camera_.orbit(dx, dy);
    }
    if (mouse_) {
        // Probe: left-drag in the view plane, right-drag tilts about the tip, wheel for depth.
        if (dragging_[GLFW_MOUSE_BUTTON_LEFT] && (dx != 0 || dy != 0)) driver_.drag(dx, dy, basis, ctrl);
        if (dragging_[GLFW_MOUSE_BUTTON_RIGHT] && (dx != 0 || dy != 0)) driver_.tilt(dx, dy, basis, ctrl);
    }
    if (!over_ui && io.MouseWheel != 0.0f) {
        if (ctrl || !mouse_) camera_.zoom(io.MouseWheel);
        else driver_.wheel(io.MouseWheel, basis, shift);
    }
    std::vector<std::pair<int, int>> keys;
    keys.swap(keys_);
    if (!io.WantCaptureKeyboard) {
        for (const auto& [key, mods] : keys) {
            const bool fine = (mods & GLFW_MOD_CONTROL) != 0;
            if (mouse_) {
                if (key == GLFW_KEY_W) driver_.key_insert(1.0, fine);
                if (key == GLFW_KEY_S) driver_.key_insert(-1.0, fine);
                if (key == GLFW_KEY_A) driver_.key_rotate(1.0, fine);
                if (key == GLFW_KEY_D) driver_.key_rotate(-1.0, fine);
                if (key == GLFW_KEY_R) driver_.reset(start_pose_);
            }
            if (key == GLFW_KEY_SPACE && chart_ && reading_.site_index >= 0) chart_reading(reading_);
            if (key == GLFW_KEY_G) ui_.translucent_gingiva = !ui_.translucent_gingiva;
            if (key == GLFW_KEY_ESCAPE) loop_.emergency_stop();
            if (key >= GLFW_KEY_0 && key <= GLFW_KEY_6) set_view(key - GLFW_KEY_0, (mods & GLFW_MOD_SHIFT) != 0);
        }
    }
    if (mouse_) {
        // No force stops a mouse: the target may not lead the drawn probe by more than
        // kMouseLead_m, so pressing on past the surface asks for at most that much force
        // (stiffness x lead) and the probe's pose never runs centimetres into the tooth.
        if (live_.has_snapshot) {
            const Vec3 lead = driver_.pose().position - live_.snapshot.graphic.position;
            const double n = glm::length(lead);
            if (n > kMouseLead_m) {
                Pose p = driver_.pose();
                p.position = live_.snapshot.graphic.position + lead * (kMouseLead_m / n);
                driver_.set_pose(p);
            }
        }
        mouse_->set_target(driver_.pose());
    }
}

void App::update_readout() {
    if (!live_.has_snapshot) return;
    reading_ = read_probe(manifest_.sites, live_.snapshot.graphic);
}

void App::draw_frame() {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    ui_.draw.gingiva_alpha = ui_.translucent_gingiva ? ui_.translucent_alpha : 1.0;
    ui_.draw.bleeding.clear();
    const double now = live_.has_snapshot ? live_.snapshot.time_s : 0.0;
    for (size_t i = 0; i < manifest_.sites.size(); ++i) {
        const SiteFrame& site = manifest_.sites[i];
        const auto& rec = manifest_.chart.teeth.at(site.fdi).sites[size_t(site.site)];
        if (rec && rec->bop && probed_at_[i] >= 0 && now - probed_at_[i] >= kBleedDelay_s)
            ui_.draw.bleeding.push_back(site.margin_point + site.outward * 0.35e-3);
    }
    const Pose graphic = live_.has_snapshot ? live_.snapshot.graphic : start_pose_;
    const Pose haptic = live_.has_snapshot ? live_.snapshot.haptic : start_pose_;

    // The inset: the pocket at the probe, magnified, gingiva see-through.
    inset_texture_ = 0;
    if (ui_.show_inset) {
        // Looking at the probe where it enters the pocket: from outside the site being probed
        // (slightly from occlusal), else from the main view's direction.
        OrbitCamera inset = camera_;
        const Vec3 axis = graphic.orientation * Vec3(0, 1, 0);
        inset.target = graphic.position + axis * (0.3 * ui_.inset_field_m);
        if (reading_.site_index >= 0) {
            const SiteFrame& s = manifest_.sites[size_t(reading_.site_index)];
            inset.yaw_rad = std::atan2(s.outward.x, s.outward.z);
            inset.pitch_rad = s.axis.y >= 0 ? 0.2 : -0.2;
        }
        inset.distance_m = 0.5 * ui_.inset_field_m / std::tan(0.5 * inset.fov_y_rad);
        DrawOptions o = ui_.draw;
        o.gingiva_alpha = std::min(ui_.translucent_alpha, 0.35);
        inset_texture_ = view_->draw_offscreen(1, inset, 360, 360, samples_, graphic, haptic, o);
    }
    if (samples_ > 0) {
        view_->draw_offscreen(0, camera_, w, h, samples_, graphic, haptic, ui_.draw);
        view_->blit(0);
    } else {
        view_->draw(camera_, 0, 0, w, h, graphic, haptic, ui_.draw);
    }

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    draw_panels();
    ImGui::Render();
    glViewport(0, 0, w, h);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

bool App::write_png(const std::string& path, int w, int h, bool ids) {
    if (ids) {
        const Pose graphic = live_.has_snapshot ? live_.snapshot.graphic : start_pose_;
        const Pose haptic = live_.has_snapshot ? live_.snapshot.haptic : start_pose_;
        view_->draw_ids(camera_, 0, 0, w, h, graphic, haptic, ui_.draw);
    }
    std::vector<unsigned char> pixels(size_t(w) * size_t(h) * 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
    // GL rows run bottom-up; PNG rows top-down.
    std::vector<unsigned char> flipped(pixels.size());
    const size_t row = size_t(w) * 3;
    for (int yy = 0; yy < h; ++yy)
        std::copy_n(&pixels[size_t(h - 1 - yy) * row], row, &flipped[size_t(yy) * row]);
    if (!stbi_write_png(path.c_str(), w, h, 3, flipped.data(), int(row))) {
        std::fprintf(stderr, "sulcus: %s: cannot write the PNG\n", path.c_str());
        return false;
    }
    return true;
}

void App::write_report(double wall_s) {
    const ServoStats st = loop_.stats();
    nlohmann::json j;
    j["case"] = options_.case_dir;
    j["device"] = device_label_;
    j["frames"] = frames_;
    j["wall_s"] = wall_s;
    j["fps"] = wall_s > 0 ? frames_ / wall_s : 0.0;
    j["servo"] = {{"ticks", st.ticks},
                  {"elapsed_s", st.elapsed_s},
                  {"rate_hz", st.achieved_rate_hz},
                  {"nominal_rate_hz", st.nominal_rate_hz},
                  {"deadline_misses", st.deadline_misses},
                  {"skipped_slots", st.skipped_slots},
                  {"read_failures", st.read_failures},
                  {"jitter_us", {{"p50", st.jitter_us.p50}, {"p99", st.jitter_us.p99}, {"max", st.jitter_us.max}}},
                  {"step_us", {{"p50", st.step_us.p50}, {"p99", st.step_us.p99}, {"max", st.step_us.max}}},
                  {"max_force_N", st.max_force_sent_N},
                  {"non_finite_sent", st.non_finite_sent},
                  {"telemetry_drops", live_.telemetry_drops},
                  {"realtime", st.realtime}};
    j["sites_charted"] = chart_ ? chart_->sites_charted() : 0;
    j["sites_total"] = chart_ ? chart_->sites_total() : 0;
    if (lesson_ && lesson_->scores) {
        const LessonScores& sc = *lesson_->scores;
        j["lesson"] = {{"title", lesson_->load.lesson.title},
                       {"overall", sc.overall},
                       {"passed", sc.passed},
                       {"sites_charted", sc.sites_charted},
                       {"sites_target", sc.sites_target},
                       {"recording", record_path_.empty() ? nlohmann::json(nullptr) : nlohmann::json(record_path_)}};
    }
    j["time_above_0_25_N_s"] = time_above_025_s_;
    j["haptic_travel_m"] = haptic_travel_m_;
    j["contact_ticks"] = contact_ticks_;
    std::ofstream out(options_.report);
    out << j.dump(2) << "\n";
    if (!out) std::fprintf(stderr, "sulcus: %s: cannot write the report\n", options_.report.c_str());
}

}  // namespace sulcus::desktop
