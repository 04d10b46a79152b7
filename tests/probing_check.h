// The probing scenario check shared by the case tests: run a probing trajectory through the
// renderer, one step per servo tick, and for every pass check where the graphic tip is when the
// rendered force first reaches 0.25 N (the charted floor) and, where the pass pushes on, when it
// first reaches 0.5 N (the documented extra depth of the site's tissue further down).
#pragma once

#include "sulcus/content/case.h"
#include "sulcus/engine/renderer.h"
#include "sulcus/engine/scene_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sulcus {

struct PassToCheck {
    int fdi;
    Site site;
    double t_start, t_end;
    Vec3 floor_point, axis;  // where the tip end should rest at 0.25 N, and the tooth's long axis
    double extra_firm_m = -1.0;  // how much deeper at 0.5 N (documented per tissue); < 0: not checked
};

struct ProbingFigures {
    double worst_rest_m = 0.0;  // largest |tip - charted floor| at 0.25 N
    double worst_firm_m = 0.0;  // largest |extra depth at 0.5 N - documented|
    int firm_checked = 0;
};

inline ProbingFigures expect_probe_stops_at_floor(const Model& model, const std::vector<TrajectorySample>& samples,
                                                  const std::vector<PassToCheck>& passes, double rate_hz,
                                                  double tolerance, double firm_tolerance = 0.1e-3) {
    ProbingFigures fig;
    EXPECT_FALSE(samples.empty());
    if (samples.empty()) return fig;
    State state = make_state(samples.front().pose);
    size_t cursor = 0, pass = 0;
    bool reached = false, firm = false;
    double max_force = 0.0, worst = 0.0;
    const double dt = 1.0 / rate_hz;
    const long ticks = long(std::floor((samples.back().t - samples.front().t) * rate_hz)) + 1;
    for (long i = 0; i < ticks && pass < passes.size(); ++i) {
        const double t = samples.front().t + double(i) * dt;
        const Pose h = sample_trajectory(samples, t, cursor);
        const StepResult r = step(model, state, h);
        const bool finite_force = std::isfinite(r.force_N.x) && std::isfinite(r.force_N.y) && std::isfinite(r.force_N.z);
        EXPECT_TRUE(finite_force) << "t=" << t;
        if (!finite_force) return fig;
        const PassToCheck& p = passes[pass];
        const double f = glm::length(r.force_N);
        if (t < p.t_start) {
            EXPECT_LT(f, 1e-9) << "force between passes at t=" << t;
        }
        if (t >= p.t_start && !reached && f >= 0.25) {
            reached = true;
            const double err = glm::dot(r.graphic.position - p.floor_point, p.axis);
            const Vec3 lateral = (r.graphic.position - p.floor_point) - err * p.axis;
            std::printf("tooth %d %-2s: tip %+.3f mm from the charted floor, %.3f mm aside, %.3f N, %.2f along the axis\n",
                        p.fdi, site_name(p.site), err * 1e3, glm::length(lateral) * 1e3, f,
                        glm::dot(r.force_N, p.axis) / f);
            worst = std::max(worst, std::abs(err));
            EXPECT_LT(std::abs(err), tolerance) << "tooth " << p.fdi << " site " << site_name(p.site) << ": tip "
                                                << err * 1e3 << " mm from the charted floor";
            // The probe rests on the floor, not on a wall: the force points back up the axis.
            EXPECT_GT(glm::dot(r.force_N, p.axis) / f, 0.9) << p.fdi << site_name(p.site);
        }
        if (t >= p.t_start && p.extra_firm_m >= 0.0 && !firm && f >= 0.5) {
            firm = true;
            const double extra = -glm::dot(r.graphic.position - p.floor_point, p.axis);
            std::printf("tooth %d %-2s: at %.3f N the tip is %.3f mm past the charted floor (documented %.3f mm)\n",
                        p.fdi, site_name(p.site), f, extra * 1e3, p.extra_firm_m * 1e3);
            fig.worst_firm_m = std::max(fig.worst_firm_m, std::abs(extra - p.extra_firm_m));
            ++fig.firm_checked;
            EXPECT_LT(std::abs(extra - p.extra_firm_m), firm_tolerance)
                << "tooth " << p.fdi << " site " << site_name(p.site) << ": " << extra * 1e3
                << " mm past the floor at 0.5 N, documented " << p.extra_firm_m * 1e3 << " mm";
        }
        max_force = std::max(max_force, f);
        if (t >= p.t_end) {
            EXPECT_TRUE(reached) << "tooth " << p.fdi << " site " << site_name(p.site)
                                 << ": 0.25 N never reached (max " << max_force << " N)";
            if (p.extra_firm_m >= 0.0) {
                EXPECT_TRUE(firm) << "tooth " << p.fdi << " site " << site_name(p.site)
                                  << ": 0.5 N never reached (max " << max_force << " N)";
            }
            reached = false;
            firm = false;
            max_force = 0.0;
            ++pass;
        }
    }
    EXPECT_EQ(pass, passes.size()) << "trajectory ended before every pass was checked";
    fig.worst_rest_m = worst;
    std::printf("%zu passes, worst tip error %.3f mm at 0.25 N; %d checked at 0.5 N, worst %.3f mm off\n",
                passes.size(), worst * 1e3, fig.firm_checked, fig.worst_firm_m * 1e3);
    return fig;
}

}  // namespace sulcus
