// Pictures of a headless run (sulcus-cli run --plot).
#include "sulcus/app/run_plots.h"

#include "sulcus/app/svg_plot.h"

#include <filesystem>

namespace sulcus {

namespace {

PlotSeries series(const std::string& name, const std::vector<double>& x, std::vector<double> y) {
    PlotSeries s;
    s.name = name;
    s.x = x;
    s.y = std::move(y);
    return s;
}

}  // namespace

bool write_run_plots(const RunResult& run, const std::string& dir, std::string* error) {
    const size_t n = run.ticks.size();
    std::vector<double> t(n), fx(n), fy(n), fz(n), fm(n), tx(n), ty(n), tz(n), us(n), solve(n), detect(n),
        gather(n), pen(n);
    for (size_t i = 0; i < n; ++i) {
        const TickRecord& r = run.ticks[i];
        t[i] = r.t;
        fx[i] = r.force_N.x;
        fy[i] = r.force_N.y;
        fz[i] = r.force_N.z;
        fm[i] = glm::length(r.force_N);
        tx[i] = r.torque_Nm.x * 1e3;
        ty[i] = r.torque_Nm.y * 1e3;
        tz[i] = r.torque_Nm.z * 1e3;
        us[i] = r.step_us;
        detect[i] = r.stats.times.detect_us;
        gather[i] = r.stats.times.gather_us;
        solve[i] = r.stats.times.solve_us;
        pen[i] = r.penetration_m * 1e9;
    }
    PlotFigure force;
    force.title = run.summary.scene + ": force and torque (eq. 4) against time";
    PlotPanel fp;
    fp.title = "force";
    fp.x_label = "time (s)";
    fp.y_label = "force (N)";
    fp.series = {series("Fx", t, fx), series("Fy", t, fy), series("Fz", t, fz), series("|F|", t, fm)};
    PlotPanel tp;
    tp.title = "torque";
    tp.x_label = "time (s)";
    tp.y_label = "torque (mN m)";
    tp.series = {series("Tx", t, tx), series("Ty", t, ty), series("Tz", t, tz)};
    PlotPanel pp;
    pp.title = "penetration of the graphic tool (exact check)";
    pp.x_label = "time (s)";
    pp.y_label = "penetration (nm)";
    pp.series = {series("penetration", t, pen)};
    force.panels = {fp, tp, pp};

    PlotFigure timing;
    timing.title = run.summary.scene + ": step time against time";
    PlotPanel sp;
    sp.title = "wall time per servo step and its stages";
    sp.x_label = "time (s)";
    sp.y_label = "time (us)";
    sp.log_y = true;
    sp.series = {series("step", t, us), series("detect", t, detect), series("gather", t, gather),
                 series("solve", t, solve)};
    timing.panels = {sp};

    const std::filesystem::path d(dir);
    return write_svg(force, (d / "force.svg").string(), error) &&
           write_svg(timing, (d / "step_time.svg").string(), error);
}

}  // namespace sulcus
