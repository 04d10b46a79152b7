// Pictures of a headless run: force and torque against time, step time against time.
#pragma once

#include "sulcus/engine/runner.h"

#include <string>

namespace sulcus {

// Writes DIR/force.svg and DIR/step_time.svg.
bool write_run_plots(const RunResult& run, const std::string& dir, std::string* error);

}  // namespace sulcus
