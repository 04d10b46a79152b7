// The lesson runtime on a synthetic tooth: what it measures per site, how steps advance, when
// rules fire, and that the same input gives the same scores bit for bit.
#include "sulcus/app/lesson_runtime.h"
#include "sulcus/app/scoring.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace sulcus;

namespace {

constexpr double kR = 4e-3;  // the sites stand on a circle of this radius around the axis (+Y)
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Tooth 11 at the origin, long axis +Y, margin at y = 0, mesial toward +X.
std::vector<SiteFrame> tooth_sites() {
    const std::pair<Site, double> at[] = {{Site::MB, 45}, {Site::B, 90}, {Site::DB, 135},
                                          {Site::DL, 225}, {Site::L, 270}, {Site::ML, 315}};
    std::vector<SiteFrame> out;
    for (Site s : kAllSites) {
        for (const auto& [site, deg] : at) {
            if (site != s) continue;
            SiteFrame f{};
            f.fdi = 11;
            f.site = s;
            f.theta_rad = deg * kDeg;
            f.outward = Vec3(std::cos(f.theta_rad), 0.0, std::sin(f.theta_rad));
            f.margin_point = kR * f.outward;
            f.axis = Vec3(0.0, 1.0, 0.0);
            f.pd_m = 2e-3;
            f.floor_point = f.margin_point - Vec3(0.0, f.pd_m, 0.0);
            out.push_back(f);
        }
    }
    return out;
}

Chart reference() {
    Chart c;
    ToothRecord t;
    t.fdi = 11;
    for (Site s : kAllSites) {
        SiteRecord r;
        r.pd_mm = 2.0;
        r.bop = s == Site::B;
        t.sites[static_cast<std::size_t>(s)] = r;
    }
    c.teeth[11] = t;
    return c;
}

Lesson lesson(std::vector<LessonStep> steps, std::vector<LessonRule> rules = {}) {
    Lesson l;
    l.title = "synthetic";
    l.chart = "cases/x/chart.json";
    l.teeth = {11};
    l.steps = std::move(steps);
    l.rules = std::move(rules);
    return l;
}

LessonStep step(const std::string& id, std::vector<SiteRef> sites, StepCondition c = StepCondition::Charted,
                StepOrder o = StepOrder::Any) {
    LessonStep s;
    s.id = id;
    s.instruction = "do " + id;
    s.sites = std::move(sites);
    s.complete = c;
    s.order = o;
    return s;
}

// Feeds ticks at 1 kHz.
struct Driver {
    LessonRuntime& rt;
    uint64_t tick = 0;
    // The tip `depth` below the margin of `site`, `along` the sulcus (m), tilted by `tilt_z_deg`
    // about +Z (the probe's +Y axis leaning toward -X), pressing with `force_N`.
    void at(Site site, double depth, double force_N, double along = 0.0, double tilt_z_deg = 0.0) {
        const std::vector<SiteFrame> f = tooth_sites();
        const SiteFrame& fr = f[static_cast<std::size_t>(site)];
        const Vec3 tangent = glm::normalize(glm::cross(fr.axis, fr.outward));
        ServoSnapshot s;
        s.tick = tick;
        s.time_s = double(tick) * 1e-3;
        s.graphic.position = fr.margin_point - Vec3(0.0, depth, 0.0) + along * tangent;
        const double h = 0.5 * tilt_z_deg * kDeg;
        s.graphic.orientation = Quat(std::cos(h), 0.0, 0.0, std::sin(h));
        s.rendered_force_N = Vec3(0.0, force_N, 0.0);
        rt.on_tick(s);
        ++tick;
    }
    void away(double force_N = 0.0) {
        ServoSnapshot s;
        s.tick = tick;
        s.time_s = double(tick) * 1e-3;
        s.graphic.position = Vec3(0.0, 0.02, 0.0);  // far above the crown
        s.rendered_force_N = Vec3(force_N, 0.0, 0.0);
        rt.on_tick(s);
        ++tick;
    }
};

int count(const LessonRuntime& rt, FeedbackLevel level, const std::string& source) {
    int n = 0;
    for (const Feedback& f : rt.feedback()) n += f.level == level && f.source == source;
    return n;
}

}  // namespace

