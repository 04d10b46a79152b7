// The servo step allocates nothing after its first call on a thread (its scratch memory is a
// per-thread workspace): counted by replacing the global operator new in this executable.
#include "scene_helpers.h"

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

namespace {
std::atomic<long> g_news{0};
}

void* operator new(std::size_t n) {
    ++g_news;
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace sulcus;
using namespace sulcus::test;

TEST(StepAllocation, NoHeapAllocationAfterTheFirstStep) {
    // A cube pressed into an L-shaped solid, sliding over a convex edge into a concave corner,
    // turning: every stage of the step runs.
    const std::vector<Vec2> ell = {{-20 * mm, -20 * mm}, {20 * mm, -20 * mm}, {20 * mm, 10 * mm},
                                   {10 * mm, 10 * mm},   {10 * mm, 0},        {-20 * mm, 0}};
    auto model = model_of(make_box(Vec3(2 * mm)), {object("ell", make_extruded_polygon(ell, -10 * mm, 10 * mm))});
    State st = make_state(pose(Vec3(-10 * mm, 3 * mm, 0)));
    step(*model, st, pose(Vec3(-10 * mm, 3 * mm, 0)));  // warm-up: the workspace is made here
    const long before = g_news.load();
    int contact = 0;
    for (int i = 1; i <= 3000; ++i) {
        const double f = i / 3000.0;
        const Pose h = pose(Vec3(-10 * mm + f * 24 * mm, 1 * mm - f * 1.5 * mm, 0),
                            axis_angle(Vec3(0, 1, 0.3), 0.4 * f));
        const StepResult r = step(*model, st, h);
        if (r.status == StepStatus::Contact) ++contact;
    }
    EXPECT_EQ(g_news.load() - before, 0);
    EXPECT_GT(contact, 1000);
    // The counter does count: a vector allocates once.
    const long probe = g_news.load();
    std::vector<double> v(static_cast<size_t>(contact));
    EXPECT_EQ(g_news.load() - probe, 1);
    EXPECT_EQ(v.size(), static_cast<size_t>(contact));
}
