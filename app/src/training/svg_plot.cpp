// SVG line plots written by hand: a few hundred lines instead of a plotting dependency.
#include "sulcus/app/svg_plot.h"
#include "sulcus/app/text.h"
#include "sulcus/app/write_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>

#include <fcntl.h>
#include <unistd.h>

namespace sulcus {
namespace {

// Distinct colours (the Tableau 10 palette), chosen to stay apart for colour-blind readers too.
constexpr const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

// Layout, in pixels.
constexpr double kLeft = 78.0;          // y tick labels and y axis label
constexpr double kLegendWidth = 190.0;  // legend column right of the plot
constexpr double kRight = 12.0;
constexpr double kFigureTitle = 34.0;
constexpr double kPanelTop = 34.0;      // panel title above the plot area
constexpr double kPanelBottom = 50.0;   // x tick labels and x axis label below it
constexpr double kLegendRow = 18.0;

std::string px(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    return buf;
}

// A tick label: as few digits as the tick spacing needs, no "-0".
std::string tick_label(double v, double step) {
    if (std::abs(v) < std::abs(step) * 1e-9) v = 0.0;
    char buf[48];
    const double big = std::abs(v);
    if (big >= 1e6 || step < 1e-4) {
        std::snprintf(buf, sizeof buf, "%.3g", v);
    } else {
        const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
        std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    }
    return buf;
}

std::string decade_label(int e) {
    if (e >= -3 && e <= 4) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.*f", std::max(0, -e), std::pow(10.0, e));
        return buf;
    }
    return "1e" + std::to_string(e);
}

struct Range {
    double lo = 0.0, hi = 1.0;
};

// Widens an empty or single-valued range so that it can be drawn.
Range widen(double lo, double hi, bool any) {
    if (!any) return {0.0, 1.0};
    if (hi > lo) return {lo, hi};
    const double pad = lo == 0.0 ? 1.0 : std::abs(lo) * 0.1;
    return {lo - pad, hi + pad};
}

bool usable_point(double x, double y, bool log_y, bool log_x = false) {
    return std::isfinite(x) && std::isfinite(y) && (!log_y || y > 0.0) && (!log_x || x > 0.0);
}

struct Mapper {
    double x0, x1, y0, y1;  // plot area in pixels (y0 top)
    Range xr, yr;           // data ranges (in log10 units on a log axis)
    bool log_y;
    bool log_x = false;
    double sx(double x) const {
        const double v = log_x ? std::log10(x) : x;
        return x0 + (v - xr.lo) / (xr.hi - xr.lo) * (x1 - x0);
    }
    double sy(double y) const {
        const double v = log_y ? std::log10(y) : y;
        return y1 - (v - yr.lo) / (yr.hi - yr.lo) * (y1 - y0);
    }
};

// One series as an SVG path. Non-finite points break the line. Where there are many more
// points than pixels, each pixel column keeps its first, lowest, highest and last point, which
// draws the same picture (spikes included) at a fraction of the size.
std::string series_path(const PlotSeries& s, const Mapper& m) {
    const size_t n = std::min(s.x.size(), s.y.size());
    const bool decimate = n > static_cast<size_t>(4.0 * (m.x1 - m.x0));
    std::string d;
    bool pen_down = false;
    auto emit = [&](double X, double Y) {
        d += pen_down ? " L" : (d.empty() ? "M" : " M");
        d += px(X) + " " + px(Y);
        pen_down = true;
    };

    // Pixel-column bucket: indices (in order) of first, min, max, last.
    long column = 0;
    bool open = false;
    size_t first = 0, lowest = 0, highest = 0, last = 0;
    auto flush = [&] {
        if (!open) return;
        size_t idx[4] = {first, lowest, highest, last};
        std::sort(idx, idx + 4);
        for (int k = 0; k < 4; ++k)
            if (k == 0 || idx[k] != idx[k - 1]) emit(m.sx(s.x[idx[k]]), m.sy(s.y[idx[k]]));
        open = false;
    };

    for (size_t i = 0; i < n; ++i) {
        if (!usable_point(s.x[i], s.y[i], m.log_y, m.log_x)) {
            flush();
            pen_down = false;
            continue;
        }
        const double X = m.sx(s.x[i]), Y = m.sy(s.y[i]);
        if (!decimate) {
            emit(X, Y);
            continue;
        }
        const long c = static_cast<long>(std::floor(X));
        if (open && c == column) {
            if (Y > m.sy(s.y[lowest])) lowest = i;  // screen y grows downward
            if (Y < m.sy(s.y[highest])) highest = i;
            last = i;
        } else {
            flush();
            open = true;
            column = c;
            first = lowest = highest = last = i;
        }
    }
    flush();
    return d;
}

void render_panel(std::string& out, const PlotPanel& panel, double top, double width, double height) {
    const bool log_y = panel.log_y, log_x = panel.log_x;
    // Data ranges over every usable point.
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    bool any = false;
    for (const PlotSeries& s : panel.series) {
        const size_t n = std::min(s.x.size(), s.y.size());
        for (size_t i = 0; i < n; ++i) {
            if (!usable_point(s.x[i], s.y[i], log_y, log_x)) continue;
            const double y = log_y ? std::log10(s.y[i]) : s.y[i];
            const double x = log_x ? std::log10(s.x[i]) : s.x[i];
            xlo = std::min(xlo, x);
            xhi = std::max(xhi, x);
            ylo = std::min(ylo, y);
            yhi = std::max(yhi, y);
            any = true;
        }
    }
    Mapper m;
    m.log_y = log_y;
    m.log_x = log_x;
    m.x0 = kLeft;
    m.x1 = width - kLegendWidth - kRight;
    m.y0 = top + kPanelTop;
    m.y1 = top + height - kPanelBottom;
    if (log_x) {
        m.xr = any ? Range{std::floor(xlo), std::ceil(xhi)} : Range{0.0, 1.0};
        if (m.xr.hi <= m.xr.lo) m.xr.hi = m.xr.lo + 1.0;
    } else {
        m.xr = widen(xlo, xhi, any);
    }
    if (log_y) {
        m.yr = any ? Range{std::floor(ylo), std::ceil(yhi)} : Range{0.0, 1.0};
        if (m.yr.hi <= m.yr.lo) m.yr.hi = m.yr.lo + 1.0;
    } else {
        m.yr = widen(ylo, yhi, any);
        const double pad = 0.05 * (m.yr.hi - m.yr.lo);  // keep lines off the frame
        m.yr = {m.yr.lo - pad, m.yr.hi + pad};
    }

    const std::string cx = px(0.5 * (m.x0 + m.x1));
    out += "<g class=\"panel\">\n";
    out += "<text x=\"" + cx + "\" y=\"" + px(top + 22) + "\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">" +
           xml_escape(panel.title) + "</text>\n";

    // Grid and tick labels.
    if (log_x) {
        const int lo = static_cast<int>(m.xr.lo), hi = static_cast<int>(m.xr.hi);
        const int every = std::max(1, (hi - lo + 7) / 8);
        for (int e = lo; e <= hi; e += every) {
            const std::string X = px(m.sx(std::pow(10.0, e)));
            out += "<line x1=\"" + X + "\" y1=\"" + px(m.y0) + "\" x2=\"" + X + "\" y2=\"" + px(m.y1) +
                   "\" stroke=\"#e4e4e4\"/>\n";
            out += "<text x=\"" + X + "\" y=\"" + px(m.y1 + 16) + "\" text-anchor=\"middle\">" +
                   xml_escape(decade_label(e)) + "</text>\n";
        }
    } else {
        const std::vector<double> xt = nice_ticks(m.xr.lo, m.xr.hi);
        const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
        for (const double v : xt) {
            const std::string X = px(m.sx(v));
            out += "<line x1=\"" + X + "\" y1=\"" + px(m.y0) + "\" x2=\"" + X + "\" y2=\"" + px(m.y1) +
                   "\" stroke=\"#e4e4e4\"/>\n";
            out += "<text x=\"" + X + "\" y=\"" + px(m.y1 + 16) + "\" text-anchor=\"middle\">" +
                   xml_escape(tick_label(v, xstep)) + "</text>\n";
        }
    }
    if (log_y) {
        const int lo = static_cast<int>(m.yr.lo), hi = static_cast<int>(m.yr.hi);
        const int every = std::max(1, (hi - lo + 7) / 8);  // at most ~8 labelled decades
        for (int e = lo; e <= hi; e += every) {
            const std::string Y = px(m.sy(std::pow(10.0, e)));
            out += "<line x1=\"" + px(m.x0) + "\" y1=\"" + Y + "\" x2=\"" + px(m.x1) + "\" y2=\"" + Y +
                   "\" stroke=\"#e4e4e4\"/>\n";
            out += "<text x=\"" + px(m.x0 - 6) + "\" y=\"" + Y + "\" text-anchor=\"end\" dominant-baseline=\"middle\">" +
                   xml_escape(decade_label(e)) + "</text>\n";
        }
    } else {
        const std::vector<double> yt = nice_ticks(m.yr.lo, m.yr.hi, 5);
        const double ystep = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
        for (const double v : yt) {
            const std::string Y = px(m.sy(v));
            out += "<line x1=\"" + px(m.x0) + "\" y1=\"" + Y + "\" x2=\"" + px(m.x1) + "\" y2=\"" + Y +
                   "\" stroke=\"#e4e4e4\"/>\n";
            out += "<text x=\"" + px(m.x0 - 6) + "\" y=\"" + Y + "\" text-anchor=\"end\" dominant-baseline=\"middle\">" +
                   xml_escape(tick_label(v, ystep)) + "</text>\n";
        }
    }

    // Frame and axis labels.
    out += "<rect x=\"" + px(m.x0) + "\" y=\"" + px(m.y0) + "\" width=\"" + px(m.x1 - m.x0) + "\" height=\"" +
           px(m.y1 - m.y0) + "\" fill=\"none\" stroke=\"#444\"/>\n";
    out += "<text x=\"" + cx + "\" y=\"" + px(m.y1 + 38) + "\" text-anchor=\"middle\">" + xml_escape(panel.x_label) +
           "</text>\n";
    const std::string ly = px(0.5 * (m.y0 + m.y1));
    out += "<text x=\"18\" y=\"" + ly + "\" text-anchor=\"middle\" transform=\"rotate(-90 18 " + ly + ")\">" +
           xml_escape(panel.y_label) + "</text>\n";
    if (!any)
        out += "<text x=\"" + cx + "\" y=\"" + ly + "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n";

    // Series. No clipping is needed: the axis ranges hold every drawn point (and simple SVG
    // renderers ignore clip paths).
    for (size_t k = 0; k < panel.series.size(); ++k) {
        const PlotSeries& s = panel.series[k];
        const std::string colour = xml_escape(s.colour.empty() ? kPalette[k % kPaletteSize] : s.colour);
        const std::string d = series_path(s, m);
        if (!d.empty())
            out += "<path d=\"" + d + "\" fill=\"none\" stroke=\"" + colour +
                   "\" stroke-width=\"1.3\" stroke-linejoin=\"round\"/>\n";
        if (s.markers) {
            const size_t n = std::min(s.x.size(), s.y.size());
            for (size_t i = 0; i < n; ++i)
                if (usable_point(s.x[i], s.y[i], m.log_y, m.log_x))
                    out += "<circle cx=\"" + px(m.sx(s.x[i])) + "\" cy=\"" + px(m.sy(s.y[i])) + "\" r=\"3\" fill=\"" +
                           colour + "\"/>\n";
        }
        // Legend entry.
        const double y = m.y0 + 10 + kLegendRow * static_cast<double>(k);
        const double lx = m.x1 + 14;
        out += "<line x1=\"" + px(lx) + "\" y1=\"" + px(y) + "\" x2=\"" + px(lx + 24) + "\" y2=\"" + px(y) +
               "\" stroke=\"" + colour + "\" stroke-width=\"2.5\"/>\n";
        out += "<text x=\"" + px(lx + 30) + "\" y=\"" + px(y) + "\" dominant-baseline=\"middle\">" +
               xml_escape(s.name) + "</text>\n";
    }
    out += "</g>\n";
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
    std::vector<double> ticks;
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return ticks;
    if (lo == hi) return {lo};
    target = std::max(target, 1);
    const double raw = (hi / target - lo / target);  // spacing; no overflow for huge ranges
    if (!(raw > 0.0) || !std::isfinite(raw)) return ticks;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double norm = raw / mag;
    const double step = (norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0) * mag;
    const double first = std::ceil(lo / step - 1e-9);
    const double last = std::floor(hi / step + 1e-9);
    for (double i = first; i <= last && ticks.size() < 100; i += 1.0) ticks.push_back(i * step);
    return ticks;
}

std::string render_svg(const PlotFigure& figure) {
    const double width = std::max(figure.width_px, 320);
    const double panel_h = std::max(figure.panel_height_px, 140);
    const double title_h = figure.title.empty() ? 0.0 : kFigureTitle;
    const double height = title_h + panel_h * static_cast<double>(std::max<size_t>(figure.panels.size(), 1));

    std::string out;
    out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + px(width) + "\" height=\"" + px(height) +
           "\" viewBox=\"0 0 " + px(width) + " " + px(height) +
           "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
    out += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    if (!figure.title.empty())
        out += "<text x=\"" + px(width / 2) + "\" y=\"24\" text-anchor=\"middle\" font-size=\"17\" font-weight=\"bold\">" +
               xml_escape(figure.title) + "</text>\n";
    for (size_t i = 0; i < figure.panels.size(); ++i)
        render_panel(out, figure.panels[i], title_h + panel_h * static_cast<double>(i), width,
                     panel_h);
    out += "</svg>\n";
    return out;
}

bool write_svg(const PlotFigure& figure, const std::string& path, std::string* error) {
    auto fail = [&](const std::string& what) {
        if (error) {
            *error = path + ": " + what;
            for (char& c : *error)  // one line, whatever the titles hold
                if (static_cast<unsigned char>(c) < 0x20) c = ' ';
        }
        return false;
    };
    if (figure.panels.empty()) return fail("figure has no panels");
    for (const PlotPanel& p : figure.panels)
        for (const PlotSeries& s : p.series)
            if (s.x.size() != s.y.size())
                return fail("panel '" + p.title + "', series '" + s.name + "': " + std::to_string(s.x.size()) +
                            " x values but " + std::to_string(s.y.size()) + " y values");

    const std::string err = write_file_atomic(path, render_svg(figure));
    if (!err.empty()) {
        if (error) *error = err;
        return false;
    }
    return true;
}

}  // namespace sulcus
