// Session recording writer and reader, format "sulcus.recording/2" (docs/recording-format.md).
#include "sulcus/haptics/recording.h"

#include "sulcus/engine/json_text.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <thread>

#include <fcntl.h>
#include <unistd.h>

namespace sulcus {
namespace {

// Layout constants; the byte tables in docs/recording-format.md are the reference.
constexpr char kFileMagic[8] = {'S', 'U', 'L', 'C', 'S', 'R', 'E', 'C'};
constexpr char kChunkMagic[4] = {'C', 'H', 'N', 'K'};
constexpr std::size_t kFileHeaderFixed = 16;  // magic, version, flags, metadata length
constexpr std::size_t kChunkHeaderBytes = 24;
constexpr std::size_t kCrcBytes = 4;
constexpr std::size_t kEventHeaderBytes = 16;
constexpr uint8_t kChunkTicks = 1;
constexpr uint8_t kChunkEvents = 2;
constexpr uint8_t kChunkAnnex = 3;
constexpr uint32_t kMaxMetadataBytes = 1u << 20;
constexpr uint32_t kMaxPayloadBytes = 64u << 20;  // larger claims are corrupt headers

// --- CRC-32 -------------------------------------------------------------------------------

struct CrcTable {
    uint32_t t[256];
    constexpr CrcTable() : t{} {
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
            t[i] = c;
        }
    }
};
constexpr CrcTable kCrc;

// --- little-endian encoding, independent of the host's byte order -------------------------

void put_u16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}
void put_u32(uint8_t* p, uint32_t v) {
    for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void put_u64(uint8_t* p, uint64_t v) {
    for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
// Doubles go as their IEEE-754 bits: bit-exact, NaN payloads included.
void put_f64(uint8_t* p, double v) { put_u64(p, std::bit_cast<uint64_t>(v)); }

uint16_t get_u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t get_u32(const uint8_t* p) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}
uint64_t get_u64(const uint8_t* p) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}
double get_f64(const uint8_t* p) { return std::bit_cast<double>(get_u64(p)); }

void encode_tick(uint8_t* p, const TickSample& s) {
    put_u64(p + 0, s.tick);
    put_f64(p + 8, s.time_s);
    put_f64(p + 16, s.device_pose.position.x);
    put_f64(p + 24, s.device_pose.position.y);
    put_f64(p + 32, s.device_pose.position.z);
    put_f64(p + 40, s.device_pose.orientation.w);
    put_f64(p + 48, s.device_pose.orientation.x);
    put_f64(p + 56, s.device_pose.orientation.y);
    put_f64(p + 64, s.device_pose.orientation.z);
    put_f64(p + 72, s.force_N.x);
    put_f64(p + 80, s.force_N.y);
    put_f64(p + 88, s.force_N.z);
    put_f64(p + 96, s.torque_Nm.x);
    put_f64(p + 104, s.torque_Nm.y);
    put_f64(p + 112, s.torque_Nm.z);
    put_u32(p + 120, s.buttons);
    p[124] = static_cast<uint8_t>(s.status);
    p[125] = static_cast<uint8_t>((s.device_read ? 1u : 0u) | (s.connected ? 2u : 0u) | (s.deadline_missed ? 4u : 0u));
    p[126] = s.safety_state;
    p[127] = 0;
    put_f64(p + 128, s.dt_s);
    put_u32(p + 136, s.device_fault);
    put_u32(p + 140, std::bit_cast<uint32_t>(s.step_us));
    std::memset(p + 144, 0, kTickRecordBytes - 144);
}

