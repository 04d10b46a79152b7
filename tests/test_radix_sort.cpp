// The step's allocation-free key sorts: the same order and the same distinct keys as std::sort and
// std::unique, whichever bytes of the keys vary, and (sort_unique) whatever earlier calls left in
// its table.
#include "radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

using namespace sulcus;

namespace {

DedupeTable& shared_table() {
    static DedupeTable table;
    return table;
}

void expect_sorted_like_std(std::vector<uint64_t> keys) {
    std::vector<uint64_t> scratch(keys.size()), work = keys;
    std::vector<uint64_t> expected = keys;
    std::sort(expected.begin(), expected.end());
    const uint64_t* sorted = radix_sort(work.data(), scratch.data(), int(work.size()));
    ASSERT_TRUE(std::equal(expected.begin(), expected.end(), sorted));

    work = keys;
    const int n = radix_sort_unique(work.data(), scratch.data(), int(work.size()));
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
    ASSERT_EQ(size_t(n), expected.size());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), work.begin()));

    work = keys;
    const int m = sort_unique(work.data(), scratch.data(), int(work.size()), shared_table());
    ASSERT_EQ(size_t(m), expected.size());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), work.begin()));
}

}  // namespace

TEST(RadixSort, MatchesStdSortAndUnique) {
    std::mt19937_64 rng(5);
    for (int trial = 0; trial < 200; ++trial) {
        // Half the trials up to past the dedupe table's half (which sort_unique radix-sorts
        // whole).
        const int count = int(rng() % uint64_t(trial % 2 ? 3000 : DedupeTable::kSlots / 2 + 2000));
        // Keys as the step packs them (object, feature, piece), full 64-bit ones, and few distinct
        // values (many repeats); an odd and an even number of varying bytes.
        const int shape = trial % 4;
        std::vector<uint64_t> keys(static_cast<size_t>(count));
        for (uint64_t& k : keys) {
            switch (shape) {
                case 0: k = (rng() % 3) << 40 | (rng() % 500000) << 8 | (rng() % 11); break;
                case 1: k = rng(); break;
                case 2: k = rng() % 17; break;
                default: k = (rng() % 300) << 16; break;
            }
        }
        expect_sorted_like_std(keys);
    }
}

TEST(RadixSort, EmptyOneAndAllEqual) {
    expect_sorted_like_std({});
    expect_sorted_like_std({42});
    expect_sorted_like_std(std::vector<uint64_t>(100, 7));
    expect_sorted_like_std({3, 1, 2, 3, 1});
}

TEST(RadixSort, DedupeTableSurvivesItsStampWrappingRound) {
    // Slots filled at stamp 1, then the stamp runs round to 1 again: the table must not take
    // the old slots for keys of the new call.
    std::mt19937_64 rng(9);
    std::vector<uint64_t> first(300), other(300);
    for (uint64_t& k : first) k = (rng() % 2) << 40 | (rng() % 300) << 8 | (rng() % 3);
    for (uint64_t& k : other) k = (rng() % 2) << 40 | (rng() % 300) << 8 | (rng() % 3);
    DedupeTable& table = shared_table();
    table.now = 0;
    expect_sorted_like_std(first);
    EXPECT_EQ(table.now, 1u);
    table.now = ~uint32_t(0) - 1;
    expect_sorted_like_std(other);
    EXPECT_EQ(table.now, ~uint32_t(0));
    expect_sorted_like_std(first);
    EXPECT_EQ(table.now, 1u);
}

TEST(RadixSort, DropRepeatsKeepsTheFirstOfEachKeyInOrder) {
    // The order gather's F-V and E-E loops take their features in: each distinct key once, where
    // it first came, whatever earlier calls left in the table.
    std::mt19937_64 rng(17);
    DedupeTable& table = shared_table();
    for (int round = 0; round < 50; ++round) {
        const int count = int(rng() % 700);
        std::vector<uint64_t> keys(size_t(count) + 1);
        for (uint64_t& k : keys) k = (rng() % 2) << 40 | (rng() % 200) << 8 | (rng() % 3);
        std::vector<uint64_t> expected;
        for (int i = 0; i < count; ++i)
            if (std::find(expected.begin(), expected.end(), keys[size_t(i)]) == expected.end())
                expected.push_back(keys[size_t(i)]);
        std::vector<uint64_t> scratch(keys.size());
        const int n = drop_repeats(keys.data(), scratch.data(), count, table);
        ASSERT_EQ(n, int(expected.size())) << "round " << round;
        EXPECT_TRUE(std::equal(expected.begin(), expected.end(), keys.begin())) << "round " << round;
    }
}
