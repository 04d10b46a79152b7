// The probe's reading at a site (depth, distance from the site's line, tilt) against hand-computed
// values, which site it picks, and the trainee's chart: rounding to whole millimetres, attachment
// level, counts, writing as a chart, comparing with the reference.
#include "sulcus/app/probing_readout.h"
#include "sulcus/content/case_manifest.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sulcus {
namespace {

constexpr double mm = 1e-3;
constexpr double kPi = 3.14159265358979323846;

// A lower tooth's buccal site: margin at (10, 20, 0) mm, axis +Y (occlusal up), outward +Z.
SiteFrame lower_site(const Vec3& margin = Vec3(10 * mm, 20 * mm, 0.0)) {
    SiteFrame f;
    f.fdi = 36;
    f.site = Site::B;
    f.margin_point = margin;
    f.axis = Vec3(0.0, 1.0, 0.0);
    f.outward = Vec3(0.0, 0.0, 1.0);
    f.pd_m = 3 * mm;
    f.floor_point = margin - 3 * mm * f.axis;
    return f;
}

Pose probe_at(const Vec3& tip, const Quat& q = Quat(1, 0, 0, 0)) { return Pose{tip, q}; }

TEST(ReadProbe, DepthLateralAndAngleAsComputedByHand) {
    const std::vector<SiteFrame> sites = {lower_site()};
    // Tip 2.5 mm below the margin, 0.3 mm mesial and 0.4 mm outward of the line: lateral 0.5 mm.
    // Probe tilted 10 degrees about X: its +Y goes to (0, cos 10, sin 10), 10 degrees off the axis.
    const double tilt = 10.0 * kPi / 180.0;
    const Pose p = probe_at(Vec3(10.3 * mm, 17.5 * mm, 0.4 * mm), glm::angleAxis(tilt, Vec3(1.0, 0.0, 0.0)));
    const ProbeReading r = read_probe(sites, p);
    ASSERT_EQ(r.site_index, 0);
    EXPECT_NEAR(r.depth_m, 2.5 * mm, 1e-12);
    EXPECT_NEAR(r.lateral_m, 0.5 * mm, 1e-12);
    EXPECT_NEAR(r.angle_rad, tilt, 1e-9);
    EXPECT_TRUE(r.in_sulcus);

    // Parallel to the axis, on the line at the charted floor: the reading is the pocket depth.
    const ProbeReading at_floor = read_probe(sites, probe_at(sites[0].floor_point));
    ASSERT_EQ(at_floor.site_index, 0);
    EXPECT_NEAR(at_floor.depth_m, sites[0].pd_m, 1e-12);
    EXPECT_NEAR(at_floor.lateral_m, 0.0, 1e-12);
    EXPECT_NEAR(at_floor.angle_rad, 0.0, 1e-7);
}

TEST(ReadProbe, UpperToothAxisPointsDown) {
    // An upper tooth: occlusal is -Y, so "below the margin" (into the pocket) is +Y.
    SiteFrame f = lower_site(Vec3(0.0, 19 * mm, 3 * mm));
    f.axis = Vec3(0.0, -1.0, 0.0);
    const std::vector<SiteFrame> sites = {f};
    // The probe held upside down (handle toward the occlusal plane, -Y): parallel, angle 0.
    const Quat flipped = glm::angleAxis(kPi, Vec3(0.0, 0.0, 1.0));
    const ProbeReading r = read_probe(sites, probe_at(Vec3(0.2 * mm, 21.5 * mm, 3 * mm), flipped));
    ASSERT_EQ(r.site_index, 0);
    EXPECT_NEAR(r.depth_m, 2.5 * mm, 1e-12);
    EXPECT_NEAR(r.lateral_m, 0.2 * mm, 1e-12);
    EXPECT_NEAR(r.angle_rad, 0.0, 1e-7);
    // Held the lower-jaw way up, it points the wrong way: pi.
    EXPECT_NEAR(read_probe(sites, probe_at(Vec3(0.2 * mm, 21.5 * mm, 3 * mm))).angle_rad, kPi, 1e-7);
}

TEST(ReadProbe, NoSiteWhenFarOrTooHigh) {
    const std::vector<SiteFrame> sites = {lower_site()};
    // 2 mm from the line, beyond the 1.5 mm capture radius.
    EXPECT_EQ(read_probe(sites, probe_at(Vec3(12 * mm, 18 * mm, 0.0))).site_index, -1);
    // Within a 2.5 mm capture radius it is.
    EXPECT_EQ(read_probe(sites, probe_at(Vec3(12 * mm, 18 * mm, 0.0)), 2.5 * mm).site_index, 0);
    // On the line 1.2 mm above the margin: too high.
    EXPECT_EQ(read_probe(sites, probe_at(Vec3(10 * mm, 21.2 * mm, 0.0))).site_index, -1);
    // 0.8 mm above: at the site, but not in the sulcus, reading a negative depth.
    const ProbeReading above = read_probe(sites, probe_at(Vec3(10 * mm, 20.8 * mm, 0.0)));
    ASSERT_EQ(above.site_index, 0);
    EXPECT_NEAR(above.depth_m, -0.8 * mm, 1e-12);
    EXPECT_FALSE(above.in_sulcus);
    // No sites at all.
    EXPECT_EQ(read_probe({}, probe_at(Vec3(0.0))).site_index, -1);
}

TEST(ReadProbe, PicksTheNearestOfTwoSites) {
    // Two sites 1 mm apart along X, both within the capture radius of tips between them.
    const std::vector<SiteFrame> sites = {lower_site(Vec3(10 * mm, 20 * mm, 0.0)), lower_site(Vec3(11 * mm, 20.5 * mm, 0.0))};
    const ProbeReading a = read_probe(sites, probe_at(Vec3(10.3 * mm, 18 * mm, 0.0)));
    ASSERT_EQ(a.site_index, 0);
    EXPECT_NEAR(a.depth_m, 2.0 * mm, 1e-12);
    const ProbeReading b = read_probe(sites, probe_at(Vec3(10.7 * mm, 18 * mm, 0.0)));
    ASSERT_EQ(b.site_index, 1);
    EXPECT_NEAR(b.depth_m, 2.5 * mm, 1e-12);  // from the second site's own margin
    EXPECT_NEAR(b.lateral_m, 0.3 * mm, 1e-12);
    // The nearer one too high: the other is taken.
    std::vector<SiteFrame> high = sites;
    high[1].margin_point.y = 16 * mm;  // tip 2 mm above site 1's margin
    EXPECT_EQ(read_probe(high, probe_at(Vec3(10.7 * mm, 18 * mm, 0.0))).site_index, 0);
}

TEST(ReadProbe, AtEveryChartedFloorOfABundledCaseReadsTheChartedDepth) {
    const CaseManifestLoad l = load_case_manifest(std::string(SULCUS_BINARY_DIR) + "/cases/quadrant_44_47");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    const std::vector<SiteFrame>& sites = l.manifest.sites;
    ASSERT_EQ(sites.size(), 24u);
    for (std::size_t i = 0; i < sites.size(); ++i) {
        const SiteFrame& f = sites[i];
        // The probe parallel to the tooth axis (+Y turned onto it), tip at the charted floor.
        const Pose p{f.floor_point, Quat(Vec3(0.0, 1.0, 0.0), f.axis)};
        const ProbeReading r = read_probe(sites, p);
        EXPECT_EQ(r.site_index, static_cast<int>(i)) << f.fdi << " " << site_name(f.site);
        EXPECT_NEAR(r.depth_m, f.pd_m, 1e-9);
        EXPECT_NEAR(r.angle_rad, 0.0, 1e-6);
        EXPECT_TRUE(r.in_sulcus);
    }
}

Chart reference_chart() {
    const ChartLoad l = parse_chart(nlohmann::json::parse(R"({"format": "sulcus.chart/1", "teeth": {
        "11": {"sites": {"MB": {"pd_mm": 2}, "B": {"pd_mm": 1}, "DB": {"pd_mm": 2}, "ML": {"pd_mm": 3},
                         "L": {"pd_mm": 2}, "DL": {"pd_mm": 2.5}}},
        "36": {"sites": {"MB": {"pd_mm": 6, "gm_mm": -1, "bop": true}, "B": {"pd_mm": 7}, "DB": {"pd_mm": 6},
                         "ML": {"pd_mm": 5}, "L": {"pd_mm": 5}, "DL": {"pd_mm": 6}}}}})"),
                                    "reference.json");
    EXPECT_TRUE(l.ok());
    return l.chart;
}