// `v1`: a version-1 record (128 bytes) has no clock or device flags; it reads as a tick of the
// nominal length on a connected, answering device.
TickSample decode_tick(const uint8_t* p, bool v1) {
    TickSample s;
    s.tick = get_u64(p + 0);
    s.time_s = get_f64(p + 8);
    s.device_pose.position = Vec3(get_f64(p + 16), get_f64(p + 24), get_f64(p + 32));
    s.device_pose.orientation = Quat(get_f64(p + 40), get_f64(p + 48), get_f64(p + 56), get_f64(p + 64));
    s.force_N = Vec3(get_f64(p + 72), get_f64(p + 80), get_f64(p + 88));
    s.torque_Nm = Vec3(get_f64(p + 96), get_f64(p + 104), get_f64(p + 112));
    s.buttons = get_u32(p + 120);
    s.status = static_cast<StepStatus>(p[124]);
    if (v1) return s;
    s.device_read = (p[125] & 1u) != 0;
    s.connected = (p[125] & 2u) != 0;
    s.deadline_missed = (p[125] & 4u) != 0;
    s.safety_state = p[126];
    s.dt_s = get_f64(p + 128);
    s.device_fault = get_u32(p + 136);
    s.step_us = std::bit_cast<float>(get_u32(p + 140));
    return s;
}

// Fills the chunk header in front of `payload_bytes` of payload and the CRC after it.
std::size_t seal_chunk(uint8_t* chunk, uint8_t type, uint32_t payload_bytes, uint32_t records, uint64_t first_tick) {
    std::memcpy(chunk, kChunkMagic, 4);
    chunk[4] = type;
    chunk[5] = chunk[6] = chunk[7] = 0;
    put_u32(chunk + 8, payload_bytes);
    put_u32(chunk + 12, records);
    put_u64(chunk + 16, first_tick);
    const std::size_t body = kChunkHeaderBytes + payload_bytes;
    put_u32(chunk + body, crc32(chunk, body));
    return body + kCrcBytes;
}

std::string errno_text(int e) { return std::strerror(e); }

// write(2) until done, retrying on EINTR and short writes.
bool write_all(int fd, const uint8_t* p, std::size_t n, int& err) {
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR) continue;
            err = errno;
            return false;
        }
        p += w;
        n -= static_cast<std::size_t>(w);
    }
    return true;
}

std::string utc_now_iso8601() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

// Makes the new file's directory entry durable too (a synced file nobody can find is no help).
void sync_parent_dir(const std::string& path) {
    std::filesystem::path dir = std::filesystem::path(path).parent_path();
    if (dir.empty()) dir = ".";
    const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd < 0) return;
    ::fsync(dfd);
    ::close(dfd);
}

double elapsed_us(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - since).count();
}

struct EventSlot {
    uint64_t tick = 0;
    uint32_t kind_bytes = 0;
    uint32_t json_bytes = 0;
};

}  // namespace

