// Session recording: bit-exact round trip, truncation and corruption handling, crash survival,
// rejection of foreign files, and the servo-side hand-off (no allocation, no lost or torn ticks).
#include "sulcus/haptics/recording.h"

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <numbers>
#include <thread>

#include <csignal>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include "allocation_counter.h"

namespace sulcus {
namespace {

namespace fs = std::filesystem;

std::string temp_path(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("sulcus_recording_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return (dir / name).string();
}

// Removes this run's scratch folder when the tests end.
struct ScratchCleanup : ::testing::Environment {
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(fs::temp_directory_path() / ("sulcus_recording_test_" + std::to_string(::getpid())), ec);
    }
};
[[maybe_unused]] ::testing::Environment* const g_cleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

std::vector<uint8_t> read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<uint8_t>& b, std::size_t n) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(n));
}

// A tick whose doubles exercise the encoding: awkward fractions, signed zero, subnormals, extremes,
// infinities and a NaN with a payload.
TickSample awkward_tick(uint64_t i) {
    TickSample s;
    s.tick = i;
    s.time_s = static_cast<double>(i) / 1000.0;
    s.device_pose.position = Vec3(1.0 / 3.0 + i, -0.0, std::nextafter(0.0, 1.0) * (i + 1));
    s.device_pose.orientation = Quat(std::cos(0.1 * i), std::sin(0.1 * i) / std::sqrt(3.0), -1e-300, 1e-17);
    s.buttons = static_cast<uint32_t>(i * 2654435761u);
    s.force_N = Vec3(std::numeric_limits<double>::max(), -std::numeric_limits<double>::infinity(), 0.1 * i);
    s.torque_Nm = Vec3(std::bit_cast<double>(uint64_t{0x7ff8dead0000beefull} + i), std::numbers::pi * i, -1e-310);
    s.status = static_cast<StepStatus>(i % kStepStatusCount);
    s.dt_s = i % 7 == 0 ? std::nextafter(1e-3, 1.0) : 0.9e-3 + 1e-6 * static_cast<double>(i);
    s.device_fault = static_cast<uint32_t>(i % 5 == 0 ? 0x300 + i : 0);
    s.device_read = i % 3 != 1;
    s.connected = i % 4 != 2;
    s.deadline_missed = i % 6 == 5;
    s.safety_state = static_cast<uint8_t>(i % 6);
    s.step_us = i % 9 == 0 ? -1.0f : 0.25f * static_cast<float>(i);
    return s;
}

bool same_bits(const TickSample& a, const TickSample& b) {
    const double da[] = {a.time_s, a.device_pose.position.x, a.device_pose.position.y, a.device_pose.position.z,
                         a.device_pose.orientation.w, a.device_pose.orientation.x, a.device_pose.orientation.y,
                         a.device_pose.orientation.z, a.force_N.x, a.force_N.y, a.force_N.z, a.torque_Nm.x,
                         a.torque_Nm.y, a.torque_Nm.z};
    const double db[] = {b.time_s, b.device_pose.position.x, b.device_pose.position.y, b.device_pose.position.z,
                         b.device_pose.orientation.w, b.device_pose.orientation.x, b.device_pose.orientation.y,
                         b.device_pose.orientation.z, b.force_N.x, b.force_N.y, b.force_N.z, b.torque_Nm.x,
                         b.torque_Nm.y, b.torque_Nm.z};
    return a.tick == b.tick && a.buttons == b.buttons && a.status == b.status && std::memcmp(da, db, sizeof da) == 0 &&
           std::memcmp(&a.dt_s, &b.dt_s, sizeof(double)) == 0 && a.device_fault == b.device_fault &&
           a.device_read == b.device_read && a.connected == b.connected && a.deadline_missed == b.deadline_missed &&
           a.safety_state == b.safety_state && std::memcmp(&a.step_us, &b.step_us, sizeof(float)) == 0;
}

RecordingMetadata test_metadata() {
    RecordingMetadata m;
    m.case_path = "content/assets/cases/demo \"36\".json";
    m.device = "replay";
    m.rate_hz = 1000.0;
    m.start_time = "2026-01-02T03:04:05Z";
    return m;
}

RecordingOptions no_sync() {
    RecordingOptions o;
    o.sync = SyncPolicy::None;
    return o;
}

// Writes `n` awkward ticks, flushing every 100 like a servo-side caller would.
std::string write_ticks(const std::string& path, uint64_t n) {
    RecordingWriter w;
    std::string err = w.open(path, test_metadata(), no_sync());
    if (!err.empty()) return err;
    for (uint64_t i = 0; i < n; ++i) {
        w.add_tick(awkward_tick(i));
        if (w.pending_ticks() >= kMaxTicksPerChunk && !(err = w.flush()).empty()) return err;
    }
    return w.close();
}

