// A fake OpenHaptics device library (built as libHD.so for the tests): the HDAPI entry points
// PhantomDevice binds, with C linkage and the same signatures, over a simulated device. Its
// scheduler is a thread ticking the scheduled callbacks at 1 kHz after hdStartScheduler; errors
// go on a stack that hdGetError pops; the stylus pose is scripted by the test; forces and
// torques written are recorded. Controls: fake_hd_* (fake_hd_control.h).
#include "fake_hd_control.h"

#include "openhaptics_abi.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

using namespace sulcus::hd;

namespace {

constexpr HHD kHandle = 1;

struct Scheduled {
    HDSchedulerHandle handle;
    HDSchedulerCallback callback;
    void* data;
    HDushort priority;
};

struct Fake {
    std::mutex m;  // device state and error stack
    std::vector<HDErrorInfo> errors;
    bool initialized = false;
    HHD current = HD_INVALID_HANDLE;
    bool force_output = false, clamping = false, soft_limit = false;
    int init_calls = 0, disable_calls = 0, calibration_updates = 0;
    unsigned last_update_style = 0;
    std::string last_init_name;
    HDerror init_error = HD_SUCCESS;
    HDerror start_error = HD_SUCCESS;
    HDerror inject_error = HD_SUCCESS;
    HDenum calibration = HD_CALIBRATION_OK;
    int calibration_styles = HD_CALIBRATION_INKWELL;
    bool update_fixes = true;
    std::string model = "Touch";
    double max_force = 0, continuous = 0, stiffness = 0;
    double workspace[6] = {0, 0, 0, 0, 0, 0};
    int input_dof = 0, output_dof = 0;
    double transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    double velocity[3] = {0, 0, 0};
    int buttons = 0;
    // Frame.
    bool in_frame = false;
    bool force_set = false, torque_set = false;
    double pending_force[3] = {0, 0, 0}, pending_torque[3] = {0, 0, 0};
    unsigned long long frames = 0, force_writes = 0, torque_writes = 0, outside = 0, force_change_frame = 0;
    double last_force[3] = {0, 0, 0}, last_torque[3] = {0, 0, 0};
    double max_force_norm = 0;
    bool non_finite_force = false;

    // Scheduler.
    std::recursive_mutex sched_m;  // held while callbacks run; hdUnschedule waits on it
    std::vector<Scheduled> callbacks;
    HDSchedulerHandle next_handle = 1;
    std::thread thread;
    std::atomic<bool> running{false};

    void push(HDerror code, int internal = 0) { errors.push_back(HDErrorInfo{code, internal, kHandle}); }
};

Fake& fake() {
    static Fake f;
    return f;
}

void tick_loop() {
    Fake& f = fake();
    auto next = std::chrono::steady_clock::now();
    while (f.running.load()) {
        next += std::chrono::milliseconds(1);
        {
            std::lock_guard<std::recursive_mutex> lk(f.sched_m);
            std::vector<Scheduled> order = f.callbacks;
            std::stable_sort(order.begin(), order.end(),
                             [](const Scheduled& a, const Scheduled& b) { return a.priority > b.priority; });
            for (const Scheduled& s : order) {
                if (s.callback(s.data) == HD_CALLBACK_DONE) {
                    std::erase_if(f.callbacks, [&](const Scheduled& c) { return c.handle == s.handle; });
                }
            }
        }
        std::this_thread::sleep_until(next);
    }
}

void stop_thread() {
    Fake& f = fake();
    f.running.store(false);
    if (f.thread.joinable() && f.thread.get_id() != std::this_thread::get_id()) f.thread.join();
}

void copy3(double* dst, const double* src) { std::memcpy(dst, src, 3 * sizeof(double)); }

}  // namespace

extern "C" {

// ---- HDAPI entry points --------------------------------------------------------------------

HHD hdInitDevice(HDstring config_name) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    ++f.init_calls;
    f.last_init_name = config_name ? config_name : "";
    if (f.init_error != HD_SUCCESS) {
        f.push(f.init_error, 7);
        return HD_INVALID_HANDLE;
    }
    if (f.initialized) {
        f.push(HD_DEVICE_ALREADY_INITIATED);
        return HD_INVALID_HANDLE;
    }
    f.initialized = true;
    f.current = kHandle;
    return kHandle;
}

void hdMakeCurrentDevice(HHD h) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (h != kHandle || !f.initialized) f.push(HD_BAD_HANDLE);
    else f.current = h;
}

