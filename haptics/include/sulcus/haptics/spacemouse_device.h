// A 3Dconnexion SpaceMouse as a Device: a reader thread pulls HID input reports (hidapi, hidraw
// backend) and folds them into a deflection state published lock-free; read() turns that state
// into a pose by integrating it once per servo tick. Input only: 6 DOF in, 0 out.
// The byte source is an interface so tests can feed recorded reports through the real reader
// thread. See docs/spacemouse.md.
#pragma once

#include "sulcus/haptics/device.h"
#include "sulcus/haptics/spacemouse.h"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sulcus {

// What was opened: IDs, the product string and the hidraw node.
struct HidDeviceIdentity {
    uint16_t vendor = 0;
    uint16_t product = 0;
    std::string product_name;  // the device's product string; "" when it gave none
    std::string path;          // e.g. /dev/hidraw3
};

// Where the reader thread gets report bytes from. open() and close() run on the thread calling
// SpaceMouseDevice::start()/stop(); read_timeout() runs on the reader thread only.
class HidReportSource {
public:
    virtual ~HidReportSource() = default;
    // Opens the device and says what it is; "" on success, else one line saying why not.
    virtual std::string open(HidDeviceIdentity& identity) = 0;
    // Waits at most timeout_ms for one input report (report ID first). Returns its size, 0 when
    // none came in time, -1 when the device failed or went away (the reader then stops).
    virtual int read_timeout(uint8_t* buffer, std::size_t size, int timeout_ms) noexcept = 0;
    virtual void close() noexcept = 0;
};

// The hidapi (hidraw) source: opens `path`, or when empty the first SpaceMouse hid_enumerate
// lists. Without hidapi in the build, open() says so.
std::unique_ptr<HidReportSource> make_hidapi_source(const std::string& path = "");

// A SpaceMouse interface as hid_enumerate lists it (no device is opened).
struct SpaceMouseHidEntry {
    HidDeviceIdentity identity;
    int interface_number = -1;
};
// Every SpaceMouse hidapi can see. On failure (hid_init, or no hidapi in this build) returns
// nothing and sets *error when given.
std::vector<SpaceMouseHidEntry> enumerate_spacemouse_hid(std::string* error = nullptr);

// The udev rule that grants hidraw access to SpaceMice (one line, for messages and docs).
const char* spacemouse_udev_rule();

struct SpaceMouseDeviceConfig {
    std::string path;  // hidraw node to open; "" = the first SpaceMouse found
    Pose start_pose;   // the pose read() starts from
    SpaceMouseMapping mapping;
    // The box the position is clamped to, device frame (m). Default: ±0.1 m, a probing volume.
    Vec3 workspace_min_m{-0.1};
    Vec3 workspace_max_m{0.1};
    double rate_hz = 1000.0;  // read() advances the pose by 1 / rate_hz per call
    // Report layout; unset = from the product ID (layout_for_product).
    std::optional<SpaceMouseLayout> layout;
    int read_timeout_ms = 20;  // the reader's wait per hid_read_timeout; bounds stop()'s delay
};

class SpaceMouseDevice final : public Device {
public:
    // Reads through hidapi.
    explicit SpaceMouseDevice(SpaceMouseDeviceConfig config = {});
    // Reads through `source` (tests: recorded bytes).
    SpaceMouseDevice(SpaceMouseDeviceConfig config, std::unique_ptr<HidReportSource> source);
    ~SpaceMouseDevice() override;  // stops the reader
    SpaceMouseDevice(const SpaceMouseDevice&) = delete;
    SpaceMouseDevice& operator=(const SpaceMouseDevice&) = delete;

    const DeviceCapabilities& capabilities() const override { return caps_; }
    // Opens the source, picks the layout, starts the reader thread; the pose restarts at the
    // start pose. "" or one line saying why not.
    std::string start() override;
    // Integrates the latest deflection over one nominal tick and clamps to the workspace.
    // After the reader saw an error or an unplug: connected = false, kDeviceFaultComm, false.
    bool read(DeviceSample& sample) noexcept override;
    // No force output; a non-finite command is counted and reported as kDeviceFaultBadCommand.
    void write(const Vec3& force_N, const Vec3& torque_Nm) noexcept override;
    void stop() override;

    // Settings (take effect at the next start()).
    void set_start_pose(const Pose& pose) { config_.start_pose = pose; }
    void set_workspace(const Vec3& min_m, const Vec3& max_m);
    void set_mapping(const SpaceMouseMapping& mapping) { config_.mapping = mapping; }

    const HidDeviceIdentity& identity() const noexcept { return identity_; }
    // The layout in use (it may switch from combined to split, see docs/spacemouse.md).
    SpaceMouseLayout layout() const noexcept { return layout_.load(std::memory_order_relaxed); }
    // Reader counters, any thread.
    uint64_t reports_parsed() const noexcept { return parsed_.load(std::memory_order_relaxed); }
    uint64_t reports_rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }
    uint64_t bad_commands() const noexcept { return bad_commands_; }

private:
    struct Reader;  // the thread and the published state (hidapi and the seqlock stay in the .cpp)

    SpaceMouseDeviceConfig config_;
    std::unique_ptr<HidReportSource> source_;
    std::unique_ptr<Reader> reader_;
    DeviceCapabilities caps_;
    HidDeviceIdentity identity_;
    std::atomic<SpaceMouseLayout> layout_{SpaceMouseLayout::combined};
    std::atomic<uint64_t> parsed_{0};
    std::atomic<uint64_t> rejected_{0};

    // Servo-thread state.
    bool running_ = false;
    Pose pose_;
    double dt_s_ = 1e-3;
    uint32_t fault_ = kDeviceFaultNotStarted;
    uint64_t bad_commands_ = 0;
};

}  // namespace sulcus
