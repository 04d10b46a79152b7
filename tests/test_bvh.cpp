// The BVH reports exactly the triangles whose own box overlaps the query box (checked against
// brute force), and its structure keeps the promises the query relies on.
#include "sulcus/engine/bvh.h"

#include "geometry.h"
#include "lanes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

namespace sulcus {
namespace {

Aabb triangle_box(const TriMesh& m, uint32_t t) {
    Aabb b;
    for (uint32_t v : m.triangles[t]) b.grow(m.vertices[v]);
    return b;
}

// A soup of n random triangles in the unit cube; sizes vary over three orders of magnitude.
// flat_axis >= 0 puts every vertex on the plane of that axis = 0.5 (flat boxes).
TriMesh random_soup(size_t n, std::mt19937_64& rng, int flat_axis = -1) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    TriMesh m;
    for (size_t t = 0; t < n; ++t) {
        const Vec3 c(u(rng), u(rng), u(rng));
        const double size = std::pow(10.0, -3.0 * u(rng));
        for (int k = 0; k < 3; ++k) {
            Vec3 p = c + size * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
            if (flat_axis >= 0) p[flat_axis] = 0.5;
            m.vertices.push_back(p);
        }
        const uint32_t b = uint32_t(3 * t);
        m.triangles.push_back({b, b + 1, b + 2});
    }
    return m;
}

Aabb random_query(std::mt19937_64& rng, int flat_axis = -1) {
    std::uniform_real_distribution<double> u(-0.1, 1.1);
    std::uniform_real_distribution<double> ext(0.0, 0.3);
    Aabb q;
    q.lo = Vec3(u(rng), u(rng), u(rng));
    q.hi = q.lo + Vec3(ext(rng), ext(rng), ext(rng));
    if (flat_axis >= 0) q.lo[flat_axis] = q.hi[flat_axis] = 0.5;
    return q;
}

std::set<uint32_t> brute_force(const TriMesh& m, const Aabb& q) {
    std::set<uint32_t> out;
    for (uint32_t t = 0; t < m.triangles.size(); ++t)
        if (triangle_box(m, t).overlaps(q)) out.insert(t);
    return out;
}

std::multiset<uint32_t> bvh_query(const Bvh& bvh, const Aabb& q) {
    std::multiset<uint32_t> out;
    EXPECT_TRUE(bvh.query(q, [&](uint32_t t) {
        out.insert(t);
        return true;
    }));
    return out;
}

void expect_same(const std::multiset<uint32_t>& got, const std::set<uint32_t>& want) {
    // The same set, and no triangle reported twice.
    EXPECT_EQ(std::set<uint32_t>(got.begin(), got.end()), want);
    EXPECT_EQ(got.size(), want.size());
}

// Structural invariants: boxes nest, leaves hold 1..max_leaf triangles, order() is a
// permutation, every triangle sits in a leaf whose box contains it, depth is bounded.
void check_structure(const Bvh& bvh, const TriMesh& m, int max_leaf) {
    const auto& nodes = bvh.nodes();
    const size_t n = m.triangles.size();
    if (n == 0) {
        EXPECT_TRUE(nodes.empty());
        EXPECT_EQ(bvh.depth(), 0);
        return;
    }
    std::vector<uint32_t> sorted = bvh.order();
    std::sort(sorted.begin(), sorted.end());
    ASSERT_EQ(sorted.size(), n);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(sorted[i], i);

    std::vector<int> seen(n, 0);
    int max_level = 0;
    struct Item {
        uint32_t node;
        int level;
    };
    std::vector<Item> stack{{0, 1}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        ASSERT_LT(it.node, nodes.size());
        const Bvh::Node& nd = nodes[it.node];
        max_level = std::max(max_level, it.level);
        if (nd.count > 0) {
            ASSERT_LE(nd.count, uint32_t(max_leaf));
            for (uint32_t i = 0; i < nd.count; ++i) {
                const uint32_t t = bvh.order()[nd.first + i];
                ++seen[t];
                const Aabb b = triangle_box(m, t);
                EXPECT_TRUE(glm::all(glm::lessThanEqual(nd.box.lo, b.lo)) &&
                            glm::all(glm::lessThanEqual(b.hi, nd.box.hi)));
            }
        } else {
            for (uint32_t c : {nd.first, nd.first + 1}) {
                ASSERT_LT(c, nodes.size());
                const Aabb& cb = nodes[c].box;
                EXPECT_TRUE(glm::all(glm::lessThanEqual(nd.box.lo, cb.lo)) &&
                            glm::all(glm::lessThanEqual(cb.hi, nd.box.hi)));
                stack.push_back({c, it.level + 1});
            }
        }
    }
    for (size_t t = 0; t < n; ++t) EXPECT_EQ(seen[t], 1) << "triangle " << t;
    EXPECT_EQ(max_level, bvh.depth());
    EXPECT_LE(bvh.depth(), kBvhMaxDepth);
    // Median split: depth is 1 + ceil(log2(n / max_leaf)) at most (plus one for rounding).
    const double leaves = std::ceil(double(n) / max_leaf);
    EXPECT_LE(bvh.depth(), 2 + int(std::ceil(std::log2(std::max(1.0, leaves)))));
}

TEST(Bvh, RandomSoupsMatchBruteForce) {
    std::mt19937_64 rng(12345);
    for (size_t n : {1u, 2u, 5u, 17u, 100u, 1000u, 5000u}) {
        for (int leaf : {1, 2, 4, 8}) {
            const TriMesh m = random_soup(n, rng);
            const Bvh bvh(m, leaf);
            check_structure(bvh, m, leaf);
            for (int q = 0; q < 200; ++q) {
                const Aabb box = random_query(rng);
                expect_same(bvh_query(bvh, box), brute_force(m, box));
            }
        }
    }
}

// A query's slots come in increasing order with their triangles' boxes, and the query of any box
// inside it is exactly its slots filtered by those boxes, in the same order: what the renderer's
// sets of compliant triangles kept between ticks stand on.
TEST(Bvh, QueryOfAnInnerBoxIsTheOuterQuerysSlotsFiltered) {
    std::mt19937_64 rng(2026);
    std::uniform_real_distribution<double> shrink(0.0, 0.5);
    int compared = 0, differing = 0;
    for (size_t n : {1u, 17u, 1000u, 5000u}) {
        for (int leaf : {1, 4, 6}) {
            const TriMesh m = random_soup(n, rng);
            const Bvh bvh(m, leaf);
            for (int q = 0; q < 100; ++q) {
                const Aabb outer = random_query(rng);
                std::vector<uint32_t> slots;
                ASSERT_TRUE(bvh.query_slots(outer, [&](uint32_t slot) {
                    slots.push_back(slot);
                    return true;
                }));
                for (size_t i = 0; i < slots.size(); ++i) {
                    ASSERT_LT(slots[i], bvh.order().size());
                    if (i > 0) {
                        ASSERT_LT(slots[i - 1], slots[i]);
                    }
                    const Aabb& box = bvh.slot_box(slots[i]);
                    const Aabb want = triangle_box(m, bvh.order()[slots[i]]);
                    ASSERT_EQ(box.lo, want.lo);
                    ASSERT_EQ(box.hi, want.hi);
                }
                // Boxes inside the outer one, some sharing a face with it.
                for (int k = 0; k < 5; ++k) {
                    Aabb inner = outer;
                    const Vec3 e = outer.hi - outer.lo;
                    for (int a = 0; a < 3; ++a) {
                        if (k != 0) inner.lo[a] += shrink(rng) * e[a];
                        if (k != 1) inner.hi[a] -= shrink(rng) * e[a];
                    }
                    std::vector<uint32_t> direct, filtered;
                    bvh.query(inner, [&](uint32_t t) {
                        direct.push_back(t);
                        return true;
                    });
                    for (uint32_t slot : slots)
                        if (bvh.slot_box(slot).overlaps(inner)) filtered.push_back(bvh.order()[slot]);
                    ASSERT_EQ(direct, filtered) << "n " << n << " leaf " << leaf << " query " << q;
                    ++compared;
                    differing += direct.size() != slots.size();
                }
            }
        }
    }
    // Many inner queries found fewer triangles than the outer one: the filter had work to do.
    EXPECT_GT(differing, compared / 4);
}

// A random chain of 1 to max_count capsules in the unit cube: links of up to `step` per axis,
// radii up to 0.05, and an extra reach up to `extra_max`.
struct CapsuleChain {
    int count = 0;
    std::vector<Vec3> points;
    std::vector<double> radii;
    double extra = 0.0;
};

CapsuleChain random_chain(std::mt19937_64& rng, int max_count, double step, double extra_max) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    CapsuleChain c;
    c.count = 1 + int(rng() % unsigned(max_count));
    c.points.push_back(Vec3(u(rng), u(rng), u(rng)));
    for (int k = 0; k < c.count; ++k) {
        c.points.push_back(c.points.back() + step * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5));
        c.radii.push_back(0.05 * u(rng));
    }
    c.extra = extra_max * u(rng);
    return c;
}

