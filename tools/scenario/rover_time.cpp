#include "scenario/rover_time.hpp"

#include "bus/channels.hpp"
#include "logcheck/log_reader.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <algorithm>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace rover::tools {

namespace {

using Interval = std::pair<std::int64_t, std::int64_t>;

double Seconds(const std::vector<Interval>& v) {
  double s = 0;
  for (const auto& [a, b] : v) s += (b - a) * 1e-6;
  return s;
}

// The length of the union of `v` clipped to [from, to].
double UnionSeconds(std::vector<Interval> v, std::int64_t from, std::int64_t to) {
  std::sort(v.begin(), v.end());
  double s = 0;
  std::int64_t end = from;
  for (auto [a, b] : v) {
    a = std::max({a, from, end});
    b = std::min(b, to);
    if (b > a) {
      s += (b - a) * 1e-6;
      end = b;
    }
  }
  return s;
}

}  // namespace

RoverTimeBreakdown BreakdownFromLog(const std::string& log_path) {
  RoverTimeBreakdown r;
  rover::logcheck::LogReader log(log_path);
  if (!log.good()) return r;
  std::map<std::int64_t, std::int64_t> requests, frames;  // frame id -> instant
  std::map<std::int64_t, std::int64_t> commands;          // command id -> instant
  std::vector<Interval> driving, imaging, vo, mapping, planning;
  std::vector<std::int64_t> frames_unmapped;
  std::int64_t first_status = -1, final_status = -1;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    const std::string& ch = e->channel;
    const std::int64_t t = e->timestamp;
    if (ch == channels::kClock) {
      rover_msgs::rover_clock_t m;
      if (m.decode(e->data, 0, e->datalen) >= 0 && m.mode == rover_msgs::rover_clock_t::MODE_VIRTUAL) r.virtual_time = true;
    } else if (ch == channels::kCaptureRequest) {
      rover_msgs::capture_request_t m;
      if (m.decode(e->data, 0, e->datalen) >= 0) requests[m.frame_id] = t;
    } else if (ch == channels::kStereoFrame) {
      // (A HAZCAM_FRAME of the same request is published just before: its imaging time is
      // inside this request-to-STEREO_FRAME interval.)
      rover_msgs::stereo_frame_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      frames[m.frame_id] = t;
      if (auto it = requests.find(m.frame_id); it != requests.end()) imaging.emplace_back(it->second, t);
      if (m.purpose != "science") frames_unmapped.push_back(m.frame_id);
    } else if (ch == channels::kVoUpdate) {
      rover_msgs::vo_update_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      if (auto it = frames.find(m.to_frame_id); it != frames.end()) vo.emplace_back(it->second, t);
    } else if (ch == channels::kTraversabilityMap) {
      rover_msgs::traversability_map_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      std::erase_if(frames_unmapped, [&](std::int64_t id) {
        if (id > m.last_frame_id) return false;
        if (auto it = frames.find(id); it != frames.end()) mapping.emplace_back(it->second, t);
        return true;
      });
    } else if (ch == channels::kMobilityCommand) {
      rover_msgs::mobility_command_t m;
      if (m.decode(e->data, 0, e->datalen) >= 0 && m.type != rover_msgs::mobility_command_t::TYPE_STOP)
        commands[m.command_id] = t;
    } else if (ch == channels::kMobilityStatus) {
      rover_msgs::mobility_status_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      if (m.state != rover_msgs::mobility_status_t::STATE_DONE && m.state != rover_msgs::mobility_status_t::STATE_STOPPED &&
          m.state != rover_msgs::mobility_status_t::STATE_FAULT)
        continue;
      if (auto it = commands.find(m.command_id); it != commands.end()) {
        driving.emplace_back(it->second, t);
        commands.erase(it);
      }
    } else if (ch == channels::kStepReport) {
      rover_msgs::step_report_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      ++r.steps;
      if (m.thought_ahead) ++r.steps_thought_ahead;
      if (m.utime_plan_end > m.utime_plan_start && m.utime_plan_start > 0)
        planning.emplace_back(m.utime_plan_start, m.utime_plan_end);
    } else if (ch == channels::kSequenceStatus) {
      rover_msgs::sequence_status_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      if (first_status < 0) first_status = t;
      const bool final = m.state == rover_msgs::sequence_status_t::STATE_COMPLETED ||
                         m.state == rover_msgs::sequence_status_t::STATE_ABORTED ||
                         m.state == rover_msgs::sequence_status_t::STATE_REJECTED;
      if (final && final_status < 0) final_status = t;
    }
  }
  if (!r.virtual_time || first_status < 0 || final_status < first_status) return r;
  r.span_s = (final_status - first_status) * 1e-6;
  r.driving_s = Seconds(driving);
  r.imaging_s = Seconds(imaging);
  r.vo_s = Seconds(vo);
  r.mapping_s = Seconds(mapping);
  r.planning_s = Seconds(planning);
  std::vector<Interval> all = driving;
  for (const auto* v : {&imaging, &vo, &mapping, &planning}) all.insert(all.end(), v->begin(), v->end());
  r.busy_s = UnionSeconds(all, first_status, final_status);
  r.waiting_s = std::max(0.0, r.span_s - r.busy_s);
  return r;
}

}  // namespace rover::tools