TEST(LessonRuntime, DeepestInsertionAndTheForceAndAngleThere) {
    LessonRuntime rt(lesson({step("b", {{11, Site::B}})}), tooth_sites(), reference());
    Driver d{rt};
    d.away();
    for (int k = 1; k <= 20; ++k) d.at(Site::B, k * 0.1e-3, k * 0.01);  // down to 2 mm at 0.2 N
    for (int k = 19; k >= 10; --k) d.at(Site::B, k * 0.1e-3, 0.05);     // back up to 1 mm
    const SiteMeasure& m = rt.sites()[static_cast<std::size_t>(Site::B)];
    EXPECT_TRUE(m.visited);
    EXPECT_DOUBLE_EQ(m.deepest_m, 20 * 0.1e-3);
    EXPECT_DOUBLE_EQ(m.force_at_deepest_N, 0.2);
    EXPECT_DOUBLE_EQ(m.deepest_time_s, 0.020);
    EXPECT_NEAR(m.angle_at_deepest_rad, 0.0, 1e-12);
    EXPECT_DOUBLE_EQ(m.max_force_N, 0.2);
    EXPECT_EQ(m.withdrawals, 0);
    EXPECT_FALSE(rt.sites()[static_cast<std::size_t>(Site::MB)].visited);
}

TEST(LessonRuntime, TiltTowardTheContactAtAnInterproximalSite) {
    LessonRuntime rt(lesson({step("mb", {{11, Site::MB}})}), tooth_sites(), reference());
    Driver d{rt};
    // MB's contact is mesial (+X); the probe's axis leaning to -X puts the tip under it.
    d.at(Site::MB, 1e-3, 0.2, 0.0, 12.0);
    const SiteMeasure& m = rt.sites()[static_cast<std::size_t>(Site::MB)];
    EXPECT_TRUE(m.interproximal);
    EXPECT_NEAR(m.tilt_at_deepest_rad, 12.0 * kDeg, 1e-12);
    EXPECT_NEAR(m.angle_at_deepest_rad, 12.0 * kDeg, 1e-12);
    // The same lean at DB (its contact distal, -X) tilts away from the contact.
    d.at(Site::DB, 1e-3, 0.2, 0.0, 12.0);
    EXPECT_NEAR(rt.sites()[static_cast<std::size_t>(Site::DB)].tilt_at_deepest_rad, -12.0 * kDeg, 1e-12);
}

TEST(LessonRuntime, WalkingAdvanceIsTheRangeAlongTheSulcus) {
    LessonRuntime rt(lesson({step("b", {{11, Site::B}}, StepCondition::Walked)}), tooth_sites(), reference());
    Driver d{rt};
    for (int k = -3; k <= 4; ++k) d.at(Site::B, 1.5e-3, 0.2, k * 0.15e-3);  // -0.45 .. +0.6 mm
    EXPECT_NEAR(rt.sites()[static_cast<std::size_t>(Site::B)].advance_m(), 1.05e-3, 1e-15);
    // Done once the range reaches walk_advance_mm (1 mm): at the last tick (0.9 mm before it).
    EXPECT_TRUE(rt.complete());
    EXPECT_EQ(rt.steps()[0].end_s, 7e-3);
}

TEST(LessonRuntime, AWithdrawalIsCountedAndNotedWhileTheSideIsUnfinished) {
    LessonRule left{"left", RuleTrigger::LeftSulcus, 0.0, RuleLevel::Note, "Stay in the sulcus.", 0.0};
    LessonRuntime rt(lesson({step("facial", {{11, Site::MB}, {11, Site::B}})}, {left}), tooth_sites(), reference());
    Driver d{rt};
    d.at(Site::B, 1e-3, 0.2);
    d.at(Site::B, -0.5e-3, 0.0);  // above the margin: out
    d.at(Site::B, 1e-3, 0.2);
    d.at(Site::MB, 1e-3, 0.2);    // to the next site below the margin: no withdrawal
    d.away();                     // out of MB
    EXPECT_EQ(rt.sites()[static_cast<std::size_t>(Site::B)].withdrawals, 1);
    EXPECT_EQ(rt.sites()[static_cast<std::size_t>(Site::MB)].withdrawals, 1);
    EXPECT_EQ(rt.withdrawals(11, false), 2);
    EXPECT_EQ(rt.withdrawals(11, true), 0);
    EXPECT_EQ(count(rt, FeedbackLevel::Note, "left"), 2);
    // Once the facial sites are charted the step is done: leaving then is no longer noted.
    rt.on_event(kEventChartDepth, chart_depth_event({11, Site::MB}, 2));
    rt.on_event(kEventChartDepth, chart_depth_event({11, Site::B}, 2));
    d.at(Site::B, 1e-3, 0.2);
    d.away();
    EXPECT_EQ(count(rt, FeedbackLevel::Note, "left"), 2);
    EXPECT_EQ(rt.sites()[static_cast<std::size_t>(Site::B)].withdrawals, 2);
}

