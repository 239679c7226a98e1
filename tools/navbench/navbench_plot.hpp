// A picture of one navbench run with gnuplot (as ./rover plot draws): the rocks (over the
// step limit filled red, smaller ones from 0.2 m as grey rings), keep-out zones, the goal
// disc, the map's edge and the true path. Data and script stay beside it (DIR/ID/).
#pragma once

#include "navbench/navbench_run.hpp"

#include <string>

namespace rover::navbench {

// Writes `plots_dir`/ID.png; returns "" or a one-line reason it could not.
std::string PlotRun(const RunPlan& plan, const RunFigures& figures, const RunTrack& track,
                    const std::string& plots_dir);

}  // namespace rover::navbench
