// PhantomDevice: OpenHaptics' libHD bound with dlopen. start() and stop() run on the caller's
// thread; frame() runs in the OpenHaptics scheduler thread (1 kHz) and trades data with the servo
// thread through two triple buffers, which neither side ever waits on.
#include "sulcus/haptics/phantom_device.h"

#include "openhaptics_abi.h"

#include <dlfcn.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <type_traits>
#include <utility>

namespace sulcus {

using namespace hd;

namespace {

int64_t now_ns() noexcept {
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string hex4(unsigned v) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "0x%04X", v);
    return buf;
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// One writer thread, one reader thread, three slots: the writer fills its own slot and swaps it
// with the shared middle one; the reader swaps the middle one for its own when it is newer.
// Wait-free on both sides, and a value is only ever seen whole.
template <class T>
class TripleBuffer {
    static constexpr uint8_t kIndex = 3, kFresh = 4;

public:
    T& back() noexcept { return slots_[back_]; }
    void publish() noexcept { back_ = middle_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel) & kIndex; }
    // Takes the latest published value if there is a newer one; true when it did.
    bool update() noexcept {
        if (!(middle_.load(std::memory_order_acquire) & kFresh)) return false;
        front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
        return true;
    }
    const T& front() const noexcept { return slots_[front_]; }
    // Only while neither side runs.
    void reset(const T& value) noexcept {
        for (T& s : slots_) s = value;
        back_ = 0;
        middle_.store(1, std::memory_order_relaxed);
        front_ = 2;
    }

private:
    T slots_[3] = {};
    uint8_t back_ = 0;                 // writer's
    std::atomic<uint8_t> middle_{1};   // shared: index | kFresh
    uint8_t front_ = 2;                // reader's
};

struct Command {
    Vec3 force_N{0.0};
    Vec3 torque_Nm{0.0};
    int64_t time_ns = 0;  // when write() gave it (CLOCK_MONOTONIC)
    bool bad = false;     // the write was not finite (zero sent)
};

struct ErrorText {
    HDerror code;
    const char* name;
    const char* meaning;
};

// Every error code of the HDAPI, with what it means for a user of this program.
constexpr ErrorText kErrors[] = {
    {HD_SUCCESS, "HD_SUCCESS", "no error"},
    {HD_INVALID_ENUM, "HD_INVALID_ENUM", "the device does not know a parameter asked of it (older driver or model?)"},
    {HD_INVALID_VALUE, "HD_INVALID_VALUE", "a value passed to the device API is out of range"},
    {HD_INVALID_OPERATION, "HD_INVALID_OPERATION", "the device API call is not valid in the current state"},
    {HD_INVALID_INPUT_TYPE, "HD_INVALID_INPUT_TYPE", "a parameter was read or written with the wrong type"},
    {HD_BAD_HANDLE, "HD_BAD_HANDLE", "the device handle is not valid"},
    {HD_WARM_MOTORS, "HD_WARM_MOTORS", "the motors are too warm; forces are off until they cool down"},
    {HD_EXCEEDED_MAX_FORCE, "HD_EXCEEDED_MAX_FORCE", "a force above the device's maximum was commanded"},
    {HD_EXCEEDED_MAX_FORCE_IMPULSE, "HD_EXCEEDED_MAX_FORCE_IMPULSE", "the force changed faster than the device allows"},
    {HD_EXCEEDED_MAX_VELOCITY, "HD_EXCEEDED_MAX_VELOCITY", "the stylus moved faster than the safe velocity limit"},
    {HD_FORCE_ERROR, "HD_FORCE_ERROR", "the device reported a force output error"},
    {HD_DEVICE_FAULT, "HD_DEVICE_FAULT", "the device reported a hardware fault; power-cycle it"},
    {HD_DEVICE_ALREADY_INITIATED, "HD_DEVICE_ALREADY_INITIATED", "the device is already initialised in this process"},
    {HD_COMM_ERROR, "HD_COMM_ERROR", "communication with the device failed; check the cable, power and that the Touch driver runs"},
    {HD_COMM_CONFIG_ERROR, "HD_COMM_CONFIG_ERROR", "the device configuration was not found or is wrong; run Touch_Setup and check the device name"},
    {HD_TIMER_ERROR, "HD_TIMER_ERROR", "the servo scheduler's timer failed (real-time permissions or a busy system?)"},
    {HD_ILLEGAL_BEGIN, "HD_ILLEGAL_BEGIN", "a frame was begun inside another frame"},
    {HD_ILLEGAL_END, "HD_ILLEGAL_END", "a frame was ended that was not begun"},
    {HD_FRAME_ERROR, "HD_FRAME_ERROR", "a servo frame went wrong (device state may be stale)"},
    {HD_INVALID_PRIORITY, "HD_INVALID_PRIORITY", "a scheduler callback priority is out of range"},
    {HD_SCHEDULER_FULL, "HD_SCHEDULER_FULL", "the scheduler has no room for another callback"},
    {HD_INVALID_LICENSE, "HD_INVALID_LICENSE", "the OpenHaptics licence is not valid"},
};

const ErrorText* find_error(unsigned code) {
    for (const ErrorText& e : kErrors)
        if (e.code == code) return &e;
    return nullptr;
}

bool is_force_error(HDerror e) { return e >= HD_WARM_MOTORS && e <= HD_FORCE_ERROR; }
// Errors after which the device cannot be trusted to follow commands: stop the callback.
bool is_fatal_error(HDerror e) {
    return e == HD_DEVICE_FAULT || e == HD_COMM_ERROR || e == HD_COMM_CONFIG_ERROR || e == HD_TIMER_ERROR ||
           e == HD_BAD_HANDLE || e == HD_INVALID_LICENSE;
}

// The process may drive one device through the one OpenHaptics scheduler.
std::atomic<bool> g_device_in_use{false};

}  // namespace

