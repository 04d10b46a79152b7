// SpaceMouseDevice: the reader thread, the lock-free hand-over to read(), and the hidapi source.
#include "sulcus/haptics/spacemouse_device.h"

#include "sulcus/haptics/servo_loop.h"  // Seqlock

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

#ifdef SULCUS_HAVE_HIDAPI
#include <hidapi.h>

#include <cerrno>
#include <cstring>
#include <cwchar>
#include <fcntl.h>
#include <unistd.h>
#endif

namespace sulcus {

namespace {

bool finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

DeviceCapabilities base_capabilities(const SpaceMouseDeviceConfig& config, const std::string& name) {
    DeviceCapabilities c;
    c.name = name.empty() ? "3Dconnexion SpaceMouse" : name;
    c.input_dof = 6;
    c.output_dof = 0;
    c.workspace_min_m = config.workspace_min_m;
    c.workspace_max_m = config.workspace_max_m;
    c.nominal_rate_Hz = config.rate_hz;
    return c;
}

}  // namespace

const char* spacemouse_udev_rule() {
    return "KERNEL==\"hidraw*\", ATTRS{idVendor}==\"046d|256f\", MODE=\"0660\", TAG+=\"uaccess\"";
}

// ---- reader thread -------------------------------------------------------------------------

struct SpaceMouseDevice::Reader {
    std::thread thread;
    std::atomic<bool> stop{false};
    std::atomic<bool> failed{false};  // the source reported an error or an unplug
    Seqlock<SpaceMouseState> published;