TEST(Bvh, CapsuleChainsVisitEveryTriangleWithinReachOnce) {
    // Every triangle within radius + extra of some capsule of the chain is visited, and none
    // twice, against the exact segment-triangle distance.
    std::mt19937_64 rng(777);
    int near = 0, skipped = 0;
    for (size_t n : {1u, 50u, 3000u}) {
        const TriMesh m = random_soup(n, rng);
        const Bvh bvh(m, 4);
        for (int q = 0; q < 60; ++q) {
            const CapsuleChain chain = random_chain(rng, 6, 0.15, 0.02);
            std::vector<int> seen(n, 0);
            EXPECT_TRUE(bvh.query_capsule_chain(chain.points.data(), chain.radii.data(), chain.count, chain.extra,
                                                [&](uint32_t t) {
                ++seen[t];
                return true;
            }));
            for (uint32_t t = 0; t < n; ++t) {
                EXPECT_LE(seen[t], 1) << "triangle " << t;
                const auto& tr = m.triangles[t];
                double d = 1e300;
                for (int k = 0; k < chain.count; ++k)
                    d = std::min(d, segment_triangle_distance(chain.points[size_t(k)], chain.points[size_t(k) + 1],
                                                              m.vertices[tr[0]], m.vertices[tr[1]], m.vertices[tr[2]]) -
                                        chain.radii[size_t(k)] - chain.extra);
                if (d <= 0.0) {
                    ++near;
                    EXPECT_EQ(seen[t], 1) << "triangle " << t << " within reach";
                } else if (seen[t] == 0) {
                    ++skipped;
                }
            }
        }
    }
    EXPECT_GT(near, 100);
    EXPECT_GT(skipped, 10000);  // it does pass over what is out of reach
}