void hdDisableDevice(HHD h) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (h != kHandle || !f.initialized) {
        f.push(HD_BAD_HANDLE);
        return;
    }
    ++f.disable_calls;
    f.initialized = false;
    f.current = HD_INVALID_HANDLE;
    f.force_output = f.clamping = f.soft_limit = false;
}

HHD hdGetCurrentDevice() {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    return f.current;
}

void hdBeginFrame(HHD h) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (h != kHandle || !f.initialized) {
        f.push(HD_BAD_HANDLE);
        return;
    }
    if (f.in_frame) f.push(HD_ILLEGAL_BEGIN);
    f.in_frame = true;
    f.force_set = f.torque_set = false;
}

void hdEndFrame(HHD h) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (h != kHandle || !f.initialized) {
        f.push(HD_BAD_HANDLE);
        return;
    }
    if (!f.in_frame) f.push(HD_ILLEGAL_END);
    f.in_frame = false;
    ++f.frames;
    if (f.force_set) {
        double F[3];
        copy3(F, f.pending_force);
        const double n = std::sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
        if (!std::isfinite(n)) {
            f.non_finite_force = true;
            F[0] = F[1] = F[2] = 0;
        } else if (f.max_force > 0 && n > f.max_force) {
            // Clamped when asked to, otherwise refused as the device does.
            if (f.clamping) {
                for (double& c : F) c *= f.max_force / n;
            } else {
                f.push(HD_EXCEEDED_MAX_FORCE);
                F[0] = F[1] = F[2] = 0;
            }
        }
        if (!f.force_output) F[0] = F[1] = F[2] = 0;
        if (std::memcmp(F, f.last_force, sizeof F) != 0) f.force_change_frame = f.frames;
        copy3(f.last_force, F);
        f.max_force_norm = std::max(f.max_force_norm, std::sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]));
        ++f.force_writes;
    }
    if (f.torque_set) {
        copy3(f.last_torque, f.pending_torque);
        ++f.torque_writes;
    }
    if (f.inject_error != HD_SUCCESS) {
        f.push(f.inject_error, 11);
        f.inject_error = HD_SUCCESS;
    }
}

HDErrorInfo hdGetError() {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (f.errors.empty()) return HDErrorInfo{HD_SUCCESS, 0, 0};
    const HDErrorInfo e = f.errors.back();
    f.errors.pop_back();
    return e;
}

HDstring hdGetErrorString(HDerror code) {
    switch (code) {
        case HD_SUCCESS: return "No error";
        case HD_COMM_ERROR: return "Fake communication error";
        case HD_TIMER_ERROR: return "Fake timer error";
        case HD_EXCEEDED_MAX_FORCE: return "Fake: maximum force exceeded";
        default: return "Fake error";
    }
}

void hdEnable(HDenum cap) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    switch (cap) {
        case HD_FORCE_OUTPUT: f.force_output = true; break;
        case HD_MAX_FORCE_CLAMPING: f.clamping = true; break;
        case HD_SOFTWARE_FORCE_LIMIT: f.soft_limit = true; break;
        case HD_FORCE_RAMPING: break;
        default: f.push(HD_INVALID_ENUM);
    }
}

void hdGetIntegerv(HDenum what, HDint* out) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    switch (what) {
        case HD_CURRENT_BUTTONS: *out = f.buttons; return;
        case HD_CALIBRATION_STYLE: *out = f.calibration_styles; return;
        case HD_INPUT_DOF:
            if (f.input_dof > 0) { *out = f.input_dof; return; }
            break;
        case HD_OUTPUT_DOF:
            if (f.output_dof > 0) { *out = f.output_dof; return; }
            break;
        default: break;
    }
    f.push(HD_INVALID_ENUM);
}

void hdGetDoublev(HDenum what, HDdouble* out) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    switch (what) {
        case HD_CURRENT_TRANSFORM: std::memcpy(out, f.transform, sizeof f.transform); return;
        case HD_CURRENT_VELOCITY: copy3(out, f.velocity); return;
        case HD_NOMINAL_MAX_FORCE:
            if (f.max_force > 0) { *out = f.max_force; return; }
            break;
        case HD_NOMINAL_MAX_CONTINUOUS_FORCE:
            if (f.continuous > 0) { *out = f.continuous; return; }
            break;
        case HD_NOMINAL_MAX_STIFFNESS:
            if (f.stiffness > 0) { *out = f.stiffness; return; }
            break;
        case HD_USABLE_WORKSPACE_DIMENSIONS:
            if (f.workspace[3] > f.workspace[0]) { std::memcpy(out, f.workspace, sizeof f.workspace); return; }
            break;
        default: break;
    }
    f.push(HD_INVALID_ENUM);
}

HDstring hdGetString(HDenum what) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (what == HD_DEVICE_MODEL_TYPE) return f.model.c_str();
    f.push(HD_INVALID_ENUM);
    return nullptr;
}

void hdSetDoublev(HDenum what, const HDdouble* value) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    if (!f.in_frame) {
        ++f.outside;
        f.push(HD_INVALID_OPERATION);
        return;
    }
    if (what == HD_CURRENT_FORCE) {
        copy3(f.pending_force, value);
        f.force_set = true;
    } else if (what == HD_CURRENT_TORQUE) {
        copy3(f.pending_torque, value);
        f.torque_set = true;
    } else {
        f.push(HD_INVALID_ENUM);
    }
}

HDenum hdCheckCalibration() {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    return f.calibration;
}

void hdUpdateCalibration(HDenum style) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    ++f.calibration_updates;
    f.last_update_style = style;
    if (!(static_cast<int>(style) & f.calibration_styles)) {
        f.push(HD_INVALID_VALUE);
        return;
    }
    if (f.calibration == HD_CALIBRATION_NEEDS_UPDATE && f.update_fixes) f.calibration = HD_CALIBRATION_OK;
}

void hdStartScheduler() {
    Fake& f = fake();
    {
        std::lock_guard<std::mutex> lk(f.m);
        if (f.start_error != HD_SUCCESS) {
            f.push(f.start_error, 3);
            return;
        }
    }
    if (f.running.exchange(true)) return;
    f.thread = std::thread(tick_loop);
}

void hdStopScheduler() { stop_thread(); }

HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback cb, void* data, HDushort priority) {
    Fake& f = fake();
    std::lock_guard<std::recursive_mutex> lk(f.sched_m);
    const HDSchedulerHandle h = f.next_handle++;
    f.callbacks.push_back(Scheduled{h, cb, data, priority});
    return h;
}

void hdUnschedule(HDSchedulerHandle h) {
    Fake& f = fake();
    std::lock_guard<std::recursive_mutex> lk(f.sched_m);
    std::erase_if(f.callbacks, [&](const Scheduled& c) { return c.handle == h; });
}

// ---- Test controls -------------------------------------------------------------------------

void fake_hd_reset() {
    stop_thread();
    Fake& f = fake();
    std::lock_guard<std::recursive_mutex> sk(f.sched_m);
    std::lock_guard<std::mutex> lk(f.m);
    f.callbacks.clear();
    f.errors.clear();
    f.initialized = false;
    f.current = HD_INVALID_HANDLE;
    f.force_output = f.clamping = f.soft_limit = false;
    f.init_calls = f.disable_calls = f.calibration_updates = 0;
    f.last_update_style = 0;
    f.last_init_name.clear();
    f.init_error = f.start_error = f.inject_error = HD_SUCCESS;
    f.calibration = HD_CALIBRATION_OK;
    f.calibration_styles = HD_CALIBRATION_INKWELL;
    f.update_fixes = true;
    f.model = "Touch";
    f.max_force = f.continuous = f.stiffness = 0;
    std::fill(std::begin(f.workspace), std::end(f.workspace), 0.0);
    f.input_dof = f.output_dof = 0;
    const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::memcpy(f.transform, identity, sizeof identity);
    std::fill(std::begin(f.velocity), std::end(f.velocity), 0.0);
    f.buttons = 0;
    f.in_frame = f.force_set = f.torque_set = false;
    f.frames = f.force_writes = f.torque_writes = f.outside = f.force_change_frame = 0;
    std::fill(std::begin(f.last_force), std::end(f.last_force), 0.0);
    std::fill(std::begin(f.last_torque), std::end(f.last_torque), 0.0);
    f.max_force_norm = 0;
    f.non_finite_force = false;
}

