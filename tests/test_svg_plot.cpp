// The SVG plot writer: a well-formed file holding every series, NaN points left out, nice
// ticks, and whole-or-nothing writing.
#include "sulcus/app/svg_plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <unistd.h>

namespace sulcus {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class SvgPlotTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("sulcus_svg_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

PlotFigure force_figure() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    PlotFigure fig;
    fig.title = "run <cube & cavity>";
    PlotPanel force;
    force.title = "force";
    force.x_label = "time (s)";
    force.y_label = "force (N)";
    PlotSeries fx{"fx", {}, {}, ""}, fy{"fy", {}, {}, ""};
    for (int i = 0; i < 200; ++i) {
        const double t = 0.001 * i;
        fx.x.push_back(t);
        fx.y.push_back(i == 50 ? nan : std::sin(40 * t));
        fy.x.push_back(t);
        fy.y.push_back(i == 120 ? std::numeric_limits<double>::infinity() : 0.5 * std::cos(40 * t));
    }
    force.series = {fx, fy};
    PlotPanel steps;
    steps.title = "step time";
    steps.x_label = "time (s)";
    steps.y_label = "step time (us)";
    steps.log_y = true;
    PlotSeries st{"step_us", {}, {}, "#000000"};
    for (int i = 0; i < 200; ++i) {
        st.x.push_back(0.001 * i);
        st.y.push_back(i == 10 ? 0.0 : 5.0 + 100.0 * (i % 17 == 0));  // 0 cannot be drawn on log axes
    }
    steps.series = {st};
    fig.panels = {force, steps};
    return fig;
}

TEST_F(SvgPlotTest, WritesWellFormedSvgWithEverySeries) {
    const fs::path p = dir_ / "plot.svg";
    std::string error;
    ASSERT_TRUE(write_svg(force_figure(), p.string(), &error)) << error;
    const std::string svg = read(p);
    EXPECT_EQ(svg.rfind("<svg", 0), 0u);
    EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
    for (const char* name : {">fx<", ">fy<", ">step_us<", ">force (N)<", ">time (s)<", ">step time (us)<"})
        EXPECT_NE(svg.find(name), std::string::npos) << name;
    // Text is escaped.
    EXPECT_NE(svg.find("run &lt;cube &amp; cavity&gt;"), std::string::npos);
    // Tags balance: every opened <g> and <text> is closed.
    auto count = [&](const std::string& s) {
        size_t n = 0;
        for (size_t at = svg.find(s); at != std::string::npos; at = svg.find(s, at + 1)) ++n;
        return n;
    };
    EXPECT_EQ(count("<g "), count("</g>"));
    EXPECT_EQ(count("<text "), count("</text>"));
    EXPECT_EQ(count("<svg "), 1u);
    // No temporary file is left behind.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(SvgPlotTest, NonFinitePointsAreSkippedNotWritten) {
    const std::string svg = render_svg(force_figure());
    // Look for printf's spellings of NaN and infinity ("dominant" happens to contain "nan").
    std::string text = svg;
    for (size_t at = text.find("dominant"); at != std::string::npos; at = text.find("dominant"))
        text.erase(at, 8);
    for (const char* bad : {"nan", "NaN", "NAN", "inf", "Inf", "INF"})
        EXPECT_EQ(text.find(bad), std::string::npos) << bad;
    // The NaN in fx breaks its line into two pieces: two move-to commands in its path.
    const size_t fx_path = svg.find("<path");
    ASSERT_NE(fx_path, std::string::npos);
    const std::string d = svg.substr(fx_path, svg.find("/>", fx_path) - fx_path);
    EXPECT_EQ(std::count(d.begin(), d.end(), 'M'), 2);
}

TEST_F(SvgPlotTest, ManyPointsAreDecimatedKeepingSpikes) {
    PlotFigure fig;
    PlotPanel p;
    p.title = "dense";
    PlotSeries s{"dense", {}, {}, ""};
    for (int i = 0; i < 200000; ++i) {
        s.x.push_back(i * 1e-5);
        s.y.push_back(i == 123457 ? 1000.0 : 1.0);
    }
    p.series = {s};
    fig.panels = {p};
    const std::string svg = render_svg(fig);
    EXPECT_LT(svg.size(), 200000u);  // far below one coordinate pair per point
    // The spike is the top of the y range, so its pixel row must be in the path.
    const size_t path_at = svg.find("<path");
    const std::string d = svg.substr(path_at, svg.find("/>", path_at) - path_at);
    // The highest point maps 5% of the plot height below the frame top at y = 34 px.
    const double frame_top = 34.0, frame_h = 280.0 - 34.0 - 50.0;
    char expected[32];
    std::snprintf(expected, sizeof expected, " %.2f", frame_top + frame_h * (0.05 / 1.1));
    EXPECT_NE(d.find(expected), std::string::npos) << expected;
}

TEST_F(SvgPlotTest, FailureLeavesNoFileAndSaysWhy) {
    std::string error;
    const fs::path p = dir_ / "no_such_folder" / "plot.svg";
    EXPECT_FALSE(write_svg(force_figure(), p.string(), &error));
    EXPECT_NE(error.find("plot.svg"), std::string::npos);
    EXPECT_FALSE(fs::exists(p));

    PlotFigure mismatched = force_figure();
    mismatched.panels[0].series[0].y.pop_back();
    EXPECT_FALSE(write_svg(mismatched, (dir_ / "m.svg").string(), &error));
    EXPECT_NE(error.find("fx"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir_ / "m.svg"));

    EXPECT_FALSE(write_svg(PlotFigure{}, (dir_ / "e.svg").string(), &error));
}

TEST(NiceTicks, AreRoundAndInsideTheRange) {
    // 0..1 in about 5 steps: spacing 0.2.
    const auto unit = nice_ticks(0.0, 1.0, 5);
    ASSERT_EQ(unit.size(), 6u);
    for (size_t i = 0; i < unit.size(); ++i) EXPECT_NEAR(unit[i], 0.2 * static_cast<double>(i), 1e-15);
    // -3.7..12.2 in about 6 steps: raw spacing 2.65 rounds to 2.
    const auto t = nice_ticks(-3.7, 12.2, 6);
    ASSERT_EQ(t.size(), 8u);
    EXPECT_EQ(t.front(), -2.0);
    EXPECT_EQ(t.back(), 12.0);
    for (double v : t) EXPECT_EQ(std::remainder(v, 2.0), 0.0) << v;
    EXPECT_TRUE(nice_ticks(NAN, 1.0).empty());
    EXPECT_TRUE(nice_ticks(2.0, 1.0).empty());
    EXPECT_EQ(nice_ticks(4.0, 4.0), std::vector<double>{4.0});
    const auto huge = nice_ticks(-1e308, 1e308);
    EXPECT_FALSE(huge.empty());
    for (double v : huge) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace sulcus
