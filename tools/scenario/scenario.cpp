#include "scenario/scenario.hpp"

#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/keepout_convert.hpp"
#include "config/yaml_config.hpp"
#include "geometry/pose.hpp"
#include "hazards/keepout.hpp"
#include "report/json_writer.hpp"
#include "sequence/executor.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace rover::tools {

ScenarioSpec LoadScenario(const std::string& path) {
  const auto root = config::ConfigNode::LoadFile(path);
  root.CheckKeys({"name", "description", "world", "sequence", "deployment", "rover_config",
                  "start", "sim_rate", "timeout_s", "inject", "expect"});
  ScenarioSpec s;
  s.source = path;
  s.name = path;
  root.Get("name", s.name);
  root.Get("description", s.description);
  s.world = root.RequireString("world");
  s.sequence = root.RequireString("sequence");
  s.deployment = root.RequireString("deployment");
  root.Get("rover_config", s.rover_config);
  if (root.Has("start")) {
    const auto start = root["start"];
    start.CheckKeys({"x", "y", "yaw_deg"});
    start.Get("x", s.start_x);
    start.Get("y", s.start_y);
    start.Get("yaw_deg", s.start_yaw_deg, -360.0, 360.0);
  }
  root.Get("sim_rate", s.sim_rate, 1.0, 10000.0);
  root.Get("timeout_s", s.timeout_s, 1.0, 7200.0);
  if (root.Has("inject")) {
    const auto inject = root["inject"];
    inject.CheckKeys({"kill", "after_steps"});
    s.kill_process = inject.RequireString("kill");
    inject.Get("after_steps", s.kill_after_steps, 0, 100000);
  }
  if (root.Has("expect")) {
    const auto expect = root["expect"];
    expect.CheckKeys({"outcome", "abort_reason"});
    expect.GetEnum("outcome", s.expect_outcome, {"completed", "aborted", "rejected"});
    expect.Get("abort_reason", s.expect_abort_reason);
  }
  return s;
}

namespace {

Xyzrpy FromTruth(const rover_msgs::sim_truth_t& t) {
  Xyzrpy x;
  for (int i = 0; i < 3; ++i) x.v[i] = t.position[i];
  for (int i = 0; i < 3; ++i) x.v[3 + i] = t.rpy[i];
  return x;
}

Xyzrpy FromPose(const rover_msgs::pose_t& p) {
  const auto v = geometry::XyzRpyFromPose(bus::PoseFromMsg(p));
  Xyzrpy x;
  for (int i = 0; i < 6; ++i) x.v[i] = v[i];
  return x;
}

// The truth sample closest in time to `utime` (truth is published at a steady rate).
const rover_msgs::sim_truth_t* TruthAt(const std::vector<rover_msgs::sim_truth_t>& truth,
                                       std::int64_t utime) {
  if (truth.empty()) return nullptr;
  auto it = std::lower_bound(truth.begin(), truth.end(), utime,
                             [](const rover_msgs::sim_truth_t& t, std::int64_t u) {
                               return t.utime < u;
                             });
  if (it == truth.end()) return &truth.back();
  if (it != truth.begin() && (utime - (it - 1)->utime) < (it->utime - utime)) --it;
  return &*it;
}

}  // namespace

