// A small, dependency-free SVG line-plot writer for run reports (force and torque against time,
// step time against time): a figure of stacked panels sharing one width, each with a title,
// axis labels (with units), nice tick values, optional log y axis and a legend.
#pragma once

#include <string>
#include <vector>

namespace sulcus {

struct PlotSeries {
    std::string name;       // shown in the legend
    std::vector<double> x;  // same length as y; NaN/infinite points are skipped (the line breaks)
    std::vector<double> y;
    std::string colour;     // SVG colour ("#1f77b4"); empty picks the next of a distinct palette
    bool markers = false;   // a dot at every point (for short series such as a parameter sweep)
};

struct PlotPanel {
    std::string title;
    std::string x_label;  // with unit, e.g. "time (s)"
    std::string y_label;  // with unit, e.g. "force (N)"
    bool log_y = false;   // log10 y axis; points with y <= 0 are skipped
    bool log_x = false;   // log10 x axis; points with x <= 0 are skipped
    std::vector<PlotSeries> series;
};

struct PlotFigure {
    std::string title;            // above the first panel; may be empty
    int width_px = 900;           // whole figure
    int panel_height_px = 280;    // each panel, including its title and x axis labels
    std::vector<PlotPanel> panels;
};

// Tick values for an axis over [lo, hi]: multiples of 1, 2 or 5 times a power of ten, about
// `target` of them, all inside [lo, hi]. Returns an empty list when the range is not finite.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

// The figure as SVG text.
std::string render_svg(const PlotFigure& figure);

// Writes the figure to `path` whole or not at all (a temporary file in the same folder, then a
// rename). On failure returns false and sets *error (if given) to one line "path: what".
bool write_svg(const PlotFigure& figure, const std::string& path, std::string* error);

}  // namespace sulcus