TEST(Bvh, CapsuleChainWalkInSlicesVisitsWhatTheWholeQueryVisits) {
    // The same triangles in the same order, whatever the budget per slice; each slice stops
    // within its budget (and a triangle's visit past it).
    std::mt19937_64 rng(4242);
    const TriMesh m = random_soup(3000, rng);
    const Bvh bvh(m, 4);
    int slices_total = 0;
    for (int q = 0; q < 40; ++q) {
        const CapsuleChain chain = random_chain(rng, 5, 0.2, 0.03);
        std::vector<uint32_t> whole, sliced;
        bvh.query_capsule_chain(chain.points.data(), chain.radii.data(), chain.count, chain.extra, [&](uint32_t t) {
            whole.push_back(t);
            return true;
        });
        for (long slice : {1L, 7L, 100L}) {
            sliced.clear();
            CapsuleChainWalk walk;
            walk.start(chain.points.data(), chain.radii.data(), chain.count, chain.extra);
            bool done = false;
            int slices = 0;
            while (!done && slices < 1000000) {
                long budget = slice;
                done = bvh.walk_capsule_chain(walk, budget, [&](uint32_t t) {
                    sliced.push_back(t);
                    return true;
                });
                EXPECT_GE(budget, -long(4)) << "a slice ran past its budget by more than a leaf";
                ++slices;
            }
            EXPECT_TRUE(done);
            EXPECT_EQ(sliced, whole) << "slice " << slice;
            slices_total += slices;
        }
    }
    EXPECT_GT(slices_total, 40 * 3 * 2);  // the walks did stop and go on
}