TEST(LessonRuntime, ForceRulesFireOnCrossingOncePerCooldown) {
    LessonRule firm{"firm", RuleTrigger::ForceAbove, 0.25, RuleLevel::Warning, "Too firm.", 1.0};
    LessonRule trauma{"trauma", RuleTrigger::ForceAtLeast, 0.5, RuleLevel::Warning, "Trauma.", 1.0};
    LessonRuntime rt(lesson({step("b", {{11, Site::B}})}, {firm, trauma}), tooth_sites(), reference());
    Driver d{rt};
    d.at(Site::B, 1e-3, 0.25);  // exactly 0.25: not above
    EXPECT_EQ(count(rt, FeedbackLevel::Warning, "firm"), 0);
    d.at(Site::B, 1e-3, 0.30);  // fires (t = 1 ms)
    d.at(Site::B, 1e-3, 0.20);
    d.at(Site::B, 1e-3, 0.30);  // crosses again within the cooldown: quiet
    EXPECT_EQ(count(rt, FeedbackLevel::Warning, "firm"), 1);
    while (d.tick < 1100) d.at(Site::B, 1e-3, 0.20);
    d.at(Site::B, 1e-3, 0.50);  // t = 1.1 s: fires again, and trauma at exactly 0.5
    EXPECT_EQ(count(rt, FeedbackLevel::Warning, "firm"), 2);
    EXPECT_EQ(count(rt, FeedbackLevel::Warning, "trauma"), 1);
    EXPECT_NE(rt.feedback().back().message.find("0.500 N at 11B"), std::string::npos);
}

TEST(LessonRuntime, TimeAboveTheWarningAndAtTraumaIntegratesTickLengths) {
    LessonRuntime rt(lesson({step("b", {{11, Site::B}})}), tooth_sites(), reference());
    Driver d{rt};
    for (int k = 0; k < 100; ++k) d.at(Site::B, 1e-3, 0.30);  // the first tick has no length
    for (int k = 0; k < 50; ++k) d.at(Site::B, 1e-3, 0.60);
    for (int k = 0; k < 50; ++k) d.away(0.60);                 // outside every sulcus
    EXPECT_NEAR(rt.time_above_warning_s(), 0.199, 1e-12);
    EXPECT_NEAR(rt.time_at_trauma_s(), 0.100, 1e-12);
    EXPECT_NEAR(rt.sites()[static_cast<std::size_t>(Site::B)].time_above_warning_s, 0.149, 1e-12);
    EXPECT_NEAR(rt.sites()[static_cast<std::size_t>(Site::B)].time_at_trauma_s, 0.050, 1e-12);
    EXPECT_DOUBLE_EQ(rt.max_force_N(), 0.60);
}

