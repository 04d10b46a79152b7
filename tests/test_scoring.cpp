// Scoring from the rubric: every row against expectations computed by hand.
#include "sulcus/app/scoring.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace sulcus;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

SiteMeasure site(int fdi, Site s, double ref_pd, std::optional<double> charted) {
    SiteMeasure m;
    m.ref = {fdi, s};
    m.target = true;
    m.interproximal = s != Site::B && s != Site::L;
    m.reference_pd_mm = ref_pd;
    m.charted_pd_mm = charted;
    return m;
}

void probe(SiteMeasure& m, double deepest_mm, double force_N, double angle_deg, double tilt_deg, double walk_mm,
           int withdrawals) {
    m.visited = true;
    m.deepest_m = deepest_mm * 1e-3;
    m.force_at_deepest_N = force_N;
    m.max_force_N = force_N;
    m.angle_at_deepest_rad = angle_deg * kDeg;
    m.tilt_at_deepest_rad = tilt_deg * kDeg;
    m.walk_min_m = -0.25e-3;
    m.walk_max_m = -0.25e-3 + walk_mm * 1e-3;
    m.withdrawals = withdrawals;
}

const RowScore& row(const LessonScores& s, const std::string& name) {
    for (const RowScore& r : s.rows)
        if (r.name == name) return r;
    throw std::runtime_error("no row " + name);
}

// The worked example of docs/lessons.md: four sites of 11, each wrong in its own way.
SessionMeasures example() {
    SessionMeasures m;
    SiteMeasure mb = site(11, Site::MB, 3, 3.0);  // exact
    probe(mb, 3.1, 0.22, 8, 10, 1.2, 0);           // right force, tilted 10 deg, walked 1.2 mm
    SiteMeasure b = site(11, Site::B, 2, 3.0);     // 1 mm off: within tolerance
    probe(b, 2.4, 0.15, 12, 0, 0.5, 2);            // light, 12 deg off the axis, 0.5 mm, out twice
    SiteMeasure db = site(11, Site::DB, 3, 5.0);   // 2 mm off
    probe(db, 3.0, 0.30, 3, 2, 0.0, 0);            // too firm, tilted only 2 deg, not walked
    SiteMeasure l = site(11, Site::L, 2, std::nullopt);  // not charted
    probe(l, 2.6, 0.55, 5, 0, 1.0, 1);             // traumatic, parallel, walked 1 mm, out once
    SiteMeasure other = site(11, Site::ML, 2, std::nullopt);
    other.target = false;                          // measured but not a target: not scored
    m.sites = {mb, b, db, other, l};
    m.time_s = 125.0;
    m.max_force_N = 0.55;
    m.time_above_warning_s = 0.8;
    m.time_at_trauma_s = 0.1;
    m.steps_total = 2;
    m.steps_completed = 1;
    return m;
}

Rubric example_rubric() {
    Rubric rb;
    rb.time_limit_s = 100.0;
    return rb;
}

}  // namespace

TEST(Scoring, OnlyTargetSitesAreScoredInTheirOrder) {
    const LessonScores s = score_measures(example_rubric(), example());
    ASSERT_EQ(s.sites.size(), 4u);
    EXPECT_EQ(site_ref_name(s.sites[0].ref), "11MB");
    EXPECT_EQ(site_ref_name(s.sites[3].ref), "11L");
    EXPECT_EQ(s.sites_target, 4);
    EXPECT_EQ(s.sites_charted, 3);
    EXPECT_EQ(s.sites_probed, 4);
}

TEST(Scoring, DepthRowGradesEachSiteAndNeedsNinetyFivePercentWithinOneMillimetre) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_EQ(s.sites[0].depth, DepthGrade::Exact);
    EXPECT_EQ(s.sites[1].depth, DepthGrade::Pass);
    EXPECT_EQ(s.sites[2].depth, DepthGrade::Fail);
    EXPECT_EQ(s.sites[3].depth, DepthGrade::NotCharted);
    EXPECT_DOUBLE_EQ(*s.sites[2].error_mm, 2.0);
    // (1 + 0.5 + 0) / 3 charted; 2 of 3 within 1 mm < 95 %.
    EXPECT_DOUBLE_EQ(row(s, "depth").score, 0.5);
    EXPECT_FALSE(row(s, "depth").passed);
    EXPECT_NE(row(s, "depth").feedback.find("11DB charted 5 mm, reference 3 mm"), std::string::npos);
}

