// Crash-safe session recording, format "sulcus.recording/2" (docs/recording-format.md).
//
// A session is a file header followed by self-checking chunks (each with its own CRC-32), written
// whole with write(2). A crash at any moment leaves a file whose chunks up to the last complete one
// read back; the reader stops at the first chunk that is cut short or fails its CRC and says what
// it dropped.
//
// Threading: single producer per ring, single consumer. The servo thread calls add_tick() (copies
// into a preallocated lock-free ring; no allocation, lock, I/O or throw). One other thread (or the
// same) calls add_event(). flush() drains the rings into chunks and does the I/O; call it from a
// non-servo thread, or let start_writer_thread() do it periodically.
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/engine/types.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace sulcus {

inline constexpr const char* kRecordingFormat = "sulcus.recording/2";
inline constexpr uint16_t kRecordingVersion = 2;
// Bytes of one tick record in a tick chunk's payload (version 1: 128, still read).
inline constexpr std::size_t kTickRecordBytes = 160;
inline constexpr std::size_t kTickRecordBytesV1 = 128;
// Largest number of ticks a chunk holds: 100 ms at 1 kHz.
inline constexpr uint32_t kMaxTicksPerChunk = 100;

// One servo tick as recorded: what the device reported, what the tick's clock said, and what was
// sent back. Everything the tick's outcome depends on besides the model and the servo commands
// (recorded as events) is here, so a replay recomputes the same forces bit for bit.
struct TickSample {
    uint64_t tick = 0;               // servo tick index since the start of the session
    double time_s = 0.0;             // session time of the tick
    Pose device_pose;                // pose read from the device, device frame
    uint32_t buttons = 0;            // device buttons, bit i = button i pressed
    Vec3 force_N{0.0};               // force sent to the device (after the safety layer)
    Vec3 torque_Nm{0.0};             // torque sent to the device
    StepStatus status = StepStatus::Free;
    // The tick's inputs to the safety layer.
    double dt_s = 0.0;               // tick length the safety layer was given; 0: not recorded (v1)
    uint32_t device_fault = 0;       // DeviceSample::fault
    bool device_read = true;         // Device::read() gave a sample
    bool connected = true;           // DeviceSample::connected
    bool deadline_missed = false;    // the tick was told its previous work overran
    uint8_t safety_state = 0;        // SafetyState after the tick (for review; not an input)
    float step_us = -1.0f;           // the step's wall time, us; < 0 when no step ran
};

// A UI or lesson event at a tick: a short kind ("site_charted", "lesson_step") and JSON text.
struct RecordingEvent {
    uint64_t tick = 0;
    std::string kind;
    std::string json;
};

// A named JSON document stored alongside the session (e.g. a lesson's score sheet), written after
// the ticks and events added before it. `tick`: the number of ticks added before it.
struct RecordingAnnex {
    uint64_t tick = 0;
    std::string name;
    std::string json;
};

// Largest annex: name + JSON text.
inline constexpr std::size_t kMaxAnnexBytes = std::size_t{16} << 20;

struct RecordingMetadata {
    std::string case_path;   // scene or case file the session ran
    std::string lesson;      // lesson file the session ran, relative to the content root; "" none
    std::string device;      // device name ("phantom-omni", "mouse", "replay", ...)
    double rate_hz = 1000.0;  // servo rate
    std::string start_time;  // ISO 8601 UTC; empty: the time open() is called
};

enum class SyncPolicy : uint8_t {
    None,      // write(2) only: survives a crash of the program, not of the machine
    DataSync,  // fdatasync after each flush(): also survives power loss, costs a disk round trip
};

struct RecordingOptions {
    uint32_t ticks_per_chunk = kMaxTicksPerChunk;  // 1..kMaxTicksPerChunk
    uint32_t tick_ring = 4096;     // ticks buffered between producer and flush (4 s at 1 kHz)
    uint32_t event_ring = 64;      // events buffered between producer and flush
    uint32_t max_event_bytes = 4096;  // largest kind + JSON text of one event
    SyncPolicy sync = SyncPolicy::DataSync;
};

struct RecordingStats {
    uint64_t ticks_written = 0;
    uint64_t events_written = 0;
    uint64_t annexes_written = 0;
    uint64_t ticks_dropped = 0;   // add_tick() found the ring full (flush not keeping up)
    uint64_t events_dropped = 0;  // ring full or event larger than max_event_bytes
    uint64_t chunks_written = 0;
    uint64_t bytes_written = 0;   // including the file header
    uint64_t flushes = 0;         // flush() calls that wrote at least one chunk
    double last_flush_us = 0.0;   // wall time of the last flush that wrote, I/O and sync included
    double max_flush_us = 0.0;
};

struct RecordingRead;

class RecordingWriter {
public:
    RecordingWriter();
    ~RecordingWriter();  // closes (errors are lost: call close() to see them)
    RecordingWriter(const RecordingWriter&) = delete;
    RecordingWriter& operator=(const RecordingWriter&) = delete;

    // Creates (truncates) `path`, writes and syncs the file header, allocates the rings.
    // Returns "" or a one-line error naming the file.
    std::string open(const std::string& path, const RecordingMetadata& metadata, const RecordingOptions& options = {});
    bool is_open() const { return fd_ >= 0; }

    // Producer (servo thread): copies the sample into the ring. Never blocks, allocates or throws.
    // Returns false, and counts the tick as dropped, when the ring is full or the writer is closed.
    bool add_tick(const TickSample& sample) noexcept;
    // Ticks added but not yet taken by flush(); producer or consumer may ask.
    uint32_t pending_ticks() const noexcept;

    // Producer of events (one thread). Copies into the event ring; false (counted as dropped) when
    // full, closed, or kind + json is longer than max_event_bytes.
    bool add_event(uint64_t tick, std::string_view kind, std::string_view json) noexcept;

    // For a non-servo thread (allocates, takes the consumer mutex): queues a named JSON document,
    // written by the next flush() or close() after every tick and event added before this call,
    // at tick index = the number of ticks added so far. Returns "" or a one-line error (closed, or
    // name + json longer than kMaxAnnexBytes). The text is stored as given (not parsed).
    std::string add_annex(std::string_view name, std::string_view json);

    // Consumer: writes every tick and event added so far as whole chunks (<= ticks_per_chunk ticks
    // each, one write(2) per chunk), then syncs per the policy. Returns "" or a one-line error.
    // Serialised with other consumers (the writer thread) by a mutex the producers never take.
    std::string flush();

    // Runs flush() every `period_s` on a thread of its own until close(). An error there stops
    // the thread; close() reports it.
    std::string start_writer_thread(double period_s = 0.02);

    // Stops the writer thread, flushes the rest, syncs and closes the file. Returns "" or the first
    // error seen since open (including the writer thread's).
    std::string close();

    RecordingStats stats() const;

private:
    // add_annex with the tick given (a rewrite keeps each stored annex's tick).
    std::string queue_annex(uint64_t tick, std::string_view name, std::string_view json);
    friend std::string write_recording(const std::string& path, const RecordingRead& recording, SyncPolicy sync);

    struct Impl;
    std::unique_ptr<Impl> impl_;
    int fd_ = -1;
};

// What a reader found after the last good chunk.
struct RecordingTruncation {
    bool truncated = false;        // the file did not end on a chunk boundary with all CRCs good
    uint64_t offset = 0;           // byte offset of the first chunk not read
    uint64_t bytes_dropped = 0;    // file bytes from `offset` to the end
    uint64_t ticks_dropped = 0;    // ticks the dropped chunk claims to hold, if its header was whole
    std::string reason;            // one line: "file: byte N: chunk cut short (...)" / "... CRC mismatch"
};

struct RecordingRead {
    std::string error;  // one line naming the file and the byte offset; empty when the file opened
    uint16_t version = 0;
    std::string metadata_json;  // the header's JSON text as stored
    RecordingMetadata metadata;  // parsed from it
    std::vector<TickSample> ticks;          // in file order
    std::vector<RecordingEvent> events;     // in file order
    std::vector<RecordingAnnex> annexes;    // in file order
    RecordingTruncation truncation;
    bool ok() const { return error.empty(); }
};

RecordingRead read_recording(const std::string& path);

// Writes `recording` as a new file at `path`: its metadata (start_time kept as given), ticks,
// events in file order and then its annexes, e.g. to rewrite a recording with an edited annex.
// Written under a temporary name beside `path`, then renamed over it, so `path` is never seen
// half-written. Returns "" or a one-line error naming the file.
std::string write_recording(const std::string& path, const RecordingRead& recording,
                            SyncPolicy sync = SyncPolicy::None);

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib's crc32). Pass the previous value
// to continue a running checksum; start from 0.
uint32_t crc32(const void* data, std::size_t size, uint32_t crc = 0) noexcept;

}  // namespace sulcus