TEST(Bvh, QueriesThatTouchOnlyAFaceOrCornerCount) {
    // Boxes that meet in a single plane or point overlap (closed boxes), as in Aabb::overlaps.
    TriMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 2, 2}, {3, 2, 2}, {2, 3, 3}};
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    const Bvh bvh(m, 1);
    Aabb q;
    q.lo = Vec3(1, 1, 0);
    q.hi = Vec3(2, 2, 2);
    expect_same(bvh_query(bvh, q), {0, 1});
    q.lo = Vec3(1.0 + 1e-12, 1, 0);
    expect_same(bvh_query(bvh, q), {1});
}

TEST(Bvh, EmptyMesh) {
    const TriMesh m;
    const Bvh bvh(m);
    check_structure(bvh, m, 4);
    Aabb q;
    q.lo = Vec3(-1e9);
    q.hi = Vec3(1e9);
    EXPECT_TRUE(bvh_query(bvh, q).empty());
    const Bvh default_constructed;
    EXPECT_TRUE(default_constructed.nodes().empty());
    EXPECT_TRUE(bvh_query(default_constructed, q).empty());
}

TEST(Bvh, SingleTriangle) {
    TriMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    const Bvh bvh(m);
    check_structure(bvh, m, 4);
    ASSERT_EQ(bvh.nodes().size(), 1u);
    EXPECT_EQ(bvh.depth(), 1);
    Aabb hit;
    hit.lo = Vec3(0.5, 0.5, -1);
    hit.hi = Vec3(2, 2, 0);  // touches the flat box from below
    expect_same(bvh_query(bvh, hit), {0});
    Aabb miss;
    miss.lo = Vec3(0.5, 0.5, 1e-9);
    miss.hi = Vec3(2, 2, 1);
    expect_same(bvh_query(bvh, miss), {});
}

TEST(Bvh, FlatTrianglesAndFlatQueries) {
    std::mt19937_64 rng(777);
    for (int axis = 0; axis < 3; ++axis) {
        const TriMesh m = random_soup(2000, rng, axis);
        const Bvh bvh(m, 4);
        check_structure(bvh, m, 4);
        for (int q = 0; q < 300; ++q) {
            // Flat query on the triangles' plane, and ordinary queries through it.
            const Aabb box = random_query(rng, q % 2 == 0 ? axis : -1);
            expect_same(bvh_query(bvh, box), brute_force(m, box));
        }
        // A flat query just off the plane finds nothing.
        Aabb off;
        off.lo = Vec3(-1);
        off.hi = Vec3(2);
        off.lo[axis] = off.hi[axis] = 0.5 + 1e-9;
        expect_same(bvh_query(bvh, off), {});
    }
}

TEST(Bvh, CoincidentTrianglesStayShallow) {
    // Every centroid equal: the median split still halves the set, by triangle index.
    TriMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 10000; ++i) m.triangles.push_back({0, 1, 2});
    const Bvh bvh(m, 4);
    check_structure(bvh, m, 4);
    Aabb q;
    q.lo = Vec3(0.2, 0.2, 0);
    q.hi = Vec3(0.3, 0.3, 0);
    EXPECT_EQ(bvh_query(bvh, q).size(), 10000u);
}

TEST(Bvh, EarlyStop) {
    std::mt19937_64 rng(5);
    const TriMesh m = random_soup(500, rng);
    const Bvh bvh(m, 4);
    Aabb all;
    all.lo = Vec3(-1);
    all.hi = Vec3(2);
    int visits = 0;
    EXPECT_FALSE(bvh.query(all, [&](uint32_t) { return ++visits < 7; }));
    EXPECT_EQ(visits, 7);
}

TEST(Bvh, DeterministicBuild) {
    std::mt19937_64 rng(99);
    const TriMesh m = random_soup(3000, rng);
    const Bvh a(m, 4), b(m, 4);
    ASSERT_EQ(a.nodes().size(), b.nodes().size());
    EXPECT_EQ(a.order(), b.order());
    for (size_t i = 0; i < a.nodes().size(); ++i) {
        EXPECT_EQ(a.nodes()[i].first, b.nodes()[i].first);
        EXPECT_EQ(a.nodes()[i].count, b.nodes()[i].count);
    }
}