TEST(Scoring, DepthBandEdgesAreInclusive) {
    SessionMeasures m;
    m.sites = {site(11, Site::MB, 2.5, 3.0), site(11, Site::B, 2.0, 3.0), site(11, Site::DB, 1.5, 3.0)};
    const LessonScores s = score_measures(Rubric{}, m);
    EXPECT_EQ(s.sites[0].depth, DepthGrade::Exact);  // 0.5 mm off: exact
    EXPECT_EQ(s.sites[1].depth, DepthGrade::Pass);   // 1 mm off: within
    EXPECT_EQ(s.sites[2].depth, DepthGrade::Fail);   // 1.5 mm off
    Rubric strict;
    strict.depth_exact_mm = 0.0;
    strict.depth_pass_mm = 0.5;
    const LessonScores t = score_measures(strict, m);
    EXPECT_EQ(t.sites[0].depth, DepthGrade::Pass);
    EXPECT_EQ(t.sites[1].depth, DepthGrade::Fail);
}

TEST(Scoring, ForceRowGradesTheForceAtTheDeepestPointAndFailsOnTrauma) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_EQ(s.sites[0].force, ForceGrade::Target);
    EXPECT_EQ(s.sites[1].force, ForceGrade::Light);
    EXPECT_EQ(s.sites[2].force, ForceGrade::Warning);
    EXPECT_EQ(s.sites[3].force, ForceGrade::Trauma);
    // (1 + 0.5 + 0.5 + 0) / 4; 0.55 N reached: not passed.
    EXPECT_DOUBLE_EQ(row(s, "force").score, 0.5);
    EXPECT_FALSE(row(s, "force").passed);
}

TEST(Scoring, ForceBandEdgesAndTimeAboveTheWarning) {
    SessionMeasures m;
    SiteMeasure a = site(11, Site::MB, 2, 2.0), b = site(11, Site::B, 2, 2.0), c = site(11, Site::DB, 2, 2.0);
    probe(a, 2, 0.20, 0, 10, 1, 0);  // the band's lower edge: right
    probe(b, 2, 0.25, 0, 0, 1, 0);   // the warning level itself: still right (above it warns)
    probe(c, 2, 0.50, 0, 10, 1, 0);  // trauma starts at 0.5 N
    m.sites = {a, b, c};
    m.max_force_N = 0.5;
    const LessonScores s = score_measures(Rubric{}, m);
    EXPECT_EQ(s.sites[0].force, ForceGrade::Target);
    EXPECT_EQ(s.sites[1].force, ForceGrade::Target);
    EXPECT_EQ(s.sites[2].force, ForceGrade::Trauma);

    // No trauma: the row passes with up to max_time_above_warning_s above 0.25 N, not beyond.
    SessionMeasures ok;
    ok.sites = {a, b};
    ok.max_force_N = 0.3;
    ok.time_above_warning_s = 1.0;
    EXPECT_TRUE(row(score_measures(Rubric{}, ok), "force").passed);
    ok.time_above_warning_s = 1.5;
    EXPECT_FALSE(row(score_measures(Rubric{}, ok), "force").passed);
    EXPECT_DOUBLE_EQ(row(score_measures(Rubric{}, ok), "force").score, 1.0);

    // A firmer band: between the target's top and the warning it is "firm" (0.75).
    Rubric rb;
    rb.force_target_max_N = 0.22;
    EXPECT_EQ(score_measures(rb, ok).sites[1].force, ForceGrade::Firm);
    EXPECT_DOUBLE_EQ(score_measures(rb, ok).sites[1].force_score, 0.75);
}

TEST(Scoring, AngulationRowParallelAtDirectSitesTiltedUnderTheContactAtInterproximalOnes) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_TRUE(s.sites[0].angle_ok);   // MB tilted 10 deg in 5..20
    EXPECT_FALSE(s.sites[1].angle_ok);  // B 12 deg > 10
    EXPECT_FALSE(s.sites[2].angle_ok);  // DB tilted 2 deg < 5
    EXPECT_TRUE(s.sites[3].angle_ok);   // L 5 deg <= 10
    EXPECT_DOUBLE_EQ(row(s, "angulation").score, 0.5);
    EXPECT_FALSE(row(s, "angulation").passed);  // 0.5 < 0.8
    Rubric loose = example_rubric();
    loose.angle_direct_max_deg = 15.0;
    loose.angle_interproximal_min_deg = 0.0;
    EXPECT_DOUBLE_EQ(row(score_measures(loose, example()), "angulation").score, 1.0);
    EXPECT_TRUE(row(score_measures(loose, example()), "angulation").passed);
}

TEST(Scoring, WalkingRowIsTheAdvanceOverOneMillimetrePerSite) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_NEAR(s.sites[0].advance_mm, 1.2, 1e-12);
    EXPECT_DOUBLE_EQ(s.sites[0].walk_score, 1.0);
    EXPECT_NEAR(s.sites[1].walk_score, 0.5, 1e-12);
    EXPECT_DOUBLE_EQ(s.sites[2].walk_score, 0.0);
    // (1 + 0.5 + 0 + 1) / 4; 2 of 4 sites walked < 80 %.
    EXPECT_NEAR(row(s, "walking").score, 0.625, 1e-12);
    EXPECT_FALSE(row(s, "walking").passed);
}