TEST(ChartSession, RoundsToTheNearestWholeMillimetreHalvesUp) {
    ChartSession s(reference_chart());
    // The rule: nearest whole millimetre, a half rounds up.
    const std::pair<double, double> cases[] = {{2.49, 2}, {2.5, 3}, {2.51, 3}, {3.5, 4}, {0.49, 0},
                                               {0.5, 1}, {6.0, 6}, {5.999, 6}, {-0.4, 0}};
    for (const auto& [depth_mm, charted] : cases) {
        ASSERT_TRUE(s.record_depth(36, Site::B, depth_mm * mm));
        EXPECT_EQ(s.pd_mm(36, Site::B), charted) << depth_mm << " mm";
    }
    EXPECT_FALSE(s.record_depth(36, Site::B, NAN));
    EXPECT_EQ(s.pd_mm(36, Site::B), 0.0);  // unchanged
    EXPECT_FALSE(s.record_depth(46, Site::B, 3 * mm));  // no such tooth in the case
    EXPECT_FALSE(s.pd_mm(46, Site::B).has_value());
}

TEST(ChartSession, AttachmentLevelAndCounts) {
    ChartSession s(reference_chart());
    EXPECT_EQ(s.sites_total(), 12);
    EXPECT_EQ(s.sites_charted(), 0);
    EXPECT_TRUE(s.has_tooth(11));
    EXPECT_FALSE(s.has_tooth(21));

    // CAL = PD - GM; recession (negative GM) adds to it. Empty without a depth.
    EXPECT_TRUE(s.set_gm(36, Site::MB, -1.5));
    EXPECT_FALSE(s.cal_mm(36, Site::MB).has_value());
    ASSERT_TRUE(s.record_depth(36, Site::MB, 5.7 * mm));
    EXPECT_EQ(s.pd_mm(36, Site::MB), 6.0);
    EXPECT_EQ(s.cal_mm(36, Site::MB), 7.5);
    ASSERT_TRUE(s.record_depth(11, Site::B, 1.2 * mm));
    EXPECT_EQ(s.cal_mm(11, Site::B), 1.0);  // GM defaults to 0
    EXPECT_TRUE(s.set_gm(11, Site::B, 2.0));  // enlargement: a pseudo-pocket
    EXPECT_EQ(s.cal_mm(11, Site::B), -1.0);
    EXPECT_FALSE(s.set_gm(11, Site::B, 20.0));  // out of range: unchanged
    EXPECT_EQ(s.gm_mm(11, Site::B), 2.0);
    EXPECT_TRUE(s.set_bop(36, Site::MB, true));
    EXPECT_TRUE(s.bop(36, Site::MB));
    EXPECT_EQ(s.sites_charted(), 2);
    ASSERT_TRUE(s.record_depth(36, Site::MB, 6.2 * mm));  // probed again: replaced, not added
    EXPECT_EQ(s.sites_charted(), 2);
    s.clear(11, Site::B);
    EXPECT_EQ(s.sites_charted(), 1);
    EXPECT_EQ(s.gm_mm(11, Site::B), 0.0);
}