ScenarioSummary SummarizeLog(const std::string& log_path, const hazards::Footprint& footprint) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");

  std::vector<rover_msgs::sim_truth_t> truth;
  std::vector<rover_msgs::step_report_t> reports;
  std::optional<rover_msgs::pose_t> last_pose;
  std::optional<rover_msgs::sequence_status_t> final_status;
  std::map<int, std::pair<int, std::string>> command_text;  // index -> line, text
  int num_commands = 0;
  // Zones in force over time, for the truth clearance.
  std::vector<std::pair<std::int64_t, std::vector<hazards::KeepOutZone>>> zone_sets;

  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    const std::string& ch = ev->channel;
    if (ch == channels::kSimTruth) {
      rover_msgs::sim_truth_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) truth.push_back(m);
    } else if (ch == channels::kStepReport) {
      rover_msgs::step_report_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) reports.push_back(m);
    } else if (ch == channels::kPose) {
      rover_msgs::pose_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) last_pose = m;
    } else if (ch == channels::kKeepOutZones) {
      rover_msgs::keepout_zones_t m;
      if (m.decode(ev->data, 0, ev->datalen) < 0) continue;
      try {
        zone_sets.emplace_back(m.utime, bus::ZonesFromMsg(m));
      } catch (const std::invalid_argument&) {
        // An invalid set was never in force (the hazard monitor refused it).
      }
    } else if (ch == channels::kSequenceSubmit) {
      // The commands, with their lines, come from the submitted text itself.
      rover_msgs::sequence_submit_t m;
      if (m.decode(ev->data, 0, ev->datalen) < 0) continue;
      const auto parsed = sequence::ParseSequence(m.text, m.name);
      if (parsed.ok()) {
        for (std::size_t i = 0; i < parsed.sequence.commands.size(); ++i) {
          command_text[static_cast<int>(i)] = {parsed.sequence.commands[i].line,
                                               parsed.sequence.commands[i].text};
        }
      }
    } else if (ch == channels::kSequenceStatus) {
      rover_msgs::sequence_status_t m;
      if (m.decode(ev->data, 0, ev->datalen) < 0) continue;
      num_commands = std::max(num_commands, static_cast<int>(m.num_commands));
      if (m.state == rover_msgs::sequence_status_t::STATE_COMPLETED ||
          m.state == rover_msgs::sequence_status_t::STATE_ABORTED ||
          m.state == rover_msgs::sequence_status_t::STATE_REJECTED) {
        if (!final_status) final_status = m;
      }
    }
  }
  std::sort(truth.begin(), truth.end(),
            [](const auto& a, const auto& b) { return a.utime < b.utime; });

  ScenarioSummary s;
  if (final_status) {
    s.outcome = sequence::ToString(static_cast<sequence::SequenceState>(final_status->state));
    s.abort_reason = final_status->abort_reason;
    s.detail = final_status->detail;
    for (int i = 0; i < num_commands; ++i) {
      CommandOutcome c;
      c.index = i;
      if (auto it = command_text.find(i); it != command_text.end()) {
        c.line = it->second.first;
        c.text = it->second.second;
      }
      if (final_status->state == rover_msgs::sequence_status_t::STATE_COMPLETED) {
        c.outcome = "completed";
      } else if (final_status->state == rover_msgs::sequence_status_t::STATE_REJECTED) {
        c.outcome = "not_run";
      } else if (i < final_status->command_index) {
        c.outcome = "completed";
      } else if (i == final_status->command_index) {
        c.outcome = "aborted";
      } else {
        c.outcome = "skipped";
      }
      s.commands.push_back(c);
    }
  } else {
    s.outcome = "incomplete";
    s.detail = "no final sequence status in the log";
  }

  for (const auto& r : reports) {
    StepSummary st;
    st.command_index = r.command_index;
    st.step_index = r.step_index;
    st.commanded_distance_m = r.commanded_distance_m;
    st.commanded_turn_rad = r.commanded_turn_rad;
    st.estimated_distance_m = r.estimated_distance_m;
    st.estimated_turn_rad = r.estimated_turn_rad;
    st.estimated_slip_pct = r.slip_pct;
    st.vo_status = r.vo_status;
    const auto* before = TruthAt(truth, r.utime_before);
    const auto* after = TruthAt(truth, r.utime_after);
    if (before != nullptr && after != nullptr) {
      // Progress along the commanded direction: the heading at the step's start.
      const double yaw = before->rpy[2];
      const Eigen::Vector2d fwd(std::cos(yaw), std::sin(yaw));
      const Eigen::Vector2d d(after->position[0] - before->position[0],
                              after->position[1] - before->position[1]);
      st.true_distance_m = d.dot(fwd);
      st.true_turn_rad = geometry::WrapAngle(after->rpy[2] - before->rpy[2]);
      if (std::abs(st.commanded_distance_m) > 1e-6) {
        st.true_slip_pct = 100.0 * (1.0 - st.true_distance_m / st.commanded_distance_m);
      }
    }
    s.steps.push_back(st);
  }

  if (last_pose) s.final_estimate = FromPose(*last_pose);
  if (!truth.empty()) {
    s.final_truth = FromTruth(truth.back());
    s.distance_travelled_m = truth.back().odometer_m - truth.front().odometer_m;
    s.rover_time_s = (truth.back().utime - truth.front().utime) * 1e-6;
  }
  if (s.final_estimate && s.final_truth) {
    double e2 = 0;
    for (int i = 0; i < 3; ++i) {
      const double d = s.final_estimate->v[i] - s.final_truth->v[i];
      e2 += d * d;
    }
    s.position_error_m = std::sqrt(e2);
    s.position_error_pct =
        s.distance_travelled_m > 1e-6 ? 100.0 * s.position_error_m / s.distance_travelled_m : 0.0;
  }

  // Truth clearance: the closest the true footprint came to any zone in force.
  std::size_t set_index = 0;
  for (const auto& t : truth) {
    while (set_index + 1 < zone_sets.size() && zone_sets[set_index + 1].first <= t.utime) {
      ++set_index;
    }
    if (zone_sets.empty() || zone_sets[set_index].first > t.utime) continue;
    for (const auto& zone : zone_sets[set_index].second) {
      const double c = hazards::Clearance(zone, footprint, t.position[0], t.position[1], t.rpy[2]);
      if (!s.min_keepout_clearance_m || c < *s.min_keepout_clearance_m) {
        s.min_keepout_clearance_m = c;
      }
    }
  }
  return s;
}

