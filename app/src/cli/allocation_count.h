// Heap allocations of the sulcus-cli process, counted by its replacement of the global operator
// new (allocation_count.cpp): how `bench` shows that a step allocates nothing.
#pragma once

namespace sulcus::cli {

// Allocations so far on the calling thread.
long thread_heap_allocations() noexcept;

}  // namespace sulcus::cli