void fake_hd_state(FakeHdState* out) {
    Fake& f = fake();
    FakeHdState s{};
    {
        std::lock_guard<std::recursive_mutex> sk(f.sched_m);
        s.callbacks_scheduled = static_cast<int>(f.callbacks.size());
    }
    std::lock_guard<std::mutex> lk(f.m);
    s.initialized = f.initialized;
    s.force_output = f.force_output;
    s.force_clamping = f.clamping;
    s.software_force_limit = f.soft_limit;
    s.scheduler_running = f.running.load();
    s.init_calls = f.init_calls;
    s.disable_calls = f.disable_calls;
    s.calibration_updates = f.calibration_updates;
    s.last_update_style = f.last_update_style;
    s.frames = f.frames;
    s.force_writes = f.force_writes;
    copy3(s.last_force, f.last_force);
    s.force_change_frame = f.force_change_frame;
    s.max_force_norm = f.max_force_norm;
    s.non_finite_force = f.non_finite_force;
    s.torque_writes = f.torque_writes;
    copy3(s.last_torque, f.last_torque);
    s.writes_outside_frame = f.outside;
    std::strncpy(s.last_init_name, f.last_init_name.c_str(), sizeof s.last_init_name - 1);
    *out = s;
}

void fake_hd_set_init_error(unsigned code) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().init_error = code;
}

void fake_hd_set_calibration(unsigned status, int supported_styles, int update_fixes) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().calibration = status;
    fake().calibration_styles = supported_styles;
    fake().update_fixes = update_fixes != 0;
}

void fake_hd_set_start_error(unsigned code) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().start_error = code;
}

void fake_hd_inject_error(unsigned code) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().inject_error = code;
}

void fake_hd_set_model(const char* model) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().model = model ? model : "";
}

void fake_hd_set_figures(double max_force_N, double continuous_N, double stiffness_N_per_mm, const double workspace_mm[6],
                         int input_dof, int output_dof) {
    Fake& f = fake();
    std::lock_guard<std::mutex> lk(f.m);
    f.max_force = max_force_N;
    f.continuous = continuous_N;
    f.stiffness = stiffness_N_per_mm;
    if (workspace_mm) std::memcpy(f.workspace, workspace_mm, sizeof f.workspace);
    else std::fill(std::begin(f.workspace), std::end(f.workspace), 0.0);
    f.input_dof = input_dof;
    f.output_dof = output_dof;
}

void fake_hd_set_transform(const double column_major_mm[16]) {
    std::lock_guard<std::mutex> lk(fake().m);
    std::memcpy(fake().transform, column_major_mm, sizeof fake().transform);
}

void fake_hd_set_velocity(const double mm_per_s[3]) {
    std::lock_guard<std::mutex> lk(fake().m);
    copy3(fake().velocity, mm_per_s);
}

void fake_hd_set_buttons(int buttons) {
    std::lock_guard<std::mutex> lk(fake().m);
    fake().buttons = buttons;
}

}  // extern "C"

// The fake's entry points have exactly the types the loader casts its dlsym results to.
static_assert(std::is_same_v<decltype(&hdInitDevice), InitDeviceFn>);
static_assert(std::is_same_v<decltype(&hdDisableDevice), HandleFn>);
static_assert(std::is_same_v<decltype(&hdBeginFrame), HandleFn>);
static_assert(std::is_same_v<decltype(&hdGetCurrentDevice), GetCurrentDeviceFn>);
static_assert(std::is_same_v<decltype(&hdGetError), GetErrorFn>);
static_assert(std::is_same_v<decltype(&hdGetErrorString), GetErrorStringFn>);
static_assert(std::is_same_v<decltype(&hdEnable), EnumFn>);
static_assert(std::is_same_v<decltype(&hdUpdateCalibration), EnumFn>);
static_assert(std::is_same_v<decltype(&hdGetIntegerv), GetIntegervFn>);
static_assert(std::is_same_v<decltype(&hdGetDoublev), GetDoublevFn>);
static_assert(std::is_same_v<decltype(&hdGetString), GetStringFn>);
static_assert(std::is_same_v<decltype(&hdSetDoublev), SetDoublevFn>);
static_assert(std::is_same_v<decltype(&hdCheckCalibration), CheckCalibrationFn>);
static_assert(std::is_same_v<decltype(&hdStartScheduler), VoidFn>);
static_assert(std::is_same_v<decltype(&hdScheduleAsynchronous), ScheduleAsynchronousFn>);
static_assert(std::is_same_v<decltype(&hdUnschedule), UnscheduleFn>);
static_assert(std::is_same_v<decltype(&fake_hd_set_figures), fake_hd_set_figures_fn>);
static_assert(std::is_same_v<decltype(&fake_hd_state), fake_hd_state_fn>);
