// The desktop app: a case in a window, the servo loop on its own thread, the mouse (or a haptic
// device) driving the probe, and the panels. The UI thread never waits on the servo thread: it
// reads the published state (a seqlock) and drains the per-tick telemetry (a lock-free queue).
#pragma once

#include "desktop/camera.h"
#include "desktop/force_history.h"
#include "desktop/scene_view.h"
#include "sulcus/app/lesson_session.h"
#include "sulcus/app/mouse_probe.h"
#include "sulcus/app/probing_readout.h"
#include "sulcus/content/asset.h"
#include "sulcus/content/case_manifest.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"
#include "sulcus/haptics/mouse_device.h"
#include "sulcus/haptics/servo_loop.h"

#include <atomic>
#include <ctime>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <string>
#include <vector>

struct GLFWwindow;

namespace sulcus::desktop {

struct AppOptions {
    std::string case_dir;         // a built case (scene.json, case.glb, case.json)
    std::string device = "auto";  // auto | mouse | sim | phantom | spacemouse
    std::string screenshot;       // write the last frame here (PNG)
    std::string ids;              // write the last frame's object-id pass here (PNG)
    std::string report;           // write the run's summary here (JSON)
    int frames = 0;               // stop after this many frames (0: no limit)
    double seconds = 0.0;         // stop once the servo loop has run this long (0: no limit)
    uint64_t ticks = 0;           // stop once the servo loop has made this many ticks (0: no limit)
    int width = 1600, height = 900;
    double gingiva_alpha = 1.0;   // start with see-through gingiva when < 1
    int sextant = 0;              // start with this sextant's view (0: the whole case)
    bool lingual = false;
    bool reference = false;       // show the case's reference chart beside the trainee's
    int msaa = -1;                // samples per pixel of the 3D view; -1: 4, or 0 on a software renderer
    std::string lesson;           // a lesson file (sulcus.lesson/1): its built case replaces case_dir
    std::string content_root;     // the lessons' content root; empty: default_content_root()
    std::string record;           // record the session here; "none": not at all; empty: a lesson's
                                  // default (sessions_dir()/<lesson>-<UTC time>.rec), else none
    bool instructor = false;      // the reference chart editable, saved as a case and a lesson
    std::size_t telemetry_queue = 0;  // ticks the telemetry queue holds; 0: the default (tests set it small)
};

// Where sessions are recorded by default: $SULCUS_SESSIONS_DIR, else $XDG_DATA_HOME/sulcus/sessions,
// else ~/.local/share/sulcus/sessions.
std::string sessions_dir();
// "<stem>-<UTC yyyymmddThhmmssZ>.rec" for a lesson file.
std::string session_file_name(const std::string& lesson_path, std::time_t now);

// What the panels show and change; the App owns it, panels.cpp draws it.
struct UiState {
    DrawOptions draw;
    bool translucent_gingiva = false;
    double translucent_alpha = 0.4;
    bool show_inset = true;
    double inset_field_m = 8e-3;  // the inset's field of view (height) at the probe
    bool show_reference = false;
    int selected_fdi = 0;
    int selected_site = -1;       // index into kAllSites
    double plot_window_s = 5.0;
};

// A running lesson: the runtime fed from the telemetry with the UI events the loop took, in order.
struct LiveLesson {
    LessonLoad load;
    std::string path;          // as given
    std::string relative;      // relative to the content root (the recording's metadata)
    std::unique_ptr<LessonRuntime> runtime;
    std::deque<std::pair<std::string, std::string>> posted;  // posted, not yet fed to the runtime
    uint64_t fed = 0;          // events fed to the runtime (== the loop's events_taken after them)
    std::optional<LessonScores> scores;  // once the lesson has ended
    bool scores_replayed = false;        // computed by replaying the recording (telemetry dropped)
};

// Instructor mode: the case's reference chart as edited, and the save and case build.
struct Instructor {
    Chart chart;
    char name[48] = "";
    char title[160] = "";
    std::string message;       // the last save's outcome
    bool message_error = false;
    // The case build on a background thread.
    std::thread builder;
    std::atomic<int> build_state{0};  // 0 idle, 1 building, 2 done, 3 failed
    std::mutex build_mutex;
    std::string build_message;        // under build_mutex
    std::string build_command;        // the command that builds it by hand
};

struct LiveServo {
    ServoSnapshot snapshot;
    bool has_snapshot = false;
    double rate_hz = 0.0;             // ticks per second over the last second
    double step_us = 0.0;             // latest step
    double step_us_max_1s = 0.0;      // worst step over the last second
    uint64_t telemetry_drops = 0;
};

class App {
public:
    explicit App(AppOptions options);
    ~App();
    // Runs until the window closes or the frame/seconds budget is spent; the process exit code.
    int run();

private:
    std::string load_case();
    std::string start_servo();
    void handle_input();
    void drain_telemetry();
    void update_readout();
    void chart_pass(const ServoSnapshot& s, const ProbeReading& r);
    void chart_reading(const ProbeReading& r);
    void draw_frame();
    void draw_panels();
    void panel_lesson();
    void panel_chart();
    void panel_force();
    void panel_device();
    void panel_settings();
    void panel_inset();
    void set_view(int sextant, bool lingual);
    // Lessons, events and recording (lesson_ui.cpp).
    std::string load_lesson_file();
    std::string open_recorder(const std::string& device_name);
    bool post(const std::string& kind, const std::string& json);
    void chart_depth(int fdi, Site site, double pd_mm);
    void chart_bop(int fdi, Site site, bool bop);
    void chart_gm(int fdi, Site site, double gm_mm);
    bool lesson_site(int fdi) const;
    void feed_lesson(const ServoSnapshot& s);
    int finish_session();
    void panel_lesson_steps();
    void panel_instructor();
    void instructor_save();
    bool write_png(const std::string& path, int w, int h, bool ids);
    void write_report(double wall_s);