TEST(Recording, Crc32MatchesTheStandardCheckValue) {
    EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
    EXPECT_EQ(crc32("", 0), 0u);
    // Running checksum equals the one-shot value.
    EXPECT_EQ(crc32("56789", 5, crc32("1234", 4)), 0xCBF43926u);
}

TEST(Recording, RoundTripIsBitExact) {
    const std::string path = temp_path("roundtrip.rec");
    RecordingWriter w;
    ASSERT_EQ(w.open(path, test_metadata(), no_sync()), "");
    for (uint64_t i = 0; i < 250; ++i) {
        ASSERT_TRUE(w.add_tick(awkward_tick(i)));
        if (i == 10) {
            ASSERT_TRUE(w.add_event(i, "site_charted", R"({"tooth":36,"site":"MB","pd_mm":5.0})"));
        }
        if (i == 120) {
            ASSERT_TRUE(w.add_event(i, "lesson_step", ""));
        }
        if (i == 121) {
            ASSERT_TRUE(w.add_event(i, "note", "{\"text\":\"ü\\n\"}"));
        }
        if (w.pending_ticks() >= 100) {
            ASSERT_EQ(w.flush(), "");
        }
    }
    ASSERT_EQ(w.close(), "");

    const RecordingRead r = read_recording(path);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_FALSE(r.truncation.truncated) << r.truncation.reason;
    EXPECT_EQ(r.version, 2);
    EXPECT_EQ(r.metadata.case_path, test_metadata().case_path);
    EXPECT_EQ(r.metadata.device, "replay");
    EXPECT_EQ(r.metadata.rate_hz, 1000.0);
    EXPECT_EQ(r.metadata.start_time, "2026-01-02T03:04:05Z");
    ASSERT_EQ(r.ticks.size(), 250u);
    for (uint64_t i = 0; i < 250; ++i) EXPECT_TRUE(same_bits(r.ticks[i], awkward_tick(i))) << "tick " << i;
    ASSERT_EQ(r.events.size(), 3u);
    EXPECT_EQ(r.events[0].tick, 10u);
    EXPECT_EQ(r.events[0].kind, "site_charted");
    EXPECT_EQ(r.events[0].json, R"({"tooth":36,"site":"MB","pd_mm":5.0})");
    EXPECT_EQ(r.events[1].kind, "lesson_step");
    EXPECT_EQ(r.events[1].json, "");
    EXPECT_EQ(r.events[2].json, "{\"text\":\"ü\\n\"}");

    // Size: header + per tick chunk 28 bytes of framing + 160 per tick.
    const auto size = fs::file_size(path);
    const RecordingStats st = w.stats();
    EXPECT_EQ(st.bytes_written, size);
    EXPECT_EQ(st.ticks_written, 250u);
    EXPECT_EQ(st.events_written, 3u);
    std::printf("[ measure ] 250 ticks + 3 events: %llu bytes, %.2f bytes/tick in full chunks\n",
                static_cast<unsigned long long>(size), (28.0 + 100.0 * kTickRecordBytes) / 100.0);
}

// A version-1 file (128-byte tick records, no clock or device flags), built byte by byte as the
// format document describes it, still reads: its ticks come back with the v1 defaults.
TEST(Recording, ReadsVersion1Files) {
    auto u16 = [](std::vector<uint8_t>& b, uint16_t v) {
        for (int i = 0; i < 2; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
    };
    auto u32 = [](std::vector<uint8_t>& b, uint32_t v) {
        for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
    };
    auto u64 = [](std::vector<uint8_t>& b, uint64_t v) {
        for (int i = 0; i < 8; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
    };
    auto f64 = [&](std::vector<uint8_t>& b, double v) { u64(b, std::bit_cast<uint64_t>(v)); };

    std::vector<uint8_t> file = {'S', 'U', 'L', 'C', 'S', 'R', 'E', 'C'};
    const std::string meta = R"({"format":"sulcus.recording/1","device":"old","rate_hz":500})";
    u16(file, 1);
    u16(file, 0);
    u32(file, static_cast<uint32_t>(meta.size()));
    file.insert(file.end(), meta.begin(), meta.end());
    u32(file, crc32(file.data(), file.size()));

    std::vector<uint8_t> chunk = {'C', 'H', 'N', 'K', 1, 0, 0, 0};
    u32(chunk, 2 * 128);
    u32(chunk, 2);
    u64(chunk, 7);
    for (uint64_t t = 7; t < 9; ++t) {
        u64(chunk, t);
        f64(chunk, 0.002 * static_cast<double>(t));
        for (double v : {0.01, 0.02, 0.03, 1.0, 0.0, 0.0, 0.0, 0.5, -0.25, 0.0, 0.0, 0.0, 0.001}) f64(chunk, v);
        u32(chunk, 3);
        chunk.push_back(1);  // contact
        chunk.insert(chunk.end(), 3, 0);
    }
    u32(chunk, crc32(chunk.data(), chunk.size()));
    file.insert(file.end(), chunk.begin(), chunk.end());

    const std::string path = temp_path("v1.rec");
    {
        std::ofstream out(path, std::ios::binary);
        out.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size()));
    }
    const RecordingRead r = read_recording(path);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.version, 1);
    EXPECT_FALSE(r.truncation.truncated) << r.truncation.reason;
    EXPECT_EQ(r.metadata.device, "old");
    EXPECT_EQ(r.metadata.rate_hz, 500.0);
    ASSERT_EQ(r.ticks.size(), 2u);
    EXPECT_EQ(r.ticks[1].tick, 8u);
    EXPECT_EQ(r.ticks[1].device_pose.position, Vec3(0.01, 0.02, 0.03));
    EXPECT_EQ(r.ticks[1].force_N, Vec3(0.5, -0.25, 0.0));
    EXPECT_EQ(r.ticks[1].torque_Nm, Vec3(0.0, 0.0, 0.001));
    EXPECT_EQ(r.ticks[1].buttons, 3u);
    EXPECT_EQ(r.ticks[1].status, StepStatus::Contact);
    EXPECT_EQ(r.ticks[1].dt_s, 0.0);  // not recorded: a replay uses 1 / rate
    EXPECT_TRUE(r.ticks[1].device_read);
    EXPECT_TRUE(r.ticks[1].connected);
    EXPECT_FALSE(r.ticks[1].deadline_missed);
    fs::remove(path);
}