namespace {

void WritePose(JsonWriter& j, const std::string& key, const std::optional<Xyzrpy>& p) {
  j.Key(key);
  if (!p) {
    j.Null();
    return;
  }
  static const char* names[] = {"x", "y", "z", "roll", "pitch", "yaw"};
  j.BeginObject();
  for (int i = 0; i < 6; ++i) j.Field(names[i], p->v[i]);
  j.EndObject();
}

}  // namespace

std::string SummaryJson(const ScenarioSummary& s) {
  JsonWriter j;
  j.BeginObject();
  j.Field("scenario", s.scenario);
  j.Field("outcome", s.outcome);
  j.Key("abort_reason");
  if (s.abort_reason.empty()) {
    j.Null();
  } else {
    j.Value(s.abort_reason);
  }
  j.Field("detail", s.detail);
  j.Key("commands").BeginArray();
  for (const auto& c : s.commands) {
    j.BeginObject();
    j.Field("index", c.index).Field("line", c.line).Field("text", c.text).Field("outcome", c.outcome);
    j.EndObject();
  }
  j.EndArray();
  j.Key("steps").BeginArray();
  for (const auto& st : s.steps) {
    j.BeginObject();
    j.Field("command_index", st.command_index).Field("step_index", st.step_index);
    j.Key("commanded").BeginObject();
    j.Field("distance_m", st.commanded_distance_m).Field("turn_rad", st.commanded_turn_rad);
    j.EndObject();
    j.Key("estimated").BeginObject();
    j.Field("distance_m", st.estimated_distance_m).Field("turn_rad", st.estimated_turn_rad);
    j.EndObject();
    j.Key("true").BeginObject();
    j.Field("distance_m", st.true_distance_m).Field("turn_rad", st.true_turn_rad);
    j.EndObject();
    j.Field("slip_pct", st.true_slip_pct);
    j.Field("estimated_slip_pct", st.estimated_slip_pct);
    j.Field("vo_status", st.vo_status);
    j.EndObject();
  }
  j.EndArray();
  WritePose(j, "final_estimate", s.final_estimate);
  WritePose(j, "final_truth", s.final_truth);
  j.Field("distance_travelled_m", s.distance_travelled_m);
  j.Field("position_error_m", s.position_error_m);
  j.Field("position_error_pct", s.position_error_pct);
  j.Key("min_keepout_clearance_m");
  if (s.min_keepout_clearance_m) {
    j.Value(*s.min_keepout_clearance_m);
  } else {
    j.Null();
  }
  j.Field("rover_time_s", s.rover_time_s);
  j.Field("wall_time_s", s.wall_time_s);
  j.Key("process_events").BeginArray();
  for (const auto& e : s.process_events) j.Value(e);
  j.EndArray();
  j.EndObject();
  return j.str();
}

std::string SummaryText(const ScenarioSummary& s) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(3);
  os << "scenario " << s.scenario << ": " << s.outcome;
  if (!s.abort_reason.empty()) os << " (" << s.abort_reason << ")";
  os << "\n";
  if (!s.detail.empty()) os << "  " << s.detail << "\n";
  for (const auto& c : s.commands) {
    os << "  command " << c.index + 1 << " (line " << c.line << ") " << std::left
       << std::setw(44) << c.text << " " << c.outcome << "\n";
  }
  os << "  steps: " << s.steps.size() << "\n";
  auto pose = [&os](const char* label, const std::optional<Xyzrpy>& p) {
    os << "  " << label;
    if (!p) {
      os << " (none)\n";
      return;
    }
    os << " x " << p->v[0] << " m, y " << p->v[1] << " m, z " << p->v[2] << " m, yaw "
       << p->v[5] * 180.0 / M_PI << " deg\n";
  };
  pose("final estimate:", s.final_estimate);
  pose("final truth:   ", s.final_truth);
  os << "  distance travelled (truth): " << s.distance_travelled_m << " m in "
     << std::setprecision(1) << s.rover_time_s << " s of rover time, " << s.wall_time_s
     << " s wall\n" << std::setprecision(3);
  os << "  position error: " << s.position_error_m << " m (" << std::setprecision(2)
     << s.position_error_pct << " % of distance)\n" << std::setprecision(3);
  if (s.min_keepout_clearance_m) {
    os << "  closest approach to a keep-out zone (truth): " << *s.min_keepout_clearance_m << " m\n";
  }
  for (const auto& e : s.process_events) os << "  " << e << "\n";
  return os.str();
}

}  // namespace rover::tools