    AppOptions options_;
    GLFWwindow* window_ = nullptr;
    bool imgui_ready_ = false;

    // The case.
    SceneLoad scene_;
    std::shared_ptr<Model> model_;
    Asset asset_;
    CaseManifest manifest_;
    std::string case_name_;
    Pose start_pose_;

    // Devices and the loop.
    std::unique_ptr<Device> device_;
    MouseDevice* mouse_ = nullptr;  // device_ when it is the mouse
    std::string device_label_;
    std::unique_ptr<RecordingWriter> recorder_;
    std::string record_path_;
    RecordingMetadata record_meta_;
    std::optional<LiveLesson> lesson_;
    std::string content_root_;
    std::unique_ptr<Instructor> instructor_;
    ServoLoop loop_;
    ServoConfig servo_config_;
    MouseProbeDriver driver_;

    // View.
    std::unique_ptr<SceneView> view_;  // GL objects: released before the window
    OrbitCamera camera_;
    UiState ui_;
    ForceHistory history_;
    LiveServo live_;
    GLuint inset_texture_ = 0;
    int samples_ = 0;
    double last_rate_time_ = 0.0;
    uint64_t last_rate_tick_ = 0;
    double step_max_window_ = 0.0;

    // Probing.
    ProbeReading reading_;
    std::optional<ChartSession> chart_;
    std::vector<double> probed_at_;  // per site: servo time it was first probed (< 0: not yet)
    size_t next_pass_ = 0;
    int acknowledged_step_ = -1;  // simulated hand: the last instruction-only step it moved on from  // simulated hand: the first of the trajectory's passes not yet charted
    std::vector<std::string> feedback_;
    double max_force_N_ = 0.0;
    double haptic_travel_m_ = 0.0;  // furthest the haptic tool went from its start
    uint64_t contact_ticks_ = 0;    // ticks with the graphic tool in contact
    double time_above_025_s_ = 0.0, time_above_05_s_ = 0.0;

    int frames_ = 0;
    // Key presses and repeats since the last frame (GLFW key, mods), so a tap shorter than a frame
    // still counts.
    std::vector<std::pair<int, int>> keys_;
    static void key_callback(GLFWwindow* window, int key, int scancode, int action, int mods);
    double mouse_x_ = 0.0, mouse_y_ = 0.0;
    bool dragging_[3] = {false, false, false};
};

}  // namespace sulcus::desktop
