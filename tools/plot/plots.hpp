// The pictures of `./rover plot` (the paper's figures, Maimone, Cheng and Matthies 2007):
//   traverse.png  the on-board path coloured by how it was measured (blind, VO), the
//                 wheel-odometry-only path, the true path, keep-out zones, step ends, the
//                 abort point, a 1 m grid, equal axes (Figs. 1, 2, 5);
//   error.png     position error against distance travelled, wheel odometry only and the
//                 on-board estimate, with the 10 % design line (Fig. 4; needs truth);
//   slip.png      commanded against measured progress per step, the true one, slip and
//                 its limit.
// Each writes its data files and gnuplot script under `data_dir` and the PNG in `out_dir`.
#pragma once

#include "plot/drive_log.hpp"

#include <string>

namespace rover::plot {

struct PlotPlace {
  std::string out_dir;   // the PNGs
  std::string data_dir;  // data files, scripts and gnuplot logs (a folder of out_dir)
  std::string terminal = "pngcairo";
  std::string title;     // what the run was, for the titles
};

// What became of one picture: written, or the one line that says why not.
struct PlotOutcome {
  std::string file;      // the PNG
  bool written = false;
  bool failed = false;   // true: gnuplot failed (not merely nothing to show)
  std::string note;      // why it was not written, or what it shows
};

PlotOutcome WriteTraversePlot(const DriveLog& log, const PlotPlace& place);
PlotOutcome WriteErrorPlot(const DriveLog& log, const PlotPlace& place);
PlotOutcome WriteSlipPlot(const DriveLog& log, const PlotPlace& place);

// Grid and label spacing for a span of metres: 1 m grid lines, with labels every 1, 2, 5,
// 10... m so that about ten are shown. Past 150 m the grid follows the labels.
struct TicSpacing {
  double label_m = 1;
  int minor_per_label = 1;  // gnuplot mxtics: grid lines every label_m / minor_per_label
};
TicSpacing TicsFor(double span_m);

}  // namespace rover::plot
