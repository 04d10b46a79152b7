// Sorting the step's keys without allocating: least-significant-digit radix sort of 64-bit keys,
// a byte per pass, skipping the bytes every key shares (the high bytes of small indices).
#pragma once

#include <cstdint>
#include <cstring>
#include <utility>

namespace sulcus {

// Sorts keys[0, count) ascending; `scratch` holds at least `count` keys. Returns the sorted keys
// (either `keys` or `scratch`).
inline uint64_t* radix_sort(uint64_t* keys, uint64_t* scratch, int count) {
    if (count < 2) return keys;
    uint64_t all_or = 0, all_and = ~uint64_t(0);
    for (int i = 0; i < count; ++i) {
        all_or |= keys[i];
        all_and &= keys[i];
    }
    const uint64_t varies = all_or ^ all_and;  // bits that differ between some keys
    uint64_t* from = keys;
    uint64_t* to = scratch;
    for (int shift = 0; shift < 64; shift += 8) {
        if (((varies >> shift) & 0xffu) == 0) continue;
        int start[257] = {};
        for (int i = 0; i < count; ++i) ++start[((from[i] >> shift) & 0xffu) + 1];
        for (int b = 0; b < 256; ++b) start[b + 1] += start[b];
        for (int i = 0; i < count; ++i) to[start[(from[i] >> shift) & 0xffu]++] = from[i];
        std::swap(from, to);
    }
    return from;
}

// Sorts and drops repeats; the distinct keys end up in keys[0, result).
inline int radix_sort_unique(uint64_t* keys, uint64_t* scratch, int count) {
    const uint64_t* sorted = radix_sort(keys, scratch, count);
    int n = 0;
    for (int i = 0; i < count; ++i)
        if (n == 0 || sorted[i] != keys[n - 1]) keys[n++] = sorted[i];
    return n;
}

}  // namespace sulcus
