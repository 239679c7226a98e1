// vo_steps/ of `./rover plot` (the paper's Fig. 3): for a few steps VO measured, the left
// image of the step's later frame with the features tracked from the earlier frame, the
// ones the motion estimate used (inliers) and the rest (outliers) in different colours.
//
// VO_UPDATE carries counts, not feature lists, so the tracks are computed again: the two
// STEREO_FRAMEs of the step's update are read from the log and run through the project's
// VO library (common/vo) with the given options and the same prior the visual_odometry
// process uses (the motion between the frames' on-board poses). RANSAC draws depend on how
// many pairs a VO instance has seen, so the recomputed counts can differ slightly from the
// logged ones; each picture's title gives both.
#pragma once

#include "plot/drive_log.hpp"
#include "plot/plots.hpp"

#include <string>

namespace rover::plot {

struct VoStepsOutcome {
  int written = 0;
  bool failed = false;  // a picture could not be made (gnuplot, a config, a frame)
  std::string note;     // one line: what was written, or why nothing was
};

// Writes up to `max_steps` pictures to place.out_dir/vo_steps/ (and a README.txt there
// saying what they are, or why there are none). `vo_config` holds the `vo:` section.
VoStepsOutcome WriteVoSteps(const DriveLog& log, const std::string& vo_config, int max_steps,
                            const PlotPlace& place);

}  // namespace rover::plot