std::string describe_hd_error(unsigned hd_error) {
    const ErrorText* e = find_error(hd_error);
    if (!e) return "unknown HD error " + hex4(hd_error);
    return std::string(e->name) + " (" + hex4(hd_error) + "): " + e->meaning;
}

std::string describe_phantom_fault(uint32_t fault) {
    if (is_phantom_hd_fault(fault)) return "OpenHaptics error " + describe_hd_error(phantom_fault_hd_error(fault));
    switch (fault) {
        case kDeviceFaultNone: return "no fault";
        case kDeviceFaultNotStarted: return "device not started";
        case kDeviceFaultBadCommand: return "a non-finite force or torque was written (zero was sent)";
        case kDeviceFaultComm: return "communication with the device was lost";
        default: return "device fault " + std::to_string(fault);
    }
}

DeviceCapabilities phantom_capabilities_for_model(const std::string& model, const DeviceCapabilities& fallback) {
    const std::string m = lower(model);
    auto has = [&](const char* s) { return m.find(s) != std::string::npos; };
    if (has("touch x") || has("desktop")) return touch_x_capabilities();
    if (has("omni")) return phantom_omni_capabilities();
    if (has("touch")) return touch_capabilities();
    if (has("premium")) return has("6dof") ? phantom_premium_15_6dof_capabilities() : phantom_premium_15_capabilities();
    return fallback;
}

struct PhantomDevice::Impl {
    struct Api {
        InitDeviceFn init_device = nullptr;
        HandleFn make_current_device = nullptr;
        HandleFn disable_device = nullptr;
        GetCurrentDeviceFn get_current_device = nullptr;
        HandleFn begin_frame = nullptr;
        HandleFn end_frame = nullptr;
        GetErrorFn get_error = nullptr;
        GetErrorStringFn get_error_string = nullptr;  // optional
        EnumFn enable = nullptr;
        GetIntegervFn get_integerv = nullptr;
        GetDoublevFn get_doublev = nullptr;
        GetStringFn get_string = nullptr;
        SetDoublevFn set_doublev = nullptr;
        CheckCalibrationFn check_calibration = nullptr;
        EnumFn update_calibration = nullptr;
        VoidFn start_scheduler = nullptr;
        VoidFn stop_scheduler = nullptr;
        ScheduleAsynchronousFn schedule_asynchronous = nullptr;
        UnscheduleFn unschedule = nullptr;
    };