    // Runs until stop or a source error. `state` lives here, so each report folds into the
    // previous ones (split reports update half the axes each).
    void run(HidReportSource& source, SpaceMouseDevice& dev, int timeout_ms) noexcept {
        uint8_t buf[64];
        SpaceMouseState state;
        while (!stop.load(std::memory_order_acquire)) {
            const int n = source.read_timeout(buf, sizeof buf, timeout_ms);
            if (n < 0) {
                failed.store(true, std::memory_order_release);
                return;
            }
            if (n == 0) continue;
            const auto size = static_cast<std::size_t>(std::min<int>(n, sizeof buf));
            SpaceMouseLayout layout = dev.layout_.load(std::memory_order_relaxed);
            bool ok = parse_spacemouse_report(buf, size, layout, state);
            // A 7-byte report 1 cannot be combined: the device sends the split layout, whatever
            // the product table guessed (docs/spacemouse.md). Switch once and keep it.
            if (!ok && layout == SpaceMouseLayout::combined && buf[0] == kSpaceMouseReportTranslation &&
                size >= kSpaceMouseAxesReportSize && size < kSpaceMouseCombinedReportSize) {
                dev.layout_.store(SpaceMouseLayout::split, std::memory_order_relaxed);
                ok = parse_spacemouse_report(buf, size, SpaceMouseLayout::split, state);
            }
            if (ok) {
                published.store(state);
                dev.parsed_.fetch_add(1, std::memory_order_relaxed);
            } else {
                dev.rejected_.fetch_add(1, std::memory_order_relaxed);  // e.g. battery report 0x17
            }
        }
    }
};

// ---- device --------------------------------------------------------------------------------

SpaceMouseDevice::SpaceMouseDevice(SpaceMouseDeviceConfig config)
    : SpaceMouseDevice(config, make_hidapi_source(config.path)) {}

SpaceMouseDevice::SpaceMouseDevice(SpaceMouseDeviceConfig config, std::unique_ptr<HidReportSource> source)
    : config_(std::move(config)), source_(std::move(source)), caps_(base_capabilities(config_, "")) {}

SpaceMouseDevice::~SpaceMouseDevice() { stop(); }

void SpaceMouseDevice::set_workspace(const Vec3& min_m, const Vec3& max_m) {
    config_.workspace_min_m = glm::min(min_m, max_m);
    config_.workspace_max_m = glm::max(min_m, max_m);
}

std::string SpaceMouseDevice::start() {
    stop();
    if (!source_) return "spacemouse: no report source";
    if (!(config_.rate_hz > 0.0) || !std::isfinite(config_.rate_hz))
        return "spacemouse: rate_hz must be a positive number";
    if (!finite(config_.workspace_min_m) || !finite(config_.workspace_max_m))
        return "spacemouse: the workspace box is not finite";
    HidDeviceIdentity id;
    std::string error = source_->open(id);
    if (!error.empty()) return error;
    identity_ = id;
    caps_ = base_capabilities(config_, id.product_name);
    layout_.store(config_.layout ? *config_.layout : layout_for_product(id.vendor, id.product),
                  std::memory_order_relaxed);
    parsed_.store(0, std::memory_order_relaxed);
    rejected_.store(0, std::memory_order_relaxed);

    pose_ = config_.start_pose;
    pose_.position = glm::clamp(pose_.position, config_.workspace_min_m, config_.workspace_max_m);
    dt_s_ = 1.0 / config_.rate_hz;
    fault_ = kDeviceFaultNone;
    bad_commands_ = 0;

    reader_ = std::make_unique<Reader>();
    Reader* r = reader_.get();
    HidReportSource* src = source_.get();
    const int timeout_ms = std::max(1, config_.read_timeout_ms);
    try {
        r->thread = std::thread([r, src, this, timeout_ms] { r->run(*src, *this, timeout_ms); });
    } catch (const std::exception& e) {
        reader_.reset();
        source_->close();
        return std::string("spacemouse: cannot start the reader thread: ") + e.what();
    }
    running_ = true;
    return "";
}

void SpaceMouseDevice::stop() {
    if (reader_) {
        reader_->stop.store(true, std::memory_order_release);
        if (reader_->thread.joinable()) reader_->thread.join();
        reader_.reset();
        if (source_) source_->close();
    }
    running_ = false;
    fault_ = kDeviceFaultNotStarted;
}

bool SpaceMouseDevice::read(DeviceSample& sample) noexcept {
    sample.pose = pose_;
    sample.linear_velocity_m_per_s = Vec3(0.0);
    if (!running_) {
        sample.connected = false;
        sample.fault = kDeviceFaultNotStarted;
        return false;
    }
    if (reader_->failed.load(std::memory_order_acquire)) {
        // The pose holds where it was; the caller decides what a lost input means.
        sample.connected = false;
        sample.fault = kDeviceFaultComm;
        return false;
    }
    SpaceMouseState state;  // at rest until the first report arrives
    reader_->published.load(state);
    const Pose before = pose_;
    pose_ = integrate_spacemouse(pose_, state, dt_s_, config_.mapping);
    pose_.position = glm::clamp(pose_.position, config_.workspace_min_m, config_.workspace_max_m);
    sample.pose = pose_;
    sample.linear_velocity_m_per_s = (pose_.position - before.position) / dt_s_;
    sample.buttons = state.buttons;
    sample.connected = true;
    sample.fault = fault_;
    return true;
}

void SpaceMouseDevice::write(const Vec3& force_N, const Vec3& torque_Nm) noexcept {
    if (!running_) return;
    // Nothing is rendered, but a broken command is still a fault upstream, as on any device.
    if (!finite(force_N) || !finite(torque_Nm)) {
        ++bad_commands_;
        fault_ = kDeviceFaultBadCommand;
    }
}

// ---- hidapi source -------------------------------------------------------------------------

#ifdef SULCUS_HAVE_HIDAPI

namespace {

// Product strings are ASCII in practice; anything else becomes '?'.
std::string narrow(const wchar_t* s) {
    std::string out;
    if (s == nullptr) return out;
    for (; *s != 0; ++s) out.push_back(*s > 0 && *s < 0x80 ? static_cast<char>(*s) : '?');
    return out;
}

std::string hid_init_error() {
    return "spacemouse: hidapi init failed (hid_init): " + narrow(hid_error(nullptr));
}

std::vector<SpaceMouseHidEntry> list_spacemice() {
    std::vector<SpaceMouseHidEntry> out;
    hid_device_info* all = hid_enumerate(0, 0);
    for (hid_device_info* d = all; d != nullptr; d = d->next) {
        if (!is_spacemouse(d->vendor_id, d->product_id)) continue;
        SpaceMouseHidEntry e;
        e.identity.vendor = d->vendor_id;
        e.identity.product = d->product_id;
        e.identity.product_name = narrow(d->product_string);
        e.identity.path = d->path ? d->path : "";
        e.interface_number = d->interface_number;
        out.push_back(std::move(e));
    }
    hid_free_enumeration(all);
    return out;
}

class HidapiSource final : public HidReportSource {
public:
    explicit HidapiSource(std::string path) : path_(std::move(path)) {}
    ~HidapiSource() override { close(); }