uint32_t crc32(const void* data, std::size_t size, uint32_t crc) noexcept {
    const auto* p = static_cast<const uint8_t*>(data);
    crc = ~crc;
    for (std::size_t i = 0; i < size; ++i) crc = kCrc.t[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
    return ~crc;
}

// --- writer -------------------------------------------------------------------------------

// The rings are single-producer single-consumer: the producer owns `head` (release store after
// filling a slot), the consumer owns `tail` (release store after copying slots out). Each side
// reads the other's index with acquire, so a slot is never read while written or reused early.
struct RecordingWriter::Impl {
    std::string path;
    RecordingOptions options;

    std::vector<TickSample> ticks;  // capacity a power of two
    uint64_t tick_mask = 0;
    alignas(64) std::atomic<uint64_t> tick_head{0};
    alignas(64) std::atomic<uint64_t> tick_tail{0};

    std::vector<EventSlot> events;
    std::vector<char> event_bytes;  // event_ring * max_event_bytes: kind then json per slot
    uint64_t event_mask = 0;
    alignas(64) std::atomic<uint64_t> event_head{0};
    alignas(64) std::atomic<uint64_t> event_tail{0};

    std::atomic<bool> accepting{false};
    std::atomic<uint64_t> ticks_dropped{0};
    std::atomic<uint64_t> events_dropped{0};

    // Consumer side, under `consumer`.
    std::mutex consumer;
    std::vector<uint8_t> tick_chunk;   // header + ticks_per_chunk records + CRC
    std::vector<uint8_t> event_chunk;  // header + a whole event ring + CRC
    std::vector<RecordingAnnex> annexes;  // queued by add_annex, written by the next flush
    RecordingStats stats;
    std::string first_error;
    bool failed = false;

    // The writer thread.
    std::thread thread;
    std::mutex wake_mutex;
    std::condition_variable wake;
    bool stop = false;
};

namespace {
uint64_t ring_capacity(uint32_t wanted) { return std::bit_ceil(std::max<uint64_t>(wanted, 2)); }
}  // namespace

RecordingWriter::RecordingWriter() = default;

RecordingWriter::~RecordingWriter() { close(); }

std::string RecordingWriter::open(const std::string& path, const RecordingMetadata& metadata,
                                  const RecordingOptions& options) {
    close();
    if (options.ticks_per_chunk < 1 || options.ticks_per_chunk > kMaxTicksPerChunk)
        return path + ": ticks_per_chunk must be 1.." + std::to_string(kMaxTicksPerChunk);
    if (options.max_event_bytes < 1 || options.max_event_bytes > (1u << 20))
        return path + ": max_event_bytes must be 1..1048576";

    if (options.tick_ring < 1 || options.tick_ring > (1u << 22) || options.event_ring < 1 ||
        options.event_ring > (1u << 16))
        return path + ": tick_ring must be 1..4194304 and event_ring 1..65536";
    if (ring_capacity(options.event_ring) * (kEventHeaderBytes + options.max_event_bytes) > kMaxPayloadBytes)
        return path + ": event_ring * max_event_bytes exceeds the 64 MiB chunk limit";

    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->options = options;
    impl->ticks.resize(ring_capacity(options.tick_ring));
    impl->tick_mask = impl->ticks.size() - 1;
    impl->events.resize(ring_capacity(options.event_ring));
    impl->event_mask = impl->events.size() - 1;
    impl->event_bytes.resize(impl->events.size() * options.max_event_bytes);
    impl->tick_chunk.resize(kChunkHeaderBytes + options.ticks_per_chunk * kTickRecordBytes + kCrcBytes);
    impl->event_chunk.resize(kChunkHeaderBytes + impl->events.size() * (kEventHeaderBytes + options.max_event_bytes) +
                             kCrcBytes);

    nlohmann::json meta = {
        {"format", kRecordingFormat},
        {"case", metadata.case_path},
        {"device", metadata.device},
        {"rate_hz", metadata.rate_hz},
        {"start_time", metadata.start_time.empty() ? utc_now_iso8601() : metadata.start_time},
    };
    if (!metadata.lesson.empty()) meta["lesson"] = metadata.lesson;
    const std::string text = meta.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() > kMaxMetadataBytes) return path + ": metadata longer than 1 MiB";

    std::vector<uint8_t> header(kFileHeaderFixed + text.size() + kCrcBytes);
    std::memcpy(header.data(), kFileMagic, 8);
    put_u16(header.data() + 8, kRecordingVersion);
    put_u16(header.data() + 10, 0);
    put_u32(header.data() + 12, static_cast<uint32_t>(text.size()));
    std::memcpy(header.data() + kFileHeaderFixed, text.data(), text.size());
    put_u32(header.data() + kFileHeaderFixed + text.size(), crc32(header.data(), kFileHeaderFixed + text.size()));

    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return path + ": cannot create: " + errno_text(errno);
    int err = 0;
    if (!write_all(fd, header.data(), header.size(), err)) {
        ::close(fd);
        return path + ": cannot write header: " + errno_text(err);
    }
    if (options.sync == SyncPolicy::DataSync) {
        if (::fdatasync(fd) != 0) {
            err = errno;
            ::close(fd);
            return path + ": fdatasync: " + errno_text(err);
        }
        sync_parent_dir(path);
    }
    impl->stats.bytes_written = header.size();
    impl->accepting.store(true, std::memory_order_release);
    impl_ = std::move(impl);
    fd_ = fd;
    return "";
}

