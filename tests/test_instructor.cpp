// Instructor mode's save: an edited reference chart becomes a case chart and a starter lesson in a
// content root; refused names write nothing.
#include "sulcus/app/lesson_session.h"
#include "sulcus/content/chart.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string temp_root(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sulcus_test_instructor_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d.string();
}

sulcus::Chart bundled_chart(const std::string& name) {
    const sulcus::ChartLoad c =
        sulcus::load_chart(std::string(SULCUS_SOURCE_DIR) + "/content/assets/cases/" + name + "/chart.json");
    EXPECT_TRUE(c.ok()) << (c.errors.empty() ? "" : c.errors.front());
    return c.chart;
}

// Every file under a folder (recursively).
int files_under(const std::string& dir) {
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) ++n;
    return n;
}

}  // namespace

TEST(Instructor, SavesTheChartAndALessonThatLoadsBack) {
    const std::string root = temp_root("save");
    sulcus::Chart chart = bundled_chart("periodontitis_36");
    // The instructor deepens one pocket by half a millimetre and makes it bleed.
    auto& site = chart.teeth.at(36).sites[size_t(sulcus::Site::MB)];
    ASSERT_TRUE(site.has_value());
    site->pd_mm += 0.5;
    site->bop = true;

    std::string chart_path, lesson_path;
    const std::string err =
        sulcus::save_instructor_lesson(chart, "deep_36", "Deep pockets on 36", root, &chart_path, &lesson_path);
    ASSERT_EQ(err, "");
    EXPECT_EQ(fs::path(chart_path), fs::path(root) / "cases" / "deep_36" / "chart.json");
    EXPECT_EQ(fs::path(lesson_path), fs::path(root) / "lessons" / "deep_36.json");

    const sulcus::ChartLoad back = sulcus::load_chart(chart_path);
    ASSERT_TRUE(back.ok()) << back.errors.front();
    EXPECT_EQ(back.chart, chart) << "the chart read back equals the edited one";

    const sulcus::LessonLoad lesson = sulcus::load_lesson(lesson_path, root);
    ASSERT_TRUE(lesson.ok()) << lesson.errors.front();
    EXPECT_EQ(lesson.lesson.title, "Deep pockets on 36");
    EXPECT_EQ(lesson.lesson.chart, "cases/deep_36/chart.json");
    EXPECT_EQ(fs::path(lesson.chart_path), fs::weakly_canonical(chart_path));
    EXPECT_EQ(lesson.lesson.target_sites().size(), 6u) << "every site of 36 is a target";
    // The content root defaults to the lesson folder's parent: the same lesson loads without it.
    EXPECT_TRUE(sulcus::load_lesson(lesson_path).ok());
}

TEST(Instructor, BadNamesAreRefusedAndNothingIsWritten) {
    const std::string root = temp_root("bad");
    const sulcus::Chart chart = bundled_chart("healthy_11");
    const std::vector<std::string> names = {"",         "Healthy",    "a-b", "../x", "x/y", "dot.name", "with space",
                                            std::string(41, 'a'), "\xc3\xa9t\xc3\xa9"};
    for (const std::string& name : names) {
        std::string chart_path = "unset", lesson_path = "unset";
        const std::string err = sulcus::save_instructor_lesson(chart, name, "T", root, &chart_path, &lesson_path);
        EXPECT_NE(err, "") << "name \"" << name << "\" accepted";
        EXPECT_EQ(chart_path, "unset");
        EXPECT_EQ(lesson_path, "unset");
    }
    EXPECT_EQ(sulcus::save_instructor_lesson(chart, std::string(40, 'a'), "T", temp_root("forty"), nullptr, nullptr), "")
        << "40 characters are allowed";
    EXPECT_EQ(files_under(root), 0) << "a refused save wrote a file";
    EXPECT_TRUE(fs::is_empty(root)) << "a refused save made a folder";
}

TEST(Instructor, BundledCaseNamesAreRefused) {
    const std::string root = temp_root("bundled");
    const sulcus::Chart chart = bundled_chart("healthy_11");
    for (const std::string& name : std::vector<std::string>{"healthy_11", "periodontitis_36", "quadrant_44_47"}) {
        const std::string err = sulcus::save_instructor_lesson(chart, name, "T", root, nullptr, nullptr);
        EXPECT_NE(err.find("bundled"), std::string::npos) << name << ": " << err;
    }
    EXPECT_TRUE(fs::is_empty(root));
}

TEST(Instructor, AChartThatCannotBecomeACaseIsRefused) {
    const std::string root = temp_root("unbuildable");
    sulcus::Chart chart = bundled_chart("healthy_11");
    chart.teeth.at(11).sites[size_t(sulcus::Site::B)].reset();  // a case needs all six sites
    EXPECT_NE(sulcus::save_instructor_lesson(chart, "gap_11", "T", root, nullptr, nullptr), "");
    EXPECT_NE(sulcus::save_instructor_lesson(bundled_chart("healthy_11"), "no_title", "", root, nullptr, nullptr), "");
    EXPECT_TRUE(fs::is_empty(root));
}