TEST(Bvh, MillionTriangles) {
    // A large mesh builds with a logarithmic depth and answers like brute force.
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    TriMesh m;
    const size_t n = 1u << 20;
    m.vertices.reserve(3 * n);
    m.triangles.reserve(n);
    for (size_t t = 0; t < n; ++t) {
        const Vec3 c(u(rng), u(rng), u(rng));
        const uint32_t b = uint32_t(m.vertices.size());
        m.vertices.push_back(c);
        m.vertices.push_back(c + Vec3(1e-3, 0, 0));
        m.vertices.push_back(c + Vec3(0, 1e-3, 1e-3));
        m.triangles.push_back({b, b + 1, b + 2});
    }
    const Bvh bvh(m, 4);
    EXPECT_LE(bvh.depth(), 20);  // 1 + log2(2^20 / 4) = 19
    check_structure(bvh, m, 4);
    for (int q = 0; q < 20; ++q) {
        Aabb box = random_query(rng);
        box.hi = box.lo + Vec3(0.02);
        expect_same(bvh_query(bvh, box), brute_force(m, box));
    }
}

#if defined(__AVX2__)
// The four-lane box test the step scans a kept set of slots with answers as Aabb::overlaps does:
// boxes apart, overlapping, touching at a face, edge or corner (equal coordinates overlap), one
// inside the other, empty, and with NaN or infinite coordinates.
TEST(LanesBoxQuery, AnswersAsOverlaps) {
    std::mt19937_64 rng(17);
    std::uniform_int_distribution<int> grid(0, 6), pick(0, 19);
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    // Coordinates on a small grid, so that equal ones (touching boxes) come often.
    auto coordinate = [&] {
        const int k = pick(rng);
        return k == 0 ? nan : k == 1 ? inf : k == 2 ? -inf : 0.25 * grid(rng);
    };
    auto box = [&] {
        Aabb b;
        for (int a = 0; a < 3; ++a) {
            double x = coordinate(), y = coordinate();
            if (pick(rng) > 1 && x > y) std::swap(x, y);  // mostly ordered; sometimes empty
            b.lo[a] = x;
            b.hi[a] = y;
        }
        return b;
    };
    int overlapping = 0, apart = 0;
    for (int trial = 0; trial < 200000; ++trial) {
        const Aabb q = box(), b = trial % 5 == 0 ? q : box();
        const bool expected = b.overlaps(q);
        EXPECT_EQ(LanesBoxQuery(q).overlaps(b), expected) << "trial " << trial;
        (expected ? overlapping : apart) += 1;
    }
    EXPECT_GT(overlapping, 10000);
    EXPECT_GT(apart, 10000);
}

// The box of a run of vectors four at a time is the box Aabb::grow makes of them one by one, for
// every length from none to past a few groups of four, with NaN and infinite coordinates among
// them and with many equal ones.
TEST(LanesBounds, GivesTheBoxGrowGives) {
    std::mt19937_64 rng(29);
    std::uniform_int_distribution<int> grid(-4, 4), pick(0, 29);
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    auto coordinate = [&] {
        const int k = pick(rng);
        return k == 0 ? nan : k == 1 ? inf : k == 2 ? -inf : k < 15 ? 0.125 * grid(rng) : std::ldexp(double(grid(rng)), -grid(rng));
    };
    std::vector<Vec3> v(40);
    for (int trial = 0; trial < 20000; ++trial) {
        const int n = trial % 19;
        for (int i = 0; i < n; ++i) v[size_t(i)] = Vec3(coordinate(), coordinate(), coordinate());
        Aabb expected;
        for (int i = 0; i < n; ++i) expected.grow(v[size_t(i)]);
        const Aabb got = lanes_bounds(v.data(), n);
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(got.lo[a], expected.lo[a]) << "trial " << trial << " axis " << a;
            EXPECT_EQ(got.hi[a], expected.hi[a]) << "trial " << trial << " axis " << a;
        }
    }
}
#endif

}  // namespace
}  // namespace sulcus