    std::string open(HidDeviceIdentity& identity) override {
        close();
        if (hid_init() != 0) return hid_init_error();
        const std::vector<SpaceMouseHidEntry> found = list_spacemice();
        if (path_.empty()) {
            if (found.empty())
                return "spacemouse: no SpaceMouse found (no hidraw device with vendor 046d/256f and a "
                       "known SpaceMouse product id)";
            identity = found.front().identity;
        } else {
            const auto it = std::find_if(found.begin(), found.end(),
                                         [&](const SpaceMouseHidEntry& e) { return e.identity.path == path_; });
            if (it == found.end())
                return "spacemouse: " + path_ + " is not a SpaceMouse hidapi can see (none, or another device)";
            identity = it->identity;
        }
        dev_ = hid_open_path(identity.path.c_str());
        if (dev_ == nullptr) {
            // hidapi opens read-write; find out whether it was the permissions.
            const int fd = ::open(identity.path.c_str(), O_RDWR | O_CLOEXEC);
            const int err = errno;
            if (fd >= 0) ::close(fd);
            if (fd < 0 && (err == EACCES || err == EPERM))
                return "spacemouse: permission denied on " + identity.path +
                       ": needs a udev rule for vendor 046d/256f, e.g. " + spacemouse_udev_rule() +
                       " in /etc/udev/rules.d/70-spacemouse.rules";
            return "spacemouse: cannot open " + identity.path + ": " + narrow(hid_error(nullptr));
        }
        return "";
    }

    int read_timeout(uint8_t* buffer, std::size_t size, int timeout_ms) noexcept override {
        if (dev_ == nullptr) return -1;
        return hid_read_timeout(dev_, buffer, size, timeout_ms);
    }

    void close() noexcept override {
        if (dev_ != nullptr) hid_close(dev_);
        dev_ = nullptr;
    }

private:
    std::string path_;
    hid_device* dev_ = nullptr;
};

}  // namespace

std::unique_ptr<HidReportSource> make_hidapi_source(const std::string& path) {
    return std::make_unique<HidapiSource>(path);
}

std::vector<SpaceMouseHidEntry> enumerate_spacemouse_hid(std::string* error) {
    if (hid_init() != 0) {
        if (error) *error = hid_init_error();
        return {};
    }
    return list_spacemice();
}

#else  // no hidapi in this build

namespace {

class UnavailableSource final : public HidReportSource {
public:
    std::string open(HidDeviceIdentity&) override {
        return "spacemouse: not available in this build (built without hidapi; install libhidapi-dev and "
               "reconfigure with SULCUS_WITH_HIDAPI=ON)";
    }
    int read_timeout(uint8_t*, std::size_t, int) noexcept override { return -1; }
    void close() noexcept override {}
};

}  // namespace

std::unique_ptr<HidReportSource> make_hidapi_source(const std::string&) {
    return std::make_unique<UnavailableSource>();
}

std::vector<SpaceMouseHidEntry> enumerate_spacemouse_hid(std::string* error) {
    if (error) *error = "SpaceMouse enumeration not available in this build (no hidapi)";
    return {};
}

#endif

}  // namespace sulcus