TEST(LessonRuntime, StepsAdvanceInOrderWithNotesSkipsAndAnEnd) {
    LessonStep s1 = step("facial", {{11, Site::MB}, {11, Site::B}}, StepCondition::Charted, StepOrder::Listed);
    LessonStep s2 = step("read", {}, StepCondition::Acknowledged);
    LessonStep s3 = step("lingual", {{11, Site::L}}, StepCondition::Probed);
    LessonStep s4 = step("last", {{11, Site::DL}});
    LessonRuntime rt(lesson({s1, s2, s3, s4}), tooth_sites(), reference());
    Driver d{rt};
    d.away();
    EXPECT_EQ(rt.current_step(), 0);
    EXPECT_TRUE(rt.steps()[0].started);
    rt.on_event(kEventChartDepth, chart_depth_event({11, Site::B}, 3));  // before MB: out of order
    EXPECT_EQ(rt.steps()[0].order_violations, 1);
    EXPECT_EQ(rt.current_step(), 0);
    d.away();
    rt.on_event(kEventChartDepth, chart_depth_event({11, Site::MB}, 2));
    EXPECT_EQ(rt.current_step(), 1);
    EXPECT_TRUE(rt.steps()[0].completed);
    d.away();
    rt.on_event(kEventLessonNext, "{}");  // acknowledges the instruction
    EXPECT_EQ(rt.current_step(), 2);
    d.at(Site::L, 0.9e-3, 0.2);  // reference 2 mm: 0.9 mm is not the floor (within 1 mm)
    EXPECT_EQ(rt.current_step(), 2);
    d.at(Site::L, 1.0e-3, 0.2);
    EXPECT_EQ(rt.current_step(), 3);
    rt.on_event(kEventLessonNext, "{}");  // moving on unfinished skips
    EXPECT_TRUE(rt.steps()[3].skipped);
    EXPECT_TRUE(rt.complete());
    rt.on_event(kEventLessonEnd, "{}");
    const uint64_t n = rt.ticks();
    d.at(Site::DL, 1e-3, 0.2);
    EXPECT_EQ(rt.ticks(), n);  // nothing counts after the end
    EXPECT_TRUE(rt.ended());
    const Chart c = rt.trainee_chart();
    EXPECT_EQ(c.teeth.at(11).sites[static_cast<std::size_t>(Site::B)]->pd_mm, 3.0);
    EXPECT_FALSE(c.teeth.at(11).sites[static_cast<std::size_t>(Site::L)].has_value());
}

TEST(LessonRuntime, HintsAppearOnceTheStepHasRunLongEnough) {
    LessonStep s = step("b", {{11, Site::B}});
    s.hints = {{"Light force.", 0.005}, {"Parallel.", 0.010}};
    LessonRuntime rt(lesson({s}), tooth_sites(), reference());
    Driver d{rt};
    for (int k = 0; k < 7; ++k) d.away();
    EXPECT_EQ(count(rt, FeedbackLevel::Hint, "b"), 1);
    for (int k = 0; k < 7; ++k) d.away();
    EXPECT_EQ(count(rt, FeedbackLevel::Hint, "b"), 2);
}

TEST(LessonRuntime, MalformedEventsAreNotedAndIgnored) {
    LessonRuntime rt(lesson({step("b", {{11, Site::B}})}), tooth_sites(), reference());
    Driver d{rt};
    d.away();
    rt.on_event(kEventChartDepth, "{\"site\":\"11B\",\"pd_mm\":99}");
    rt.on_event(kEventChartDepth, "not json");
    rt.on_event(kEventChartDepth, "{\"site\":\"36B\",\"pd_mm\":2}");  // not a tooth of the lesson
    rt.on_event(kEventChartBop, "{\"site\":\"11B\",\"bop\":1}");
    rt.on_event("view.sextant", "garbage");  // other kinds are not the runtime's
    EXPECT_EQ(rt.bad_events(), 4);
    EXPECT_EQ(count(rt, FeedbackLevel::Note, "input"), 4);
    EXPECT_FALSE(rt.sites()[static_cast<std::size_t>(Site::B)].charted_pd_mm.has_value());
    rt.on_event(kEventChartBop, chart_bop_event({11, Site::B}, true));
    EXPECT_TRUE(rt.sites()[static_cast<std::size_t>(Site::B)].charted_bop);
}

TEST(LessonRuntime, TheSameInputScoresTheSameBitForBit) {
    auto run = [] {
        LessonRule firm{"firm", RuleTrigger::ForceAbove, 0.25, RuleLevel::Warning, "Too firm.", 1.0};
        LessonRuntime rt(lesson({step("all", {{11, Site::MB}, {11, Site::B}, {11, Site::L}})}, {firm}), tooth_sites(),
                         reference());
        Driver d{rt};
        for (int k = 0; k < 300; ++k) d.at(Site::B, 1e-3 + 1e-3 * std::sin(k * 0.05), 0.2 + 0.1 * std::cos(k * 0.07), 0.3e-3 * std::sin(k * 0.01), 3.0);
        rt.on_event(kEventChartDepth, chart_depth_event({11, Site::B}, 2));
        for (int k = 0; k < 300; ++k) d.at(Site::MB, 1.5e-3 * std::fabs(std::sin(k * 0.03)), 0.22, 0.0, 9.0);
        rt.finish();
        return scores_to_json(score_lesson(rt)).dump();
    };
    const std::string a = run(), b = run();
    EXPECT_EQ(a, b);
    EXPECT_GT(a.size(), 500u);
}