TEST(ChartSession, WritesAChartThatReadsBackAndComparesWithTheReference) {
    const Chart ref = reference_chart();
    ChartSession s(ref);
    ASSERT_TRUE(s.record_depth(36, Site::MB, 6.4 * mm));
    ASSERT_TRUE(s.set_gm(36, Site::MB, -1.0));
    ASSERT_TRUE(s.set_bop(36, Site::MB, true));
    ASSERT_TRUE(s.record_depth(36, Site::B, 5.5 * mm));
    ASSERT_TRUE(s.record_depth(11, Site::DL, 2.5 * mm));
    ASSERT_TRUE(s.set_bop(11, Site::L, true));  // bleeding without a depth: not a chart site

    const Chart c = s.to_chart();
    ASSERT_EQ(c.teeth.size(), 2u);  // every tooth of the case
    const SiteRecord& mb = *c.teeth.at(36).sites[std::size_t(Site::MB)];
    EXPECT_EQ(mb.pd_mm, 6.0);
    EXPECT_EQ(mb.gm_mm, -1.0);
    EXPECT_TRUE(mb.bop);
    EXPECT_FALSE(c.teeth.at(11).sites[std::size_t(Site::L)].has_value());
    const ChartLoad back = parse_chart(chart_to_json(c), "trainee.json");
    ASSERT_TRUE(back.ok()) << back.errors.front();
    EXPECT_EQ(back.chart, c);

    // Per site: trainee - reference where both are charted, every site of the case listed.
    const std::vector<SiteComparison> cmp = s.compare(ref);
    ASSERT_EQ(cmp.size(), 12u);
    auto of = [&](int fdi, Site site) {
        for (const SiteComparison& x : cmp)
            if (x.fdi == fdi && x.site == site) return x;
        ADD_FAILURE() << "no " << fdi << " " << site_name(site);
        return SiteComparison{};
    };
    EXPECT_EQ(of(36, Site::MB).difference_mm, 0.0);   // 6 vs 6
    EXPECT_EQ(of(36, Site::B).difference_mm, -1.0);   // 6 vs 7
    EXPECT_EQ(of(11, Site::DL).difference_mm, 0.5);   // 3 vs 2.5
    EXPECT_EQ(of(11, Site::DL).reference_pd_mm, 2.5);
    EXPECT_FALSE(of(11, Site::MB).difference_mm.has_value());  // not probed
    EXPECT_EQ(of(11, Site::MB).reference_pd_mm, 2.0);
    EXPECT_EQ(cmp.front().fdi, 11);
    EXPECT_EQ(cmp.front().site, Site::MB);
}

}  // namespace
}  // namespace sulcus
