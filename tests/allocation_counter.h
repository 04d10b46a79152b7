// Counts the heap allocations of a test executable by replacing the global operator new, so a
// test can show that a call allocates nothing. Include it in exactly one source file of the
// executable (every tests/test_*.cpp is an executable of its own).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace sulcus::test {
inline std::atomic<long> g_heap_allocations{0};
// Allocations so far in this process (every thread).
inline long heap_allocations() noexcept { return g_heap_allocations.load(std::memory_order_relaxed); }
}  // namespace sulcus::test

// GCC pairs an inlined replacement new with the free() in the replacement delete and warns about a
// mismatch that is not one: both sides use malloc/free.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
    sulcus::test::g_heap_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    sulcus::test::g_heap_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop
