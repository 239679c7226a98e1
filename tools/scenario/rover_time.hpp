// Where a run's rover time went (README, "Simulated time"): driving, imaging, VO, mapping
// and waiting, from a virtual-time log, whose events are stamped with the instant each
// message was published in.
//
//   driving  a mobility command (arc or turn) to its end (done, stopped or fault)
//   imaging  a capture request to its stereo frame
//   vo       a stereo frame to its VO update
//   mapping  a stereo frame to the first traversability map that holds it
//   planning the rover time charged for choosing each `goto ... avoid on` step (its step
//            report's utime_plan_start to utime_plan_end)
//   waiting  the rest of the sequence's span: none of the above (hazard replies, the
//            executor's own checks, waits on peers)
// With thinking while driving, a step chosen on an earlier pair's map is driven while the
// pair taken before it is mapped: that mapping overlaps driving (steps_thought_ahead counts
// those steps among all the step reports).
// VO and mapping run at once on the rover's computer, so their sum may exceed their share
// of the span; `busy_s` is the union of all of them.
#pragma once

#include <optional>
#include <string>

namespace rover::tools {

struct RoverTimeBreakdown {
  bool virtual_time = false;  // false: a real-clock log, whose stamps are wall times (no breakdown)
  double span_s = 0;          // first status of the sequence to its final status
  double driving_s = 0, imaging_s = 0, vo_s = 0, mapping_s = 0, planning_s = 0, busy_s = 0, waiting_s = 0;
  int steps = 0, steps_thought_ahead = 0;  // step reports, and those of steps chosen while driving
};

RoverTimeBreakdown BreakdownFromLog(const std::string& log_path);

}  // namespace rover::tools