    Api api;
    void* lib = nullptr;
    HHD hhd = HD_INVALID_HANDLE;
    HDSchedulerHandle sched = 0;
    bool scheduled = false;
    bool scheduler_started = false;
    bool running = false;       // start() succeeded, stop() not yet called
    bool send_torque = false;
    int64_t watchdog_ns = 0;

    TripleBuffer<DeviceSample> samples;  // scheduler thread -> servo thread
    TripleBuffer<Command> commands;      // servo thread -> scheduler thread
    bool have_sample = false;            // reader side

    // Scheduler-thread state.
    uint32_t latched_fault = kDeviceFaultNone;
    bool watchdog_active = false;
    Quat last_orientation{1.0, 0.0, 0.0, 0.0};

    std::atomic<uint64_t> frames{0};
    std::atomic<uint64_t> watchdog_trips{0};
    std::atomic<bool> clear_request{false};
    std::atomic<bool> callback_done{false};
    std::atomic<uint32_t> done_fault{0};

    // The error on top of the vendor's error stack, popping what lies under it (bounded).
    HDErrorInfo drain_errors() noexcept {
        HDErrorInfo first{HD_SUCCESS, 0, 0};
        for (int i = 0; i < 64; ++i) {
            const HDErrorInfo e = api.get_error();
            if (e.errorCode == HD_SUCCESS) break;
            if (first.errorCode == HD_SUCCESS) first = e;
        }
        return first;
    }

    std::string error_line(const HDErrorInfo& e) const {
        std::string s = describe_hd_error(e.errorCode);
        const char* vendor = api.get_error_string ? api.get_error_string(e.errorCode) : nullptr;
        if (vendor && *vendor) s += std::string(" [OpenHaptics: ") + vendor + "]";
        if (e.internalErrorCode != 0) s += " (internal error " + std::to_string(e.internalErrorCode) + ")";
        return s;
    }

    HDCallbackCode frame() noexcept;
};

namespace {

HDCallbackCode SULCUS_HD_CALL servo_callback(void* user) {
    return static_cast<PhantomDevice::Impl*>(user)->frame();
}

}  // namespace

// One scheduler frame: read the stylus, send the latest command (or zero), check the error
// stack, publish the sample.
HDCallbackCode PhantomDevice::Impl::frame() noexcept {
    api.begin_frame(hhd);
    HDdouble m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    HDdouble v[3] = {0, 0, 0};
    HDint buttons = 0;
    api.get_doublev(HD_CURRENT_TRANSFORM, m);
    api.get_doublev(HD_CURRENT_VELOCITY, v);
    api.get_integerv(HD_CURRENT_BUTTONS, &buttons);

    const bool fresh = commands.update();
    const Command& cmd = commands.front();
    if (fresh && cmd.bad) latched_fault = kDeviceFaultBadCommand;
    if (clear_request.exchange(false, std::memory_order_acq_rel)) latched_fault = kDeviceFaultNone;

    bool send = latched_fault == kDeviceFaultNone;
    const bool nonzero = cmd.force_N != Vec3(0.0) || cmd.torque_Nm != Vec3(0.0);
    if (watchdog_ns > 0 && nonzero && now_ns() - cmd.time_ns > watchdog_ns) {
        if (!watchdog_active) watchdog_trips.fetch_add(1, std::memory_order_relaxed);
        watchdog_active = true;
        send = false;
    } else {
        watchdog_active = false;
    }
    const Vec3 f = send ? cmd.force_N : Vec3(0.0);
    const HDdouble force[3] = {f.x, f.y, f.z};
    api.set_doublev(HD_CURRENT_FORCE, force);
    if (send_torque) {
        // Cartesian torque in mN·m through the vendor's (deprecated) HD_CURRENT_TORQUE, as
        // CHAI3D does on the Premium 6DOF; the library maps it onto the gimbal motors.
        const Vec3 t = send ? cmd.torque_Nm * 1000.0 : Vec3(0.0);
        const HDdouble torque[3] = {t.x, t.y, t.z};
        api.set_doublev(HD_CURRENT_TORQUE, torque);
    }
    api.end_frame(hhd);

    bool fatal = false;
    for (int i = 0; i < 64; ++i) {
        const HDErrorInfo e = api.get_error();
        if (e.errorCode == HD_SUCCESS) break;
        if (is_fatal_error(e.errorCode)) {
            fatal = true;
            latched_fault = phantom_fault_from_hd(e.errorCode);
        } else if (!fatal && (is_force_error(e.errorCode) || latched_fault == kDeviceFaultNone)) {
            // Force errors take precedence over API misuse; either way force stays off.
            latched_fault = phantom_fault_from_hd(e.errorCode);
        }
    }

    DeviceSample& s = samples.back();
    s.pose.position = Vec3(m[12], m[13], m[14]) * 1e-3;
    Mat3 r;
    for (int c = 0; c < 3; ++c) r[c] = Vec3(m[4 * c], m[4 * c + 1], m[4 * c + 2]);  // column-major, as glm
    Quat q = glm::quat_cast(r);
    const double qn = glm::length(q);
    if (std::isfinite(qn) && qn > 0.5) last_orientation = q / qn;  // re-normalised: the matrix may drift
    s.pose.orientation = last_orientation;
    s.linear_velocity_m_per_s = Vec3(v[0], v[1], v[2]) * 1e-3;
    s.buttons = static_cast<uint32_t>(buttons);
    s.connected = !fatal;
    s.fault = latched_fault;
    if (!finite(s.pose.position) || !finite(s.linear_velocity_m_per_s)) {
        s.connected = false;  // garbage from the device: let the safety layer cut force
        s.pose.position = Vec3(0.0);
        s.linear_velocity_m_per_s = Vec3(0.0);
    }
    samples.publish();
    frames.fetch_add(1, std::memory_order_release);
    if (fatal) {
        done_fault.store(latched_fault, std::memory_order_relaxed);
        callback_done.store(true, std::memory_order_release);
        return HD_CALLBACK_DONE;
    }
    return HD_CALLBACK_CONTINUE;
}