TEST(Recording, CutAnywhereInTheLastChunkKeepsTheEarlierChunks) {
    const std::string path = temp_path("full.rec");
    ASSERT_EQ(write_ticks(path, 250), "");  // chunks of 100, 100, 50 ticks
    const std::vector<uint8_t> bytes = read_bytes(path);
    const std::size_t last_chunk = bytes.size() - (24 + 50 * kTickRecordBytes + 4);
    const std::string cut = temp_path("cut.rec");
    for (std::size_t n = last_chunk; n < bytes.size(); ++n) {
        write_bytes(cut, bytes, n);
        const RecordingRead r = read_recording(cut);
        ASSERT_TRUE(r.ok()) << "cut at " << n << ": " << r.error;
        ASSERT_EQ(r.ticks.size(), 200u) << "cut at " << n;
        EXPECT_TRUE(same_bits(r.ticks.back(), awkward_tick(199)));
        if (n == last_chunk) {
            EXPECT_FALSE(r.truncation.truncated);  // a cut on a chunk boundary is a clean end
            continue;
        }
        ASSERT_TRUE(r.truncation.truncated) << "cut at " << n;
        EXPECT_EQ(r.truncation.offset, last_chunk);
        EXPECT_EQ(r.truncation.bytes_dropped, n - last_chunk);
        EXPECT_EQ(r.truncation.ticks_dropped, n >= last_chunk + 24 ? 50u : 0u) << "cut at " << n;
        EXPECT_NE(r.truncation.reason.find("byte " + std::to_string(last_chunk)), std::string::npos)
            << r.truncation.reason;
    }
    // And the whole file reads all of it.
    EXPECT_EQ(read_recording(path).ticks.size(), 250u);
}

TEST(Recording, FlippedByteStopsTheReadAtThatChunk) {
    const std::string path = temp_path("flip_src.rec");
    ASSERT_EQ(write_ticks(path, 300), "");
    const std::vector<uint8_t> bytes = read_bytes(path);
    const std::size_t chunk_bytes = 24 + 100 * kTickRecordBytes + 4;
    const std::size_t first_chunk = bytes.size() - 3 * chunk_bytes;
    const std::size_t second_chunk = first_chunk + chunk_bytes;
    const std::string flipped = temp_path("flip.rec");
    // A byte of the payload, of the header's first-tick field, and of the CRC itself.
    for (const std::size_t at : {second_chunk + 24 + 777, second_chunk + 16, second_chunk + chunk_bytes - 1}) {
        std::vector<uint8_t> b = bytes;
        b[at] ^= 0x10;
        write_bytes(flipped, b, b.size());
        const RecordingRead r = read_recording(flipped);
        ASSERT_TRUE(r.ok()) << r.error;
        EXPECT_EQ(r.ticks.size(), 100u) << "flip at " << at;
        ASSERT_TRUE(r.truncation.truncated);
        EXPECT_EQ(r.truncation.offset, second_chunk);
        EXPECT_EQ(r.truncation.bytes_dropped, 2 * chunk_bytes);
        EXPECT_NE(r.truncation.reason.find(flipped + ": byte " + std::to_string(second_chunk) + ": "), std::string::npos)
            << r.truncation.reason;
        EXPECT_NE(r.truncation.reason.find("CRC"), std::string::npos) << r.truncation.reason;
    }
}

