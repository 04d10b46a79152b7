// Sorting the step's keys without allocating: least-significant-digit radix sort of 64-bit keys,
// a byte per pass, skipping the bytes every key shares (the high bytes of small indices).
#pragma once

#include <algorithm>
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

// The slot of `key` in a table of 2^bits slots (Fibonacci hashing: the top bits of the key times
// the golden ratio's 64-bit fraction).
inline uint32_t hash_slot(uint64_t key, int bits) { return uint32_t((key * 0x9E3779B97F4A7C15ull) >> (64 - bits)); }

// Slots of an open-addressing table that drops repeats before a sort. Each slot carries the
// stamp of the call that filled it, so a call never clears the table; a call uses only the
// first 2^k slots, k just enough for half of them to stay empty, so that a few hundred keys touch
// a few kilobytes. 16,384 slots: the vertices of the 2,300 gingiva triangles round a probe deep
// in an inflamed floor (some 7,000 keys, a third of them distinct) still go through the table.
struct DedupeTable {
    static constexpr int kBits = 14;
    static constexpr int kSlots = 1 << kBits;
    uint64_t key[kSlots];
    uint32_t stamp[kSlots] = {};
    uint32_t now = 0;
};

// Drops repeats by the table, keeping the first of each key in place and in order; returns the
// distinct keys' count. Inputs too large for the table are sorted as radix_sort_unique does
// (distinct, but in key order).
inline int drop_repeats(uint64_t* keys, uint64_t* scratch, int count, DedupeTable& table) {
    if (count > DedupeTable::kSlots / 2) return radix_sort_unique(keys, scratch, count);
    if (count < 2) return count;
    if (++table.now == 0) {
        std::fill(table.stamp, table.stamp + DedupeTable::kSlots, 0u);
        table.now = 1;
    }
    int bits = 4;
    while ((1 << bits) < 2 * count) ++bits;
    const uint32_t mask = (1u << bits) - 1u;
    int n = 0;
    for (int i = 0; i < count; ++i) {
        const uint64_t k = keys[i];
        uint32_t h = hash_slot(k, bits);
        bool seen = false;
        while (table.stamp[h] == table.now) {
            if (table.key[h] == k) {
                seen = true;
                break;
            }
            h = (h + 1u) & mask;
        }
        if (seen) continue;
        table.stamp[h] = table.now;
        table.key[h] = k;
        keys[n++] = k;
    }
    return n;
}

// Sorts and drops repeats, as radix_sort_unique does, for inputs that repeat most keys (the
// features of neighbouring triangles): the repeats go first, by the table, then the distinct
// keys are sorted. Inputs too large for the table are radix-sorted whole.
inline int sort_unique(uint64_t* keys, uint64_t* scratch, int count, DedupeTable& table) {
    if (count > DedupeTable::kSlots / 2) return radix_sort_unique(keys, scratch, count);
    const int n = drop_repeats(keys, scratch, count, table);
    if (n < 2) return n;
    if (n > 256) {
        const uint64_t* sorted = radix_sort(keys, scratch, n);
        if (sorted != keys) std::memcpy(keys, sorted, sizeof(uint64_t) * size_t(n));
    } else {
        std::sort(keys, keys + n);
    }
    return n;
}

}  // namespace sulcus
