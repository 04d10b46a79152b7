// The desktop app: a case in a window, the servo loop on its own thread, the mouse (or a haptic
// device) driving the probe, and the panels. The UI thread never waits on the servo thread: it
// reads the published state (a seqlock) and drains the per-tick telemetry (a lock-free queue).
#pragma once

#include "desktop/camera.h"
#include "desktop/force_history.h"
#include "desktop/scene_view.h"
#include "sulcus/app/mouse_probe.h"
#include "sulcus/app/probing_readout.h"
#include "sulcus/content/asset.h"
#include "sulcus/content/case_manifest.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"
#include "sulcus/haptics/mouse_device.h"
#include "sulcus/haptics/servo_loop.h"

#include <memory>
#include <optional>
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
};

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
    bool write_png(const std::string& path, int w, int h, bool ids);
    void write_report(double wall_s);

    AppOptions options_;
    GLFWwindow* window_ = nullptr;
    bool imgui_ready_ = false;

    // The case.
    SceneLoad scene_;
    std::unique_ptr<Model> model_;
    Asset asset_;
    CaseManifest manifest_;
    std::string case_name_;
    Pose start_pose_;

    // Devices and the loop.
    std::unique_ptr<Device> device_;
    MouseDevice* mouse_ = nullptr;  // device_ when it is the mouse
    std::string device_label_;
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
    size_t next_pass_ = 0;  // simulated hand: the first of the trajectory's passes not yet charted
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
