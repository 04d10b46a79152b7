// A bounded single-producer / single-consumer queue of trivially copyable values: the hand-off
// from the UI or lesson thread to the servo thread. Fixed capacity chosen at construction (the
// only allocation); push() and pop() never block, allocate or throw. push() on a full queue fails
// and the producer decides what to do; the consumer is never held up.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>

namespace sulcus {

template <class T>
class SpscQueue {
    static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds trivially copyable values");

public:
    // Capacity is rounded up to a power of two (at least 2).
    explicit SpscQueue(std::size_t capacity) {
        std::size_t c = 2;
        while (c < capacity) c <<= 1;
        slots_ = std::make_unique<T[]>(c);
        mask_ = c - 1;
    }
    SpscQueue(const SpscQueue&) = delete;
    SpscQueue& operator=(const SpscQueue&) = delete;

    std::size_t capacity() const noexcept { return mask_ + 1; }

    // Producer thread only. False when full.
    bool push(const T& value) noexcept {
        const uint64_t head = head_.load(std::memory_order_relaxed);
        if (head - tail_cache_ > mask_) {
            tail_cache_ = tail_.load(std::memory_order_acquire);
            if (head - tail_cache_ > mask_) return false;
        }
        slots_[head & mask_] = value;
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    // Consumer thread only. False when empty.
    bool pop(T& out) noexcept {
        const uint64_t tail = tail_.load(std::memory_order_relaxed);
        if (tail == head_cache_) {
            head_cache_ = head_.load(std::memory_order_acquire);
            if (tail == head_cache_) return false;
        }
        out = slots_[tail & mask_];
        tail_.store(tail + 1, std::memory_order_release);
        return true;
    }

    // Either thread; a snapshot that may be stale by the time it is used.
    std::size_t size() const noexcept {
        return static_cast<std::size_t>(head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire));
    }

private:
    std::unique_ptr<T[]> slots_;
    std::size_t mask_ = 0;
    // Producer's line: its index and its last view of the consumer's.
    alignas(64) std::atomic<uint64_t> head_{0};
    uint64_t tail_cache_ = 0;
    // Consumer's line.
    alignas(64) std::atomic<uint64_t> tail_{0};
    uint64_t head_cache_ = 0;
};

}  // namespace sulcus