TEST(Scoring, WithdrawalsRowCountsTheExtraOnesPerSideOfATooth) {
    const LessonScores s = score_measures(example_rubric(), example());
    // Facial side: 0 + 2 + 0 = 2, one more than allowed; lingual: 1, allowed. 1 - 1/4.
    EXPECT_DOUBLE_EQ(row(s, "withdrawals").score, 0.75);
    EXPECT_FALSE(row(s, "withdrawals").passed);
    Rubric two = example_rubric();
    two.max_withdrawals_per_side = 2;
    EXPECT_DOUBLE_EQ(row(score_measures(two, example()), "withdrawals").score, 1.0);
    EXPECT_TRUE(row(score_measures(two, example()), "withdrawals").passed);
}

TEST(Scoring, CompletenessRowIsTheFractionOfTargetSitesCharted) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_DOUBLE_EQ(row(s, "completeness").score, 0.75);
    EXPECT_FALSE(row(s, "completeness").passed);
    EXPECT_NE(row(s, "completeness").feedback.find("Missing: 11L"), std::string::npos);
    Rubric rb = example_rubric();
    rb.completeness_pass_fraction = 0.75;
    EXPECT_TRUE(row(score_measures(rb, example()), "completeness").passed);
}

TEST(Scoring, TimeRowScoresOnlyWithALimit) {
    const LessonScores s = score_measures(example_rubric(), example());
    EXPECT_DOUBLE_EQ(row(s, "time").score, 0.8);  // 100 / 125
    EXPECT_FALSE(row(s, "time").passed);
    EXPECT_DOUBLE_EQ(row(s, "time").weight, 0.05);
    const LessonScores none = score_measures(Rubric{}, example());
    EXPECT_DOUBLE_EQ(row(none, "time").weight, 0.0);
    EXPECT_TRUE(row(none, "time").passed);
}

TEST(Scoring, OverallIsTheWeightedMeanOfTheRows) {
    const LessonScores s = score_measures(example_rubric(), example());
    // 0.35*0.5 + 0.20*0.5 + 0.15*0.5 + 0.10*0.625 + 0.05*0.75 + 0.10*0.75 + 0.05*0.8 over weights 1.0.
    EXPECT_NEAR(s.overall, 0.565, 1e-12);
    EXPECT_FALSE(s.passed);
    // Without the time limit the time row carries no weight: 0.525 / 0.95.
    const LessonScores n = score_measures(Rubric{}, example());
    EXPECT_NEAR(n.overall, 0.525 / 0.95, 1e-12);
    Rubric low = example_rubric();
    low.pass_score = 0.5;
    EXPECT_TRUE(score_measures(low, example()).passed);
}

TEST(Scoring, APerfectSessionScoresOneAndPasses) {
    SessionMeasures m;
    for (Site st : kAllSites) {
        SiteMeasure x = site(36, st, 5, 5.0);
        probe(x, 5.0, 0.23, 4, 12, 1.5, 0);
        m.sites.push_back(x);
    }
    m.sites[0].withdrawals = 1;  // one exit per side is allowed
    m.sites[3].withdrawals = 1;
    m.time_s = 60.0;
    m.max_force_N = 0.24;
    const LessonScores s = score_measures(Rubric{}, m);
    for (const RowScore& r : s.rows) {
        EXPECT_DOUBLE_EQ(r.score, 1.0) << r.name;
        EXPECT_TRUE(r.passed) << r.name;
    }
    EXPECT_DOUBLE_EQ(s.overall, 1.0);
    EXPECT_TRUE(s.passed);
}

TEST(Scoring, JsonRoundTripsBitForBitAndAnEditIsNamed) {
    const LessonScores s = score_measures(example_rubric(), example());
    const nlohmann::json j = scores_to_json(s);
    const nlohmann::json back = nlohmann::json::parse(j.dump());
    EXPECT_EQ(first_json_difference(back, j), "");
    nlohmann::json edited = back;
    edited["sites"][1]["force_N"] = 0.151;
    EXPECT_EQ(first_json_difference(edited, j), "sites[1].force_N: stored 0.151, recomputed 0.15");
    nlohmann::json one_ulp = back;
    one_ulp["overall"] = std::nextafter(back["overall"].get<double>(), 1.0);
    EXPECT_NE(first_json_difference(one_ulp, j).find("overall: stored"), std::string::npos);
    nlohmann::json missing = back;
    missing.erase("time_s");
    EXPECT_EQ(first_json_difference(missing, j).rfind("time_s: not stored", 0), 0u);
}