// The child records at 1 kHz and reports each tick's time down a pipe; it is killed without warning.
// What the file holds afterwards must reach to within 100 ms of the last tick the child reported.
void crash_test(bool writer_thread, SyncPolicy sync) {
    const std::string path = temp_path(writer_thread ? "crash_thread.rec" : "crash_inline.rec");
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        ::close(fds[0]);
        RecordingWriter w;
        RecordingOptions o;
        o.sync = sync;
        if (!w.open(path, test_metadata(), o).empty()) ::_exit(2);
        if (writer_thread && !w.start_writer_thread(0.02).empty()) ::_exit(3);
        for (uint64_t i = 0; i < 20000; ++i) {
            TickSample s = awkward_tick(i);
            s.time_s = static_cast<double>(i) * 1e-3;
            w.add_tick(s);
            if (!writer_thread && w.pending_ticks() >= kMaxTicksPerChunk && !w.flush().empty()) ::_exit(4);
            if (::write(fds[1], &s.time_s, sizeof s.time_s) != sizeof s.time_s) ::_exit(5);
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        ::_exit(6);  // not reached within the test's time: the parent kills first
    }
    ::close(fds[1]);
    // Killed once it has recorded a while, 0.2 s of ticks (some 300 ms after the fork; a slow
    // start, such as a first sync that the file system takes long over, only puts it off), or
    // after 30 s without.
    double last_reported = -1.0, t = 0.0;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (last_reported < 0.2 && std::chrono::steady_clock::now() < give_up) {
        pollfd ready{fds[0], POLLIN, 0};
        if (::poll(&ready, 1, 100) <= 0) continue;
        if (::read(fds[0], &t, sizeof t) != sizeof t) break;  // the child has gone: its status says why
        last_reported = t;
    }
    ASSERT_EQ(::kill(child, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "child exited early with status " << WEXITSTATUS(status);
    while (::read(fds[0], &t, sizeof t) == sizeof t) last_reported = t;
    ::close(fds[0]);
    ASSERT_GE(last_reported, 0.1) << "the child recorded too few ticks to test anything";

    const RecordingRead r = read_recording(path);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_FALSE(r.ticks.empty());
    for (std::size_t i = 0; i < r.ticks.size(); ++i) ASSERT_EQ(r.ticks[i].tick, i);
    const double lost_s = last_reported - r.ticks.back().time_s;
    std::printf("[ measure ] %s, %s: child reported t=%.3f s, file ends at t=%.3f s: %.0f ms lost%s\n",
                writer_thread ? "writer thread" : "flush every 100 ticks",
                sync == SyncPolicy::DataSync ? "fdatasync" : "no sync", last_reported, r.ticks.back().time_s,
                lost_s * 1e3, r.truncation.truncated ? " (partial chunk dropped)" : "");
    EXPECT_LE(lost_s, 0.1 + 1e-9);
}

TEST(Recording, KilledWriterLosesAtMost100msFlushingEvery100Ticks) { crash_test(false, SyncPolicy::DataSync); }

TEST(Recording, KilledWriterLosesAtMost100msWithWriterThread) { crash_test(true, SyncPolicy::DataSync); }

TEST(Recording, ForeignOrCorruptFilesGiveAOneLineErrorWithTheOffset) {
    const std::string good = temp_path("good.rec");
    ASSERT_EQ(write_ticks(good, 10), "");
    const std::vector<uint8_t> bytes = read_bytes(good);
    const std::string bad = temp_path("bad.rec");
    auto expect_error = [&](const std::vector<uint8_t>& b, std::size_t n, const std::string& offset,
                            const std::string& what) {
        write_bytes(bad, b, n);
        const RecordingRead r = read_recording(bad);
        ASSERT_FALSE(r.ok()) << what;
        EXPECT_EQ(r.error.rfind(bad + ": byte " + offset + ": ", 0), 0u) << r.error;
        EXPECT_NE(r.error.find(what), std::string::npos) << r.error;
        EXPECT_EQ(r.error.find('\n'), std::string::npos);
        EXPECT_TRUE(r.ticks.empty());
    };

    const std::string text = "t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n";
    expect_error(std::vector<uint8_t>(text.begin(), text.end()), text.size(), "0", "bad magic");
    expect_error(bytes, 0, "0", "bad magic");  // empty file
    expect_error(bytes, 5, "0", "bad magic");

    std::vector<uint8_t> b = bytes;
    b[3] = 'X';
    expect_error(b, b.size(), "0", "bad magic");

    // A future version is refused even with a consistent header CRC.
    b = bytes;
    b[8] = static_cast<uint8_t>(kRecordingVersion + 1);
    const uint32_t meta = b[12] | (b[13] << 8) | (b[14] << 16) | (static_cast<uint32_t>(b[15]) << 24);
    const uint32_t crc = crc32(b.data(), 16 + meta);
    for (int i = 0; i < 4; ++i) b[16 + meta + i] = static_cast<uint8_t>(crc >> (8 * i));
    expect_error(b, b.size(), "8", "newer than this reader");

    b = bytes;
    b[20] ^= 1;  // inside the metadata
    expect_error(b, b.size(), std::to_string(16 + meta), "header CRC mismatch");
    expect_error(bytes, 16 + meta + 2, "12", "runs past the end");  // header cut short

    const RecordingRead missing = read_recording(temp_path("does_not_exist.rec"));
    EXPECT_FALSE(missing.ok());
    EXPECT_NE(missing.error.find("does_not_exist.rec: byte 0: cannot open"), std::string::npos) << missing.error;
}

TEST(Recording, ProducerCallsDoNotAllocate) {
    const std::string path = temp_path("noalloc.rec");
    RecordingWriter w;
    ASSERT_EQ(w.open(path, test_metadata(), no_sync()), "");
    const TickSample s = awkward_tick(7);
    const std::string json(1000, 'x');
    const long before = sulcus::test::heap_allocations();
    for (int i = 0; i < 2000; ++i) w.add_tick(s);
    for (int i = 0; i < 50; ++i) w.add_event(7, "site_charted", json);
    const long after = sulcus::test::heap_allocations();
    EXPECT_EQ(after, before);
    // Flushing allocates nothing either once open (the chunk buffers are preallocated).
    const long before_flush = sulcus::test::heap_allocations();
    ASSERT_EQ(w.flush(), "");
    EXPECT_EQ(sulcus::test::heap_allocations(), before_flush);
    ASSERT_EQ(w.close(), "");
    EXPECT_EQ(read_recording(path).ticks.size(), 2000u);
}

TEST(Recording, FullRingDropsAndCountsWithoutBlocking) {
    const std::string path = temp_path("full_ring.rec");
    RecordingWriter w;
    RecordingOptions o = no_sync();
    o.tick_ring = 8;
    o.event_ring = 2;
    o.max_event_bytes = 16;
    ASSERT_EQ(w.open(path, test_metadata(), o), "");
    for (uint64_t i = 0; i < 8; ++i) EXPECT_TRUE(w.add_tick(awkward_tick(i)));
    EXPECT_FALSE(w.add_tick(awkward_tick(8)));
    EXPECT_FALSE(w.add_tick(awkward_tick(9)));
    EXPECT_FALSE(w.add_event(0, "too_long_a_kind", "{}"));  // 17 bytes > 16
    EXPECT_TRUE(w.add_event(0, "a", "{}"));
    EXPECT_TRUE(w.add_event(1, "b", "{}"));
    EXPECT_FALSE(w.add_event(2, "c", "{}"));
    ASSERT_EQ(w.flush(), "");
    EXPECT_TRUE(w.add_tick(awkward_tick(10)));  // room again after the flush
    ASSERT_EQ(w.close(), "");
    EXPECT_FALSE(w.add_tick(awkward_tick(11)));  // closed
    const RecordingStats st = w.stats();
    EXPECT_EQ(st.ticks_written, 9u);
    EXPECT_EQ(st.ticks_dropped, 3u);
    EXPECT_EQ(st.events_written, 2u);
    EXPECT_EQ(st.events_dropped, 2u);
    const RecordingRead r = read_recording(path);
    ASSERT_EQ(r.ticks.size(), 9u);
    EXPECT_EQ(r.ticks.back().tick, 10u);
}

// A producer thread against the writer thread: every tick in the file is whole
// (no torn slot), in order, and written + dropped accounts for every tick.
TEST(Recording, WriterThreadHandOffLosesOrTearsNothing) {
    const std::string path = temp_path("spsc.rec");
    RecordingWriter w;
    RecordingOptions o = no_sync();
    o.tick_ring = 256;
    ASSERT_EQ(w.open(path, test_metadata(), o), "");
    ASSERT_EQ(w.start_writer_thread(0.001), "");
    constexpr uint64_t kTicks = 200000;
    uint64_t accepted = 0;
    // Paced to keep the ring from filling, so that every tick crosses a live hand-off.
    std::thread producer([&] {
        for (uint64_t i = 0; i < kTicks; ++i) {
            while (w.pending_ticks() > 200) std::this_thread::yield();
            accepted += w.add_tick(awkward_tick(i)) ? 1 : 0;
        }
    });
    producer.join();
    ASSERT_EQ(w.close(), "");
    const RecordingStats st = w.stats();
    EXPECT_EQ(accepted, kTicks);
    EXPECT_GE(st.flushes, 100u);  // many hand-offs, not one drain at close
    EXPECT_EQ(st.ticks_written, accepted);
    EXPECT_EQ(st.ticks_written + st.ticks_dropped, kTicks);
    const RecordingRead r = read_recording(path);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(r.ticks.size(), accepted);
    for (std::size_t i = 0; i < r.ticks.size(); ++i) {
        ASSERT_TRUE(same_bits(r.ticks[i], awkward_tick(r.ticks[i].tick))) << "torn tick " << r.ticks[i].tick;
        if (i > 0) {
            ASSERT_GT(r.ticks[i].tick, r.ticks[i - 1].tick);
        }
    }
    std::printf("[ measure ] %llu ticks through a 256-tick ring in %llu flushes\n",
                static_cast<unsigned long long>(accepted), static_cast<unsigned long long>(st.flushes));
}

// Reports the cost of a flush of one 100-tick chunk, with and without fdatasync (never fails on
// a slow disk: timings are reported, not tested).
TEST(Recording, MeasureFlushCost) {
    for (const SyncPolicy sync : {SyncPolicy::None, SyncPolicy::DataSync}) {
        const std::string path = temp_path("flush_cost.rec");
        RecordingWriter w;
        RecordingOptions o;
        o.sync = sync;
        ASSERT_EQ(w.open(path, test_metadata(), o), "");
        double total_us = 0.0;
        int flushes = 0;
        for (uint64_t i = 0; i < 5000; ++i) {
            w.add_tick(awkward_tick(i));
            if (w.pending_ticks() >= 100) {
                ASSERT_EQ(w.flush(), "");
                total_us += w.stats().last_flush_us;
                ++flushes;
            }
        }
        ASSERT_EQ(w.close(), "");
        ASSERT_EQ(flushes, 50);
        std::printf("[ measure ] flush of 100 ticks (%zu bytes), %s: mean %.1f us, max %.1f us\n",
                    24 + 100 * kTickRecordBytes + 4, sync == SyncPolicy::DataSync ? "fdatasync" : "no sync",
                    total_us / flushes, w.stats().max_flush_us);
    }
}

// The chunks of a file as (type, first tick), in file order, walking the headers (no checks).
std::vector<std::pair<int, uint64_t>> chunk_list(const std::vector<uint8_t>& b) {
    auto u32 = [&](std::size_t at) {
        return static_cast<uint32_t>(b[at] | (b[at + 1] << 8) | (b[at + 2] << 16) | (static_cast<uint32_t>(b[at + 3]) << 24));
    };
    std::vector<std::pair<int, uint64_t>> out;
    std::size_t off = 16 + u32(12) + 4;
    while (off + 24 <= b.size()) {
        uint64_t first = 0;
        for (int i = 7; i >= 0; --i) first = (first << 8) | b[off + 16 + i];
        out.emplace_back(b[off + 4], first);
        off += 24 + u32(off + 8) + 4;
    }
    return out;
}

// Annexes: each is written by the next flush after every tick and event added before it, at the
// count of ticks added so far, and reads back as stored; the lesson metadata key round-trips.
TEST(Recording, AnnexesFollowWhatWasAddedBeforeThemAndReadBack) {
    const std::string path = temp_path("annex.rec");
    RecordingWriter w;
    RecordingMetadata meta = test_metadata();
    meta.lesson = "lessons/probing-basics.json";
    EXPECT_NE(w.add_annex("score", "{}"), "");  // not open
    ASSERT_EQ(w.open(path, meta, no_sync()), "");
    const std::string score = R"({"sites":[{"tooth":36,"site":"MB","pd_mm":5.0}],"grade":"ü"})";
    for (uint64_t i = 0; i < 250; ++i) {
        ASSERT_TRUE(w.add_tick(awkward_tick(i)));
        if (i == 115) {
            ASSERT_TRUE(w.add_event(i, "chart.depth", R"({"mm":3})"));
        }
        if (i == 119) {
            ASSERT_EQ(w.add_annex("score", score), "");  // 20 ticks and an event still pending
        }
        if (i == 129) {
            ASSERT_EQ(w.flush(), "");
        }
        if (i == 199) {
            ASSERT_EQ(w.flush(), "");
        }
    }
    ASSERT_EQ(w.add_annex("notes/über", ""), "");  // written by close(), after the last 50 ticks
    ASSERT_NE(w.add_annex("big", std::string(kMaxAnnexBytes, 'x')), "");
    ASSERT_EQ(w.close(), "");
    const std::string closed = w.add_annex("late", "{}");
    EXPECT_NE(closed, "");
    EXPECT_EQ(closed.find('\n'), std::string::npos);
    EXPECT_EQ(w.stats().annexes_written, 2u);

    const RecordingRead r = read_recording(path);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_FALSE(r.truncation.truncated) << r.truncation.reason;
    EXPECT_EQ(r.metadata.lesson, "lessons/probing-basics.json");
    ASSERT_EQ(r.ticks.size(), 250u);
    ASSERT_EQ(r.events.size(), 1u);
    ASSERT_EQ(r.annexes.size(), 2u);
    EXPECT_EQ(r.annexes[0].tick, 120u);
    EXPECT_EQ(r.annexes[0].name, "score");
    EXPECT_EQ(r.annexes[0].json, score);
    EXPECT_EQ(r.annexes[1].tick, 250u);
    EXPECT_EQ(r.annexes[1].name, "notes/über");
    EXPECT_EQ(r.annexes[1].json, "");

    // In the file: ticks 0..99, then (flush at 129) ticks 100..129, the event, the annex; then the
    // rest, the second annex last.
    const std::vector<std::pair<int, uint64_t>> chunks = chunk_list(read_bytes(path));
    const std::vector<std::pair<int, uint64_t>> expected = {{1, 0}, {1, 100}, {2, 115}, {3, 120},
                                                            {1, 130}, {1, 200}, {3, 250}};
    EXPECT_EQ(chunks, expected);

    // Without a lesson, no "lesson" key.
    const std::string plain = temp_path("plain.rec");
    ASSERT_EQ(write_ticks(plain, 3), "");
    const RecordingRead p = read_recording(plain);
    EXPECT_EQ(p.metadata.lesson, "");
    EXPECT_EQ(p.metadata_json.find("lesson"), std::string::npos) << p.metadata_json;
    EXPECT_TRUE(p.annexes.empty());
}

// An annex chunk whose lengths run past its payload (with a good CRC) ends the read there, as any
// malformed chunk does; an annex chunk from a writer that knows nothing of annexes would have been
// skipped, but this reader knows the type and checks it.
TEST(Recording, MalformedAnnexChunkIsATruncation) {
    const std::string path = temp_path("annex_bad_src.rec");
    ASSERT_EQ(write_ticks(path, 100), "");
    const std::vector<uint8_t> good = read_bytes(path);
    auto chunk = [](uint8_t type, const std::vector<uint8_t>& payload, uint32_t records, uint64_t first) {
        std::vector<uint8_t> c = {'C', 'H', 'N', 'K', type, 0, 0, 0};
        for (int i = 0; i < 4; ++i) c.push_back(static_cast<uint8_t>(payload.size() >> (8 * i)));
        for (int i = 0; i < 4; ++i) c.push_back(static_cast<uint8_t>(records >> (8 * i)));
        for (int i = 0; i < 8; ++i) c.push_back(static_cast<uint8_t>(first >> (8 * i)));
        c.insert(c.end(), payload.begin(), payload.end());
        const uint32_t crc = crc32(c.data(), c.size());
        for (int i = 0; i < 4; ++i) c.push_back(static_cast<uint8_t>(crc >> (8 * i)));
        return c;
    };
    // name length 200 in a 12-byte payload; a name that fits but a text length past the end; a
    // well-formed annex (control).
    const std::vector<uint8_t> past_name = {200, 0, 0, 0, 'a', 'b', 'c', 'd', 0, 0, 0, 0};
    const std::vector<uint8_t> past_text = {1, 0, 0, 0, 'a', 9, 0, 0, 0, '{', '}'};
    const std::vector<uint8_t> fine = {1, 0, 0, 0, 'a', 2, 0, 0, 0, '{', '}'};
    const std::string bad = temp_path("annex_bad.rec");
    const std::vector<std::vector<uint8_t>> payloads = {past_name, past_text, fine};
    for (std::size_t k = 0; k < payloads.size(); ++k) {
        const std::vector<uint8_t>& payload = payloads[k];
        std::vector<uint8_t> b = good;
        const std::vector<uint8_t> c = chunk(3, payload, 1, 100);
        b.insert(b.end(), c.begin(), c.end());
        const std::vector<uint8_t> after = chunk(9, {1, 2, 3}, 1, 100);  // an unknown type: skipped
        b.insert(b.end(), after.begin(), after.end());
        write_bytes(bad, b, b.size());
        const RecordingRead r = read_recording(bad);
        ASSERT_TRUE(r.ok()) << r.error;
        EXPECT_EQ(r.ticks.size(), 100u);
        if (k == 2) {  // well formed
            EXPECT_FALSE(r.truncation.truncated) << r.truncation.reason;
            ASSERT_EQ(r.annexes.size(), 1u);
            EXPECT_EQ(r.annexes[0].name, "a");
            EXPECT_EQ(r.annexes[0].json, "{}");
            EXPECT_EQ(r.annexes[0].tick, 100u);
            continue;
        }
        EXPECT_TRUE(r.annexes.empty()) << "payload " << k;
        ASSERT_TRUE(r.truncation.truncated) << "payload " << k;
        EXPECT_EQ(r.truncation.offset, good.size());
        EXPECT_EQ(r.truncation.bytes_dropped, b.size() - good.size());
        EXPECT_NE(r.truncation.reason.find("annex"), std::string::npos) << r.truncation.reason;
    }
}

// read -> write_recording -> read gives the same metadata, ticks (bit for bit), events and
// annexes; rewriting in place with an edited annex replaces the file whole.
TEST(Recording, WriteRecordingRewritesTheSameSession) {
    const std::string src = temp_path("rewrite_src.rec");
    {
        RecordingWriter w;
        RecordingMetadata meta = test_metadata();
        meta.lesson = "lessons/one.json";
        meta.rate_hz = 500.0;
        ASSERT_EQ(w.open(src, meta, no_sync()), "");
        for (uint64_t i = 0; i < 333; ++i) {
            ASSERT_TRUE(w.add_tick(awkward_tick(i)));
            if (i % 37 == 0) {
                ASSERT_TRUE(w.add_event(i, i % 2 ? "servo.reset" : "chart.depth", "{\"i\":" + std::to_string(i) + "}"));
            }
            if (i == 150) {
                ASSERT_EQ(w.add_annex("score", R"({"n":1})"), "");
            }
            if (w.pending_ticks() >= 100) {
                ASSERT_EQ(w.flush(), "");
            }
        }
        ASSERT_TRUE(w.add_event(400, "after", ""));  // past the last tick
        ASSERT_EQ(w.add_annex("final", R"({"n":2})"), "");
        ASSERT_EQ(w.close(), "");
    }
    const RecordingRead a = read_recording(src);
    ASSERT_TRUE(a.ok()) << a.error;
    ASSERT_EQ(a.ticks.size(), 333u);
    ASSERT_EQ(a.events.size(), 10u);
    ASSERT_EQ(a.annexes.size(), 2u);

    const std::string copy = temp_path("rewrite_copy.rec");
    ASSERT_EQ(write_recording(copy, a), "");
    const RecordingRead b = read_recording(copy);
    ASSERT_TRUE(b.ok()) << b.error;
    EXPECT_FALSE(b.truncation.truncated) << b.truncation.reason;
    EXPECT_EQ(b.metadata.case_path, a.metadata.case_path);
    EXPECT_EQ(b.metadata.lesson, "lessons/one.json");
    EXPECT_EQ(b.metadata.device, a.metadata.device);
    EXPECT_EQ(b.metadata.rate_hz, 500.0);
    EXPECT_EQ(b.metadata.start_time, "2026-01-02T03:04:05Z");
    ASSERT_EQ(b.ticks.size(), a.ticks.size());
    for (std::size_t i = 0; i < a.ticks.size(); ++i) ASSERT_TRUE(same_bits(b.ticks[i], a.ticks[i])) << "tick " << i;
    ASSERT_EQ(b.events.size(), a.events.size());
    for (std::size_t i = 0; i < a.events.size(); ++i) {
        EXPECT_EQ(b.events[i].tick, a.events[i].tick);
        EXPECT_EQ(b.events[i].kind, a.events[i].kind);
        EXPECT_EQ(b.events[i].json, a.events[i].json);
    }
    ASSERT_EQ(b.annexes.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(b.annexes[i].tick, a.annexes[i].tick);
        EXPECT_EQ(b.annexes[i].name, a.annexes[i].name);
        EXPECT_EQ(b.annexes[i].json, a.annexes[i].json);
    }
    EXPECT_EQ(b.annexes[0].tick, 151u);
    // Annexes last in the file.
    const auto chunks = chunk_list(read_bytes(copy));
    ASSERT_GE(chunks.size(), 2u);
    EXPECT_EQ(chunks[chunks.size() - 1].first, 3);
    EXPECT_EQ(chunks[chunks.size() - 2].first, 3);
    for (std::size_t i = 0; i + 2 < chunks.size(); ++i) EXPECT_NE(chunks[i].first, 3) << "chunk " << i;

    // Edit a stored annex in place.
    RecordingRead edited = b;
    edited.annexes[0].json = R"({"n":1,"reviewed":true})";
    ASSERT_EQ(write_recording(copy, edited, SyncPolicy::DataSync), "");
    const RecordingRead c = read_recording(copy);
    ASSERT_TRUE(c.ok()) << c.error;
    ASSERT_EQ(c.annexes.size(), 2u);
    EXPECT_EQ(c.annexes[0].json, R"({"n":1,"reviewed":true})");
    EXPECT_EQ(c.ticks.size(), 333u);
    // No temporary file is left beside it.
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(fs::path(copy).parent_path()))
        if (entry.path().filename().string().rfind("rewrite_copy.rec", 0) == 0) ++files;
    EXPECT_EQ(files, 1u);
    // A folder that does not exist: an error naming the file, nothing renamed.
    const std::string nowhere = temp_path("no_such_dir/x.rec");
    const std::string err = write_recording(nowhere, a);
    EXPECT_NE(err, "");
    EXPECT_NE(err.find("x.rec"), std::string::npos) << err;
}

}  // namespace
}  // namespace sulcus