PhantomDevice::PhantomDevice(PhantomOptions options)
    : options_(std::move(options)), caps_(options_.fallback), impl_(std::make_unique<Impl>()) {}

PhantomDevice::~PhantomDevice() { stop(); }

bool PhantomDevice::sends_torque() const noexcept { return impl_->send_torque; }
uint64_t PhantomDevice::frames() const noexcept { return impl_->frames.load(std::memory_order_acquire); }
uint64_t PhantomDevice::watchdog_trips() const noexcept { return impl_->watchdog_trips.load(std::memory_order_relaxed); }
void PhantomDevice::clear_fault() noexcept { impl_->clear_request.store(true, std::memory_order_release); }

std::string PhantomDevice::start() {
    Impl& d = *impl_;
    if (d.running) return "Phantom: already started";
    bool expected = false;
    if (!g_device_in_use.compare_exchange_strong(expected, true))
        return "Phantom: another PhantomDevice is running in this process (one device per process)";

    // Undo whatever was done so far, in reverse order, and return `why`.
    auto fail = [&](std::string why) {
        if (d.scheduler_started) d.api.stop_scheduler();
        if (d.scheduled) d.api.unschedule(d.sched);
        if (d.hhd != HD_INVALID_HANDLE) d.api.disable_device(d.hhd);
        if (d.api.get_error) (void)d.drain_errors();
        d.scheduler_started = d.scheduled = false;
        d.hhd = HD_INVALID_HANDLE;
        if (d.lib && options_.unload_library_on_stop) {
            dlclose(d.lib);
            d.lib = nullptr;
        }
        g_device_in_use.store(false);
        return why;
    };

    // 1. The library: reused when kept loaded by an earlier start.
    if (!d.lib) {
        std::vector<std::string> names;
        if (!options_.library_path.empty()) {
            names.push_back(options_.library_path);
        } else if (const char* env = options_.use_env ? std::getenv("SULCUS_LIBHD") : nullptr; env && *env) {
            names.push_back(env);
        } else {
            names = options_.library_candidates;
        }
        if (names.empty()) return fail("OpenHaptics: no library name to try");
        std::string last_error, tried;
        for (const std::string& n : names) {
            // RTLD_GLOBAL as CHAI3D does: libHD loads its device driver itself.
            d.lib = dlopen(n.c_str(), RTLD_LAZY | RTLD_GLOBAL);
            if (d.lib) {
                library_ = n;
                break;
            }
            const char* e = dlerror();
            last_error = e ? e : "unknown dlopen error";
            tried += (tried.empty() ? "" : ", ") + n;
        }
        if (!d.lib)
            return fail("OpenHaptics library " + names.front() + " not found (install OpenHaptics and the Touch driver; tried: " +
                        tried + "): " + last_error);

        // 2. Every entry point used; a missing one is named.
        std::string missing;
        auto bind = [&](auto& fn, const char* name, bool required) {
            dlerror();
            void* p = dlsym(d.lib, name);
            if (!p && required && missing.empty()) {
                const char* e = dlerror();
                missing = std::string(name) + (e ? std::string(": ") + e : std::string());
            }
            fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(p);
        };
        Impl::Api& a = d.api;
        bind(a.init_device, "hdInitDevice", true);
        bind(a.make_current_device, "hdMakeCurrentDevice", true);
        bind(a.disable_device, "hdDisableDevice", true);
        bind(a.get_current_device, "hdGetCurrentDevice", true);
        bind(a.begin_frame, "hdBeginFrame", true);
        bind(a.end_frame, "hdEndFrame", true);
        bind(a.get_error, "hdGetError", true);
        bind(a.get_error_string, "hdGetErrorString", false);
        bind(a.enable, "hdEnable", true);
        bind(a.get_integerv, "hdGetIntegerv", true);
        bind(a.get_doublev, "hdGetDoublev", true);
        bind(a.get_string, "hdGetString", true);
        bind(a.set_doublev, "hdSetDoublev", true);
        bind(a.check_calibration, "hdCheckCalibration", true);
        bind(a.update_calibration, "hdUpdateCalibration", true);
        bind(a.start_scheduler, "hdStartScheduler", true);
        bind(a.stop_scheduler, "hdStopScheduler", true);
        bind(a.schedule_asynchronous, "hdScheduleAsynchronous", true);
        bind(a.unschedule, "hdUnschedule", true);
        if (!missing.empty()) {
            // Not a usable libHD: always unload it.
            dlclose(d.lib);
            d.lib = nullptr;
            d.api = Impl::Api{};
            const std::string lib = library_;
            library_.clear();
            return fail("OpenHaptics library " + lib + " lacks the entry point " + missing +
                        " (not the OpenHaptics 3.x device library?)");
        }
    }
    Impl::Api& a = d.api;
    (void)d.drain_errors();  // left over from whoever used the library before

    // 3. The device. An "already initiated" device is one this process left enabled (no other
    // PhantomDevice runs: checked above): disable it and try once more, as SOFA does.
    const std::string dev_label = options_.device_name.empty() ? "the default device" : "\"" + options_.device_name + "\"";
    const char* cfg = options_.device_name.empty() ? nullptr : options_.device_name.c_str();
    d.hhd = a.init_device(cfg);
    HDErrorInfo e = d.drain_errors();
    if (e.errorCode == HD_DEVICE_ALREADY_INITIATED) {
        const HHD stale = a.get_current_device();
        if (stale != HD_INVALID_HANDLE) a.disable_device(stale);
        (void)d.drain_errors();
        d.hhd = a.init_device(cfg);
        e = d.drain_errors();
    }
    if (e.errorCode != HD_SUCCESS || d.hhd == HD_INVALID_HANDLE) {
        const HDErrorInfo err = e;
        d.hhd = HD_INVALID_HANDLE;  // nothing to disable
        if (err.errorCode == HD_SUCCESS)
            return fail("OpenHaptics could not initialise " + dev_label + ": hdInitDevice returned an invalid handle");
        return fail("OpenHaptics could not initialise " + dev_label + ": " + d.error_line(err));
    }
    a.make_current_device(d.hhd);

    // 4. Calibration. An automatic update is tried only with the styles that need no pose from
    // the user (auto, inkwell); an encoder reset assumes the arm is held at its reset pose.
    HDenum cal = a.check_calibration();
    if (cal == HD_CALIBRATION_NEEDS_UPDATE) {
        HDint styles = 0;
        a.get_integerv(HD_CALIBRATION_STYLE, &styles);
        (void)d.drain_errors();
        const HDenum style = (styles & HD_CALIBRATION_AUTO) ? HD_CALIBRATION_AUTO
                             : (styles & HD_CALIBRATION_INKWELL) ? HD_CALIBRATION_INKWELL : 0;
        if (style == 0) {
            if (styles & HD_CALIBRATION_ENCODER_RESET)
                return fail("Phantom needs an encoder-reset calibration: hold the arm in its reset position and run "
                            "the vendor's calibration (Touch_Diagnostic / PHANToM Test), then start again");
            return fail("Phantom needs calibrating but reports no calibration style (HD_CALIBRATION_STYLE = " +
                        hex4(static_cast<unsigned>(styles)) + "); run the vendor's calibration tool");
        }
        a.update_calibration(style);
        e = d.drain_errors();
        if (e.errorCode != HD_SUCCESS) return fail("Phantom calibration update failed: " + d.error_line(e));
        cal = a.check_calibration();
    }
    if (cal == HD_CALIBRATION_NEEDS_MANUAL_INPUT)
        return fail("Phantom is not calibrated: put the stylus in the inkwell (or follow the device's manual "
                    "calibration), then start again");
    if (cal != HD_CALIBRATION_OK)
        return fail("Phantom is not calibrated (hdCheckCalibration = " + hex4(cal) +
                    "); run the vendor's calibration tool, then start again");
    (void)d.drain_errors();

    // 5. Model and figures: the model's record, then what the device itself reports.
    const char* model = a.get_string(HD_DEVICE_MODEL_TYPE);
    model_ = (model && d.drain_errors().errorCode == HD_SUCCESS) ? model : "";
    DeviceCapabilities caps = phantom_capabilities_for_model(model_, options_.fallback);
    if (caps.name == options_.fallback.name && !model_.empty()) caps.name = model_;
    auto get_double = [&](HDenum what, HDdouble* out, int n) {
        for (int i = 0; i < n; ++i) out[i] = std::nan("");
        a.get_doublev(what, out);
        if (d.drain_errors().errorCode != HD_SUCCESS) return false;
        for (int i = 0; i < n; ++i)
            if (!std::isfinite(out[i])) return false;
        return true;
    };
    auto get_int = [&](HDenum what, HDint& out) {
        out = -1;
        a.get_integerv(what, &out);
        return d.drain_errors().errorCode == HD_SUCCESS;
    };
    HDdouble x[6];
    if (get_double(HD_NOMINAL_MAX_FORCE, x, 1) && x[0] > 0.0) caps.max_force_N = x[0];
    if (get_double(HD_NOMINAL_MAX_CONTINUOUS_FORCE, x, 1) && x[0] > 0.0) caps.max_continuous_force_N = x[0];
    if (get_double(HD_NOMINAL_MAX_STIFFNESS, x, 1) && x[0] > 0.0) caps.max_stiffness_N_per_m = x[0] * 1000.0;  // N/mm
    if (get_double(HD_USABLE_WORKSPACE_DIMENSIONS, x, 6) && x[0] < x[3] && x[1] < x[4] && x[2] < x[5]) {
        caps.workspace_min_m = Vec3(x[0], x[1], x[2]) * 1e-3;
        caps.workspace_max_m = Vec3(x[3], x[4], x[5]) * 1e-3;
    }
    HDint dof = 0;
    if (get_int(HD_INPUT_DOF, dof) && dof >= 3 && dof <= 7) caps.input_dof = dof;
    if (get_int(HD_OUTPUT_DOF, dof) && dof >= 3 && dof <= 7) caps.output_dof = dof;
    if (caps.output_dof < 6) caps.max_torque_Nm = 0.0;
    caps_ = caps;
    d.send_torque = options_.torque_output && caps_.output_dof >= 6;

    // 6. The vendor's own force protections.
    for (HDenum cap : {HD_FORCE_OUTPUT, HD_MAX_FORCE_CLAMPING, HD_SOFTWARE_FORCE_LIMIT}) {
        a.enable(cap);
        e = d.drain_errors();
        if (e.errorCode != HD_SUCCESS) {
            const char* name = cap == HD_FORCE_OUTPUT ? "HD_FORCE_OUTPUT"
                               : cap == HD_MAX_FORCE_CLAMPING ? "HD_MAX_FORCE_CLAMPING" : "HD_SOFTWARE_FORCE_LIMIT";
            return fail(std::string("OpenHaptics refused to enable ") + name + ": " + d.error_line(e));
        }
    }

    // 7. The servo callback and the scheduler.
    d.samples.reset(DeviceSample{});
    d.commands.reset(Command{Vec3(0.0), Vec3(0.0), now_ns(), false});
    d.have_sample = false;
    d.latched_fault = kDeviceFaultNone;
    d.watchdog_active = false;
    d.last_orientation = Quat(1.0, 0.0, 0.0, 0.0);
    d.frames.store(0);
    d.watchdog_trips.store(0);
    d.clear_request.store(false);
    d.callback_done.store(false);
    d.done_fault.store(0);
    d.watchdog_ns = options_.watchdog_s > 0.0 ? static_cast<int64_t>(options_.watchdog_s * 1e9) : 0;

    d.sched = a.schedule_asynchronous(&servo_callback, &d, HD_MAX_SCHEDULER_PRIORITY);
    e = d.drain_errors();
    if (e.errorCode != HD_SUCCESS) return fail("OpenHaptics could not schedule the servo callback: " + d.error_line(e));
    d.scheduled = true;
    a.start_scheduler();
    e = d.drain_errors();
    if (e.errorCode != HD_SUCCESS) return fail("OpenHaptics could not start its scheduler: " + d.error_line(e));
    d.scheduler_started = true;

    // 8. The first frame, so the servo loop's first read() has the real pose.
    const int64_t deadline = now_ns() + static_cast<int64_t>(std::max(options_.first_frame_timeout_s, 0.0) * 1e9);
    while (d.frames.load(std::memory_order_acquire) == 0 && now_ns() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (d.frames.load(std::memory_order_acquire) == 0)
        return fail("OpenHaptics scheduler started but ran no servo frame within " +
                    std::to_string(options_.first_frame_timeout_s) + " s");
    if (d.callback_done.load(std::memory_order_acquire))
        return fail("Phantom servo callback stopped at its first frame: " +
                    describe_phantom_fault(d.done_fault.load(std::memory_order_relaxed)));
    d.running = true;
    return "";
}

bool PhantomDevice::read(DeviceSample& sample) noexcept {
    Impl& d = *impl_;
    if (!d.running) {
        sample.connected = false;
        sample.fault = kDeviceFaultNotStarted;
        return false;
    }
    if (d.samples.update()) d.have_sample = true;
    if (!d.have_sample) {  // not reached after start(), which waits for a frame
        sample.connected = false;
        sample.fault = kDeviceFaultNotStarted;
        return false;
    }
    sample = d.samples.front();
    return true;
}

void PhantomDevice::write(const Vec3& force_N, const Vec3& torque_Nm) noexcept {
    Impl& d = *impl_;
    if (!d.running) return;
    Command& c = d.commands.back();
    c.bad = !finite(force_N) || !finite(torque_Nm);
    c.force_N = c.bad ? Vec3(0.0) : force_N;
    c.torque_Nm = c.bad ? Vec3(0.0) : torque_Nm;
    c.time_ns = now_ns();
    d.commands.publish();
}

void PhantomDevice::stop() {
    Impl& d = *impl_;
    if (!d.running) return;
    // Zero out through a frame before the scheduler stops (bounded wait: the callback may be done).
    write(Vec3(0.0), Vec3(0.0));
    const uint64_t f0 = d.frames.load(std::memory_order_acquire);
    const int64_t deadline = now_ns() + 20'000'000;
    while (!d.callback_done.load(std::memory_order_acquire) && d.frames.load(std::memory_order_acquire) < f0 + 2 &&
           now_ns() < deadline)
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    Impl::Api& a = d.api;
    a.stop_scheduler();
    a.unschedule(d.sched);
    a.disable_device(d.hhd);
    (void)d.drain_errors();
    d.scheduler_started = d.scheduled = false;
    d.hhd = HD_INVALID_HANDLE;
    d.running = false;
    d.have_sample = false;
    if (options_.unload_library_on_stop && d.lib) {
        dlclose(d.lib);
        d.lib = nullptr;
        d.api = Impl::Api{};
    }
    g_device_in_use.store(false);
}

}  // namespace sulcus