bool RecordingWriter::add_tick(const TickSample& sample) noexcept {
    Impl* m = impl_.get();
    if (m == nullptr) return false;
    if (!m->accepting.load(std::memory_order_acquire)) {
        m->ticks_dropped.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    const uint64_t head = m->tick_head.load(std::memory_order_relaxed);
    const uint64_t tail = m->tick_tail.load(std::memory_order_acquire);
    if (head - tail >= m->ticks.size()) {
        m->ticks_dropped.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    m->ticks[head & m->tick_mask] = sample;
    m->tick_head.store(head + 1, std::memory_order_release);
    return true;
}

uint32_t RecordingWriter::pending_ticks() const noexcept {
    const Impl* m = impl_.get();
    if (m == nullptr) return 0;
    return static_cast<uint32_t>(m->tick_head.load(std::memory_order_acquire) -
                                 m->tick_tail.load(std::memory_order_acquire));
}

bool RecordingWriter::add_event(uint64_t tick, std::string_view kind, std::string_view json) noexcept {
    Impl* m = impl_.get();
    if (m == nullptr) return false;
    const uint64_t head = m->event_head.load(std::memory_order_relaxed);
    const uint64_t tail = m->event_tail.load(std::memory_order_acquire);
    if (!m->accepting.load(std::memory_order_acquire) || head - tail >= m->events.size() ||
        kind.size() + json.size() > m->options.max_event_bytes) {
        m->events_dropped.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    const uint64_t slot = head & m->event_mask;
    EventSlot& e = m->events[slot];
    e.tick = tick;
    e.kind_bytes = static_cast<uint32_t>(kind.size());
    e.json_bytes = static_cast<uint32_t>(json.size());
    char* dst = m->event_bytes.data() + slot * m->options.max_event_bytes;
    std::memcpy(dst, kind.data(), kind.size());
    std::memcpy(dst + kind.size(), json.data(), json.size());
    m->event_head.store(head + 1, std::memory_order_release);
    return true;
}

std::string RecordingWriter::flush() {
    Impl* m = impl_.get();
    if (m == nullptr || fd_ < 0) return "";
    std::lock_guard<std::mutex> lock(m->consumer);
    const auto started = std::chrono::steady_clock::now();
    bool wrote = false;
    int err = 0;

    // Ticks: whole chunks of at most ticks_per_chunk, slots released as soon as they are encoded.
    const uint64_t tick_end = m->tick_head.load(std::memory_order_acquire);
    uint64_t t = m->tick_tail.load(std::memory_order_relaxed);
    while (t < tick_end) {
        const uint32_t n = static_cast<uint32_t>(std::min<uint64_t>(tick_end - t, m->options.ticks_per_chunk));
        uint8_t* payload = m->tick_chunk.data() + kChunkHeaderBytes;
        for (uint32_t i = 0; i < n; ++i) encode_tick(payload + i * kTickRecordBytes, m->ticks[(t + i) & m->tick_mask]);
        const uint64_t first_tick = m->ticks[t & m->tick_mask].tick;
        t += n;
        m->tick_tail.store(t, std::memory_order_release);
        if (m->failed) {
            m->stats.ticks_dropped += n;  // a failed file gets nothing more after its last good chunk
            continue;
        }
        const std::size_t bytes =
            seal_chunk(m->tick_chunk.data(), kChunkTicks, static_cast<uint32_t>(n * kTickRecordBytes), n, first_tick);
        if (!write_all(fd_, m->tick_chunk.data(), bytes, err)) {
            m->failed = true;
            m->first_error = m->path + ": write: " + errno_text(err);
            m->stats.ticks_dropped += n;
            continue;
        }
        wrote = true;
        m->stats.ticks_written += n;
        m->stats.chunks_written += 1;
        m->stats.bytes_written += bytes;
    }

    // Events: everything pending fits one chunk (the chunk buffer holds a whole ring).
    const uint64_t event_end = m->event_head.load(std::memory_order_acquire);
    uint64_t e = m->event_tail.load(std::memory_order_relaxed);
    if (e < event_end) {
        uint8_t* payload = m->event_chunk.data() + kChunkHeaderBytes;
        std::size_t used = 0;
        const uint32_t n = static_cast<uint32_t>(event_end - e);
        const uint64_t first_tick = m->events[e & m->event_mask].tick;
        for (; e < event_end; ++e) {
            const uint64_t slot = e & m->event_mask;
            const EventSlot& ev = m->events[slot];
            uint8_t* rec = payload + used;
            put_u64(rec, ev.tick);
            put_u32(rec + 8, ev.kind_bytes);
            put_u32(rec + 12, ev.json_bytes);
            std::memcpy(rec + kEventHeaderBytes, m->event_bytes.data() + slot * m->options.max_event_bytes,
                        ev.kind_bytes + ev.json_bytes);
            used += kEventHeaderBytes + ev.kind_bytes + ev.json_bytes;
        }
        m->event_tail.store(e, std::memory_order_release);
        if (m->failed) {
            m->stats.events_dropped += n;
        } else {
            const std::size_t bytes =
                seal_chunk(m->event_chunk.data(), kChunkEvents, static_cast<uint32_t>(used), n, first_tick);
            if (!write_all(fd_, m->event_chunk.data(), bytes, err)) {
                m->failed = true;
                m->first_error = m->path + ": write: " + errno_text(err);
                m->stats.events_dropped += n;
            } else {
                wrote = true;
                m->stats.events_written += n;
                m->stats.chunks_written += 1;
                m->stats.bytes_written += bytes;
            }
        }
    }

    // Annexes: after every tick and event added before them (those were drained above). One chunk
    // each, built here: they are rare and may be large.
    for (const RecordingAnnex& a : m->annexes) {
        if (m->failed) break;
        const std::size_t payload_bytes = 8 + a.name.size() + a.json.size();
        std::vector<uint8_t> chunk(kChunkHeaderBytes + payload_bytes + kCrcBytes);
        uint8_t* p = chunk.data() + kChunkHeaderBytes;
        put_u32(p, static_cast<uint32_t>(a.name.size()));
        std::memcpy(p + 4, a.name.data(), a.name.size());
        put_u32(p + 4 + a.name.size(), static_cast<uint32_t>(a.json.size()));
        std::memcpy(p + 8 + a.name.size(), a.json.data(), a.json.size());
        const std::size_t bytes = seal_chunk(chunk.data(), kChunkAnnex, static_cast<uint32_t>(payload_bytes), 1, a.tick);
        if (!write_all(fd_, chunk.data(), bytes, err)) {
            m->failed = true;
            m->first_error = m->path + ": write: " + errno_text(err);
            break;
        }
        wrote = true;
        m->stats.annexes_written += 1;
        m->stats.chunks_written += 1;
        m->stats.bytes_written += bytes;
    }
    m->annexes.clear();

    if (wrote && !m->failed && m->options.sync == SyncPolicy::DataSync && ::fdatasync(fd_) != 0) {
        m->failed = true;
        m->first_error = m->path + ": fdatasync: " + errno_text(errno);
    }
    if (wrote) {
        m->stats.flushes += 1;
        m->stats.last_flush_us = elapsed_us(started);
        m->stats.max_flush_us = std::max(m->stats.max_flush_us, m->stats.last_flush_us);
    }
    return m->first_error;
}

std::string RecordingWriter::add_annex(std::string_view name, std::string_view json) {
    Impl* m = impl_.get();
    if (m == nullptr) return "recording: add_annex before open";
    if (name.size() + json.size() > kMaxAnnexBytes)
        return m->path + ": annex \"" + textio::one_line(std::string(name.substr(0, 64))) + "\" is larger than " +
               std::to_string(kMaxAnnexBytes >> 20) + " MiB";
    // Every tick added before this call is in the ring by now (the caller saw it added).
    return queue_annex(m->tick_head.load(std::memory_order_acquire), name, json);
}

std::string RecordingWriter::queue_annex(uint64_t tick, std::string_view name, std::string_view json) {
    Impl* m = impl_.get();
    if (m == nullptr) return "recording: add_annex before open";
    if (name.size() + json.size() > kMaxAnnexBytes)
        return m->path + ": annex \"" + textio::one_line(std::string(name.substr(0, 64))) + "\" is larger than " +
               std::to_string(kMaxAnnexBytes >> 20) + " MiB";
    std::lock_guard<std::mutex> lock(m->consumer);
    if (!m->accepting.load(std::memory_order_acquire)) return m->path + ": add_annex after close";
    m->annexes.push_back({tick, std::string(name), std::string(json)});
    return "";
}

std::string RecordingWriter::start_writer_thread(double period_s) {
    Impl* m = impl_.get();
    if (m == nullptr || fd_ < 0) return "recording: start_writer_thread before open";
    if (m->thread.joinable()) return m->path + ": writer thread already running";
    if (!(period_s > 0.0) || period_s > 0.1) return m->path + ": writer period must be in (0, 0.1] s";
    m->stop = false;
    const auto period = std::chrono::duration<double>(period_s);
    m->thread = std::thread([this, m, period] {
        std::unique_lock<std::mutex> lock(m->wake_mutex);
        while (!m->stop) {
            m->wake.wait_for(lock, period, [m] { return m->stop; });
            if (m->stop) break;
            lock.unlock();
            const std::string err = flush();
            lock.lock();
            if (!err.empty()) break;  // kept in first_error; close() reports it
        }
    });
    return "";
}

std::string RecordingWriter::close() {
    Impl* m = impl_.get();
    if (m == nullptr || fd_ < 0) return "";
    if (m->thread.joinable()) {
        {
            std::lock_guard<std::mutex> lock(m->wake_mutex);
            m->stop = true;
        }
        m->wake.notify_all();
        m->thread.join();
    }
    m->accepting.store(false, std::memory_order_release);
    std::string err = flush();
    if (err.empty() && m->options.sync == SyncPolicy::DataSync && ::fsync(fd_) != 0)
        err = m->path + ": fsync: " + errno_text(errno);
    if (::close(fd_) != 0 && err.empty()) err = m->path + ": close: " + errno_text(errno);
    fd_ = -1;
    std::lock_guard<std::mutex> lock(m->consumer);
    if (m->first_error.empty()) m->first_error = err;
    return m->first_error;
}

RecordingStats RecordingWriter::stats() const {
    Impl* m = impl_.get();
    if (m == nullptr) return {};
    std::lock_guard<std::mutex> lock(m->consumer);
    RecordingStats s = m->stats;
    s.ticks_dropped += m->ticks_dropped.load(std::memory_order_relaxed);
    s.events_dropped += m->events_dropped.load(std::memory_order_relaxed);
    return s;
}

// --- reader -------------------------------------------------------------------------------

namespace {

std::string at(const std::string& path, uint64_t offset) { return path + ": byte " + std::to_string(offset) + ": "; }

// Reads one chunk's records into `out`. Returns "" or why the (CRC-good) chunk is malformed.
std::string decode_chunk(uint8_t type, const uint8_t* payload, uint32_t bytes, uint32_t records, uint64_t first_tick,
                         RecordingRead& out) {
    if (type == kChunkTicks) {
        const bool v1 = out.version == 1;
        const std::size_t record_bytes = v1 ? kTickRecordBytesV1 : kTickRecordBytes;
        if (static_cast<uint64_t>(records) * record_bytes != bytes)
            return "tick chunk of " + std::to_string(records) + " records has " + std::to_string(bytes) +
                   " payload bytes";
        for (uint32_t i = 0; i < records; ++i) out.ticks.push_back(decode_tick(payload + i * record_bytes, v1));
        if (records > 0 && out.ticks[out.ticks.size() - records].tick != first_tick)
            return "tick chunk's first tick index does not match its first record";
        return "";
    }
    if (type == kChunkEvents) {
        uint64_t used = 0;
        for (uint32_t i = 0; i < records; ++i) {
            if (bytes - used < kEventHeaderBytes) return "event " + std::to_string(i) + " runs past the chunk";
            const uint8_t* rec = payload + used;
            const uint64_t kind = get_u32(rec + 8), json = get_u32(rec + 12);
            if (bytes - used - kEventHeaderBytes < kind + json)
                return "event " + std::to_string(i) + " runs past the chunk";
            const char* text = reinterpret_cast<const char*>(rec + kEventHeaderBytes);
            out.events.push_back({get_u64(rec), std::string(text, kind), std::string(text + kind, json)});
            used += kEventHeaderBytes + kind + json;
        }
        if (used != bytes) return "event chunk has " + std::to_string(bytes - used) + " bytes after its records";
        return "";
    }
    if (type == kChunkAnnex) {
        if (records != 1) return "annex chunk holds " + std::to_string(records) + " records, not 1";
        if (bytes < 4) return "annex runs past the chunk";
        const uint64_t name = get_u32(payload);
        if (bytes - 4 < name + 4) return "annex runs past the chunk";
        const uint64_t json = get_u32(payload + 4 + name);
        if (bytes - 8 - name != json) return "annex length does not match its chunk";
        const char* text = reinterpret_cast<const char*>(payload);
        out.annexes.push_back({first_tick, std::string(text + 4, name), std::string(text + 8 + name, json)});
        return "";
    }
    return "";  // a chunk type this reader does not know: skipped (later minor additions)
}

}  // namespace

RecordingRead read_recording(const std::string& path) {
    RecordingRead out;
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        out.error = path + ": byte 0: cannot open: " + errno_text(errno);
        return out;
    }
    const std::vector<uint8_t> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) {
        out.error = path + ": byte 0: read error";
        return out;
    }
    const uint64_t size = data.size();
    const uint8_t* d = data.data();

    // File header: any fault here makes the file unreadable (it is written and synced at open).
    if (size < 8 || std::memcmp(d, kFileMagic, 8) != 0) {
        out.error = at(path, 0) + "not a sulcus recording (bad magic)";
        return out;
    }
    if (size < kFileHeaderFixed) {
        out.error = at(path, size) + "file header cut short";
        return out;
    }
    out.version = get_u16(d + 8);
    if (out.version == 0 || out.version > kRecordingVersion) {
        out.error = at(path, 8) + "recording version " + std::to_string(out.version) +
                    (out.version == 0 ? " is invalid" : " is newer than this reader (" +
                                                            std::to_string(kRecordingVersion) + ")");
        return out;
    }
    const uint32_t meta_bytes = get_u32(d + 12);
    if (meta_bytes > kMaxMetadataBytes || kFileHeaderFixed + meta_bytes + kCrcBytes > size) {
        out.error = at(path, 12) + "metadata length " + std::to_string(meta_bytes) + " runs past the end of the file";
        return out;
    }
    const uint64_t header_end = kFileHeaderFixed + meta_bytes;
    if (crc32(d, header_end) != get_u32(d + header_end)) {
        out.error = at(path, header_end) + "file header CRC mismatch";
        return out;
    }
    out.metadata_json.assign(reinterpret_cast<const char*>(d + kFileHeaderFixed), meta_bytes);
    nlohmann::json meta;
    std::string why;
    if (!textio::parse_json(path, out.metadata_json, meta, why) || !meta.is_object()) {
        out.error = at(path, kFileHeaderFixed) + "metadata is not a JSON object";
        return out;
    }
    const std::string format = out.version == 1 ? "sulcus.recording/1" : kRecordingFormat;
    if (!meta.contains("format") || meta["format"] != format) {
        out.error = at(path, kFileHeaderFixed) + "metadata format is not " + format;
        return out;
    }
    auto text_of = [&](const char* key) {
        return meta.contains(key) && meta[key].is_string() ? meta[key].get<std::string>() : std::string();
    };
    out.metadata.case_path = text_of("case");
    out.metadata.lesson = text_of("lesson");
    out.metadata.device = text_of("device");
    out.metadata.start_time = text_of("start_time");
    if (meta.contains("rate_hz") && meta["rate_hz"].is_number()) out.metadata.rate_hz = meta["rate_hz"].get<double>();

    // Chunks, until the end or the first one that is cut short or fails its check.
    uint64_t off = header_end + kCrcBytes;
    auto stop = [&](const std::string& what, uint64_t ticks_claimed) {
        out.truncation.truncated = true;
        out.truncation.offset = off;
        out.truncation.bytes_dropped = size - off;
        out.truncation.ticks_dropped = ticks_claimed;
        out.truncation.reason = textio::one_line(at(path, off) + what);
    };
    while (off < size) {
        const uint64_t left = size - off;
        const uint8_t* c = d + off;
        if (std::memcmp(c, kChunkMagic, std::min<uint64_t>(left, 4)) != 0) {
            stop("no chunk starts here (bad chunk magic)", 0);
            break;
        }
        if (left < kChunkHeaderBytes) {
            stop("chunk header cut short (" + std::to_string(left) + " of " + std::to_string(kChunkHeaderBytes) +
                     " bytes)",
                 0);
            break;
        }
        const uint8_t type = c[4];
        const uint32_t payload = get_u32(c + 8);
        const uint32_t records = get_u32(c + 12);
        const uint64_t first_tick = get_u64(c + 16);
        const uint64_t claimed = type == kChunkTicks ? records : 0;
        if (payload > kMaxPayloadBytes) {
            stop("chunk payload length " + std::to_string(payload) + " is implausible (corrupt header)", 0);
            break;
        }
        const uint64_t whole = kChunkHeaderBytes + payload + kCrcBytes;
        if (left < whole) {
            stop("chunk cut short (" + std::to_string(left) + " of " + std::to_string(whole) + " bytes)", claimed);
            break;
        }
        if (crc32(c, kChunkHeaderBytes + payload) != get_u32(c + kChunkHeaderBytes + payload)) {
            stop("chunk CRC mismatch", claimed);
            break;
        }
        const std::size_t ticks_before = out.ticks.size(), events_before = out.events.size(),
                          annexes_before = out.annexes.size();
        const std::string bad = decode_chunk(type, c + kChunkHeaderBytes, payload, records, first_tick, out);
        if (!bad.empty()) {
            out.ticks.resize(ticks_before);
            out.events.resize(events_before);
            out.annexes.resize(annexes_before);
            stop(bad, claimed);
            break;
        }
        off += whole;
    }
    return out;
}

std::string write_recording(const std::string& path, const RecordingRead& recording, SyncPolicy sync) {
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
    std::size_t max_event = 1;
    for (const RecordingEvent& e : recording.events) max_event = std::max(max_event, e.kind.size() + e.json.size());
    if (max_event > (1u << 20)) return path + ": an event is longer than 1 MiB";
    RecordingOptions options;
    options.sync = sync;
    options.max_event_bytes = static_cast<uint32_t>(max_event);
    options.event_ring = 64;  // a power of two: the ring holds exactly this many
    while (options.event_ring > 2 && options.event_ring * (kEventHeaderBytes + max_event) > kMaxPayloadBytes)
        options.event_ring /= 2;

    RecordingWriter w;
    auto fail = [&](const std::string& err) {
        (void)w.close();
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        return err;
    };
    if (std::string err = w.open(tmp, recording.metadata, options); !err.empty()) return fail(err);

    // Events go in file order, each before the first tick after its own, as the loop writes them.
    std::size_t next_event = 0;
    uint32_t pending_events = 0;
    auto put_event = [&]() -> std::string {
        if (pending_events == options.event_ring) {
            if (std::string err = w.flush(); !err.empty()) return err;
            pending_events = 0;
        }
        const RecordingEvent& e = recording.events[next_event++];
        if (!w.add_event(e.tick, e.kind, e.json)) return tmp + ": event refused by the writer";
        ++pending_events;
        return "";
    };
    for (const TickSample& t : recording.ticks) {
        while (next_event < recording.events.size() && recording.events[next_event].tick <= t.tick)
            if (std::string err = put_event(); !err.empty()) return fail(err);
        if (!w.add_tick(t)) return fail(tmp + ": tick refused by the writer");
        if (w.pending_ticks() >= kMaxTicksPerChunk) {
            if (std::string err = w.flush(); !err.empty()) return fail(err);
            pending_events = 0;
        }
    }
    while (next_event < recording.events.size())
        if (std::string err = put_event(); !err.empty()) return fail(err);
    if (std::string err = w.flush(); !err.empty()) return fail(err);
    for (const RecordingAnnex& a : recording.annexes)
        if (std::string err = w.queue_annex(a.tick, a.name, a.json); !err.empty()) return fail(err);
    if (std::string err = w.close(); !err.empty()) return fail(err);
    if (std::rename(tmp.c_str(), path.c_str()) != 0) return fail(path + ": cannot rename " + tmp + ": " + errno_text(errno));
    if (sync == SyncPolicy::DataSync) sync_parent_dir(path);
    return "";
}

}  // namespace sulcus
