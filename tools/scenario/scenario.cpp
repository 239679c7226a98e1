#include "scenario/scenario.hpp"

#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/keepout_convert.hpp"
#include "config/yaml_config.hpp"
#include "geometry/pose.hpp"
#include "hazards/keepout.hpp"
#include "logcheck/log_reader.hpp"
#include "report/json_writer.hpp"
#include "sequence/executor.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

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
  root.CheckKeys({"name", "description", "world", "sequence", "sequence_name", "then_sequences", "deployment", "rover_config",
                  "start", "sim_rate", "timeout_s", "inject", "expect", "seeds", "dragged_wheel", "pause", "then_idle_s",
                  "overrides", "world_overrides", "campaign"});
  ScenarioSpec s;
  s.source = path;
  s.name = path;
  root.Get("name", s.name);
  root.Get("description", s.description);
  s.world = root.RequireString("world");
  s.sequence = root.RequireString("sequence");
  s.sequence_name = s.sequence;
  if (root.Has("sequence_name")) {
    s.sequence_name = root.RequireString("sequence_name");
    if (s.sequence_name.empty()) root["sequence_name"].Fail("expected a name, not an empty string");
  }
  if (root.Has("then_sequences")) {
    const auto list = root["then_sequences"];
    if (!list.IsSequence()) list.Fail("expected a list of sequence files");
    for (std::size_t i = 0; i < list.size(); ++i) s.then_sequences.push_back(list.at(i).AsString());
  }
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
  if (root.Has("pause")) {
    const auto pause = root["pause"];
    pause.CheckKeys({"after_steps", "for_s"});
    pause.Get("after_steps", s.pause_after_steps, 1, 100000);
    pause.Get("for_s", s.pause_for_s, 0.0, 1e6);
    if (!pause.Has("after_steps")) pause.Fail("expected after_steps: N (the pause comes after N steps)");
  }
  root.Get("then_idle_s", s.then_idle_s, 0.0, 1e6);
  if (s.then_idle_s > 0 && s.then_sequences.empty()) {
    root["then_idle_s"].Fail("expected then_sequences (the idle comes before each of them)");
  }
  if (root.Has("inject")) {
    const auto inject = root["inject"];
    inject.CheckKeys({"kill", "after_steps"});
    s.kill_process = inject.RequireString("kill");
    inject.Get("after_steps", s.kill_after_steps, 0, 100000);
  }
  // Seeds and the dragged wheel are overrides by another name; the maps come after them.
  if (root.Has("seeds")) {
    const auto seeds = root["seeds"];
    seeds.CheckKeys({"world", "mobility", "render"});
    std::uint64_t seed = 0;
    if (seeds.Has("world")) {
      seeds.Get("world", seed);
      s.world_overrides.push_back({"seed", YAML::Node(seed)});
    }
    if (seeds.Has("mobility")) {
      seeds.Get("mobility", seed);
      s.overrides.push_back({"mobility.seed", YAML::Node(seed)});
    }
    if (seeds.Has("render")) {
      seeds.Get("render", seed);
      s.overrides.push_back({"capture.render.noise_seed", YAML::Node(seed)});
    }
  }
  if (root.Has("campaign")) {
    const auto c = root["campaign"];
    c.CheckKeys({"start_jitter_m", "yaw_jitter_deg", "slope_jitter_deg"});
    c.Get("start_jitter_m", s.campaign_start_jitter_m, 0.0, 10.0);
    c.Get("yaw_jitter_deg", s.campaign_yaw_jitter_deg, 0.0, 180.0);
    c.Get("slope_jitter_deg", s.campaign_slope_jitter_deg, 0.0, 10.0);
  }
  if (root.Has("dragged_wheel")) {
    s.overrides.push_back({"mobility.slip.dragged_wheel.wheel", YAML::Node(root.RequireString("dragged_wheel"))});
  }
  for (auto& o : LoadOverrides(root["overrides"])) s.overrides.push_back(std::move(o));
  for (auto& o : LoadOverrides(root["world_overrides"])) s.world_overrides.push_back(std::move(o));
  if (root.Has("expect")) {
    const auto expect = root["expect"];
    expect.CheckKeys({"outcome", "abort_reason", "min_clearance_m", "max_position_error_pct",
                      "max_false_updates", "horizontal_nees", "heading_nees", "max_final_3sigma_m"});
    expect.GetEnum("outcome", s.expect_outcome, {"completed", "aborted", "rejected"});
    // One reason, or a list of acceptable ones.
    const auto reason = expect["abort_reason"];
    if (reason.IsSequence()) {
      for (std::size_t i = 0; i < reason.size(); ++i) s.expect_abort_reasons.push_back(reason.at(i).AsString());
      if (s.expect_abort_reasons.empty()) reason.Fail("expected an abort reason or a non-empty list of them");
    } else if (!reason.IsNull()) {
      s.expect_abort_reasons.push_back(reason.AsString());
    }
    for (const auto& r : s.expect_abort_reasons) {
      s.expect_abort_reason += (s.expect_abort_reason.empty() ? "" : "|") + r;
    }
    if (expect.Has("min_clearance_m")) {
      double v = 0;
      expect.Get("min_clearance_m", v);
      s.expect_min_clearance_m = v;
    }
    if (expect.Has("max_position_error_pct")) {
      double v = 0;
      expect.Get("max_position_error_pct", v, 0.0);
      s.expect_max_position_error_pct = v;
    }
    if (expect.Has("max_false_updates")) {
      int v = 0;
      expect.Get("max_false_updates", v, 0);
      s.expect_max_false_updates = v;
    }
    // A NEES mean's range: [min, max].
    auto range = [&expect](const char* key) -> std::optional<std::pair<double, double>> {
      if (!expect.Has(key)) return std::nullopt;
      const auto r = expect[key];
      if (!r.IsSequence() || r.size() != 2) r.Fail("expected [min, max], two numbers");
      const double lo = r.at(0).AsDouble(), hi = r.at(1).AsDouble();
      if (!(lo >= 0.0 && hi >= lo)) r.Fail("expected 0 <= min <= max");
      return std::make_pair(lo, hi);
    };
    s.expect_horizontal_nees = range("horizontal_nees");
    s.expect_heading_nees = range("heading_nees");
    if (expect.Has("max_final_3sigma_m")) {
      double v = 0;
      expect.Get("max_final_3sigma_m", v, 0.0);
      s.expect_max_final_3sigma_m = v;
    }
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

// "; the log lost N CHANNEL messages" when the completeness check found losses on `channel`.
std::string LostNote(const logcheck::LogReport& log, const std::string& channel) {
  const auto it = log.channels.find(channel);
  if (it == log.channels.end() || it->second.lost == 0) return "";
  return "; the log lost " + std::to_string(it->second.lost) + " " + channel + " messages";
}

// Says why each figure the log could not give is absent (summary.json: KEY_reason).
void ExplainMissing(ScenarioSummary& s, bool zones_defined) {
  const std::string no_truth = "no SIM_TRUTH in the log (not a simulated run, or lost)" +
                               LostNote(s.log, channels::kSimTruth);
  if (!s.final_estimate) {
    s.missing["final_estimate"] = "no POSE in the log" + LostNote(s.log, channels::kPose);
  }
  if (!s.final_truth) {
    for (const char* key : {"final_truth", "distance_travelled_m", "rover_time_s"}) {
      s.missing[key] = no_truth;
    }
  }
  if (!s.final_estimate || !s.final_truth) {
    std::string why = "needs the final estimate and truth: ";
    if (!s.final_estimate) why += s.missing["final_estimate"];
    if (!s.final_truth) why += std::string(s.final_estimate ? "" : "; ") + s.missing["final_truth"];
    s.missing["position_error_m"] = s.missing["position_error_pct"] = why;
  }
  if (!s.min_keepout_clearance_m) {
    s.missing["min_keepout_clearance_m"] =
        !zones_defined    ? "no keep-out zone was defined"
        : !s.final_truth ? no_truth
                         : "no SIM_TRUTH sample while a keep-out zone was in force" +
                               LostNote(s.log, channels::kSimTruth);
  }
  if (!s.pose_honesty) {
    s.missing["pose_honesty"] = !s.final_estimate ? s.missing["final_estimate"]
                                : !s.final_truth  ? no_truth
                                                  : "no POSE of site 0 with a heading sigma at a time truth covers";
  }
  if (!s.nees_mean) {
    s.missing["nees_mean"] = s.vo_updates_accepted == 0
                                 ? "no accepted VO update" + LostNote(s.log, channels::kVoUpdate)
                                 : "no truth for the accepted VO updates" +
                                       LostNote(s.log, channels::kSimTruth);
  }
}

}  // namespace

ScenarioSummary SummarizeLog(const std::string& log_path, const hazards::Footprint& footprint) {
  rover::logcheck::LogReader log(log_path);
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");

  std::vector<rover_msgs::sim_truth_t> truth;
  std::vector<rover_msgs::step_report_t> reports;
  std::vector<rover_msgs::vo_update_t> vo_updates;
  std::optional<rover_msgs::pose_t> last_pose;
  std::vector<rover_msgs::pose_t> poses;
  std::optional<rover_msgs::sequence_status_t> final_status;
  std::map<int, std::pair<int, std::string>> command_text;  // index -> line, text
  std::int64_t latest_submission = -1;  // the summary judges the last sequence submitted
  int num_commands = 0;
  // Zones in force over time, for the truth clearance.
  std::vector<std::pair<std::int64_t, std::vector<hazards::KeepOutZone>>> zone_sets;

  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    const std::string& ch = ev->channel;
    if (ch == channels::kSimTruth) {
      rover_msgs::sim_truth_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) truth.push_back(m);
    } else if (ch == channels::kVoUpdate) {
      rover_msgs::vo_update_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) vo_updates.push_back(m);
    } else if (ch == channels::kStepReport) {
      rover_msgs::step_report_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) reports.push_back(m);
    } else if (ch == channels::kPose) {
      rover_msgs::pose_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) last_pose = m, poses.push_back(m);
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
      command_text.clear();  // a later submission on the same stack: the summary is its
      num_commands = 0;
      latest_submission = std::max(latest_submission, m.submission_id);
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
        if (!final_status || m.submission_id > final_status->submission_id) final_status = m;
      }
    }
  }
  // A later sequence that never ended leaves the run incomplete, whatever the first did.
  if (final_status && final_status->submission_id < latest_submission) final_status.reset();
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

  // Every VO update against truth; a step's is the last whose pair was taken during it.
  std::vector<VoCheck> vo_checks;
  double nees_sum = 0.0;
  int nees_count = 0;
  for (const auto& u : vo_updates) {
    if (u.status == rover_msgs::vo_update_t::STATUS_BASELINE) continue;
    vo_checks.push_back(CheckVoUpdate(u, truth));
    const VoCheck& c = vo_checks.back();
    ++s.vo_updates;
    s.vo_updates_accepted += c.accepted;
    s.false_updates += c.false_update();
    if (c.nees) {
      nees_sum += *c.nees;
      ++nees_count;
    }
  }
  if (nees_count > 0) s.nees_mean = nees_sum / nees_count;
  auto step_vo = [&](const rover_msgs::step_report_t& r) -> std::optional<VoCheck> {
    std::optional<VoCheck> found;
    for (const auto& c : vo_checks) {
      if (c.to_utime > r.utime_before && c.to_utime <= r.utime_after) found = c;
    }
    return found;
  };

  for (const auto& r : reports) {
    StepSummary st;
    st.vo = step_vo(r);
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
  s.pose_honesty = JudgePoses(poses, truth);
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

  for (const auto& t : truth) s.truth_track.push_back({t.position[0], t.position[1], t.rpy[2]});
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
  s.log = logcheck::CheckLog(log_path);
  ExplainMissing(s, !zone_sets.empty());
  // The log holds no world: the scenario runner adds the rock clearance (AddRockClearance).
  s.missing["min_rock_clearance_m"] = "the rocks are not in the log (the scenario runner adds them from the world)";
  return s;
}

void AddRockClearance(const std::vector<RockDisc>& rocks, const hazards::Footprint& footprint,
                      ScenarioSummary* s) {
  s->rocks_over_limit = static_cast<int>(rocks.size());
  s->min_rock_clearance_m.reset();
  s->min_rock_clearance_rock.clear();
  s->missing.erase("min_rock_clearance_m");
  if (rocks.empty() || s->truth_track.empty()) {
    s->missing["min_rock_clearance_m"] = rocks.empty() ? "no rock in the world is taller than the step limit"
                                                       : "no SIM_TRUTH in the log";
    return;
  }
  for (const RockDisc& r : rocks) {
    const auto zone = hazards::KeepOutZone::Circle(r.name.empty() ? "rock" : r.name, r.x, r.y, r.radius_m);
    for (const auto& t : s->truth_track) {
      const double c = hazards::Clearance(zone, footprint, t);
      if (!s->min_rock_clearance_m || c < *s->min_rock_clearance_m) {
        s->min_rock_clearance_m = c;
        s->min_rock_clearance_rock = r.name;
      }
    }
  }
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

// `KEY_reason` beside a null KEY, when the summary says why the figure is absent.
void WriteReason(JsonWriter& j, const ScenarioSummary& s, const std::string& key) {
  if (auto it = s.missing.find(key); it != s.missing.end()) j.Field(key + "_reason", it->second);
}

// A figure, or null and its reason when the log could not give it.
void WriteFigure(JsonWriter& j, const ScenarioSummary& s, const std::string& key, double v) {
  if (!s.missing.count(key)) {
    j.Field(key, v);
    return;
  }
  j.Key(key).Null();
  WriteReason(j, s, key);
}

// cpu_s: the whole run's user + sys CPU seconds, per rover-hour, and each process's share.
void WriteCpu(JsonWriter& j, const ScenarioSummary& s) {
  if (s.cpu_s.empty()) return;
  double total = 0;
  for (const auto& [name, cpu] : s.cpu_s) total += cpu;
  j.Key("cpu_s");
  j.BeginObject();
  j.Field("total", total);
  if (s.rover_time_s > 0) j.Field("per_rover_hour", total / (s.rover_time_s / 3600.0));
  j.Key("by_process");
  j.BeginObject();
  for (const auto& [name, cpu] : s.cpu_s) j.Field(name, cpu);
  j.EndObject();
  j.EndObject();
}

// Whether the log lost anything: the verdict, and count, lost and gaps per channel.
void WriteLogCheck(JsonWriter& j, const logcheck::LogReport& log) {
  j.Field("log_complete", log.complete);
  if (!log.complete) j.Field("log_complete_reason", log.verdict_reason);
  j.Field("log_messages", static_cast<long long>(log.messages));
  j.Field("log_lost", static_cast<long long>(log.lost));
  j.Key("log_channels").BeginObject();
  for (const auto& [channel, c] : log.channels) {
    j.Key(channel).BeginObject();
    j.Field("count", static_cast<long long>(c.count)).Field("lost", static_cast<long long>(c.lost));
    j.Key("gaps").BeginArray();
    for (const auto& g : c.gaps) {
      const auto name = log.publisher_names.find(g.publisher);
      j.BeginObject();
      j.Field("publisher", name == log.publisher_names.end() ? g.publisher : name->second);
      j.Field("lost", static_cast<long long>(g.lost));
      j.Field("count_before", static_cast<long long>(g.count_before));
      j.Field("count_after", static_cast<long long>(g.count_after));
      j.Field("utime_before", static_cast<long long>(g.utime_before));
      j.Field("utime_after", static_cast<long long>(g.utime_after));
      j.EndObject();
    }
    j.EndArray();
    j.Field("restarts", static_cast<long long>(c.restarts.size()));
    if (c.unchecked > 0) {
      j.Field("unchecked", static_cast<long long>(c.unchecked));
      j.Field("unchecked_reason", c.unchecked_reason);
    }
    j.EndObject();
  }
  j.EndObject();
  j.Key("log_warnings").BeginArray();
  for (const auto& w : log.warnings) j.Value(w);
  j.EndArray();
}

// A step's VO update: status, VO's delta and covariance, the true delta, the NEES.
void WriteVoCheck(JsonWriter& j, const std::string& key, const std::optional<VoCheck>& c) {
  j.Key(key);
  if (!c) {
    j.Null();
    return;
  }
  static const char* names[] = {"x", "y", "z", "roll", "pitch", "yaw"};
  auto vector6 = [&](const std::string& k, const std::optional<Vector6>& v) {
    j.Key(k);
    if (!v) {
      j.Null();
      return;
    }
    j.BeginObject();
    for (int i = 0; i < 6; ++i) j.Field(names[i], (*v)(i));
    j.EndObject();
  };
  j.BeginObject();
  j.Field("status", c->status).Field("reason", c->reason);
  j.Field("from_frame_id", static_cast<long long>(c->from_frame_id));
  j.Field("to_frame_id", static_cast<long long>(c->to_frame_id));
  j.Field("from_utime", static_cast<long long>(c->from_utime));
  j.Field("to_utime", static_cast<long long>(c->to_utime));
  j.Field("accepted", c->accepted);
  vector6("delta", c->accepted ? std::optional<Vector6>(c->delta) : std::nullopt);
  j.Key("covariance");
  if (c->accepted) {
    j.BeginArray();  // 6 rows of 6: x y z roll pitch yaw
    for (int r = 0; r < 6; ++r) {
      j.BeginArray();
      for (int k = 0; k < 6; ++k) j.Value(c->covariance(r, k));
      j.EndArray();
    }
    j.EndArray();
  } else {
    j.Null();
  }
  vector6("true_delta", c->true_delta);
  j.Key("nees");
  if (c->nees) {
    j.Value(*c->nees);
  } else {
    j.Null();
  }
  j.Field("false_update", c->false_update());
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
    WriteVoCheck(j, "vo", st.vo);
    j.EndObject();
  }
  j.EndArray();
  WritePose(j, "final_estimate", s.final_estimate);
  WriteReason(j, s, "final_estimate");
  WritePose(j, "final_truth", s.final_truth);
  WriteReason(j, s, "final_truth");
  WriteFigure(j, s, "distance_travelled_m", s.distance_travelled_m);
  WriteFigure(j, s, "position_error_m", s.position_error_m);
  WriteFigure(j, s, "position_error_pct", s.position_error_pct);
  j.Key("min_keepout_clearance_m");
  if (s.min_keepout_clearance_m) {
    j.Value(*s.min_keepout_clearance_m);
  } else {
    j.Null();
  }
  WriteReason(j, s, "min_keepout_clearance_m");
  j.Key("min_rock_clearance_m");
  if (s.min_rock_clearance_m) {
    j.Value(*s.min_rock_clearance_m);
  } else {
    j.Null();
  }
  WriteReason(j, s, "min_rock_clearance_m");
  j.Key("min_rock_clearance_rock");
  j.Value(s.min_rock_clearance_rock);
  j.Key("rocks_over_limit");
  j.Value(s.rocks_over_limit);
  j.Field("vo_updates", s.vo_updates);
  j.Field("vo_updates_accepted", s.vo_updates_accepted);
  j.Field("false_updates", s.false_updates);
  j.Key("nees_mean");
  if (s.nees_mean) {
    j.Value(*s.nees_mean);
  } else {
    j.Null();
  }
  WriteReason(j, s, "nees_mean");
  j.Key("pose_honesty");
  if (const auto& h = s.pose_honesty) {
    j.BeginObject();
    j.Field("poses", h->poses).Field("heading_nees_mean", h->heading_nees_mean);
    j.Field("heading_beyond_3_sigma_pct", h->heading_beyond_pct);
    j.Field("horizontal_poses", h->horizontal_poses).Field("horizontal_nees_mean", h->horizontal_nees_mean);
    j.Field("horizontal_beyond_3_sigma_pct", h->horizontal_beyond_pct);
    j.Field("final_horizontal_3sigma_m", h->final_horizontal_3sigma_m);
    j.Field("final_horizontal_error_m", h->final_horizontal_error_m);
    j.EndObject();
  } else {
    j.Null();
  }
  WriteReason(j, s, "pose_honesty");
  j.Key("rest_checks");
  j.BeginArray();
  for (const auto& c : s.rest_checks) {
    j.BeginObject();
    j.Field("after", c.after).Field("rested_s", c.rested_s).Field("position_error_m", c.position_error_m);
    j.Field("heading_error_deg", c.heading_error_deg).Field("heading_sigma_deg", c.heading_sigma_deg);
    j.Field("heading_nees", c.heading_nees).Field("horizontal_nees", c.horizontal_nees);
    j.EndObject();
  }
  j.EndArray();
  WriteFigure(j, s, "rover_time_s", s.rover_time_s);
  j.Field("wall_time_s", s.wall_time_s);
  WriteCpu(j, s);
  WriteLogCheck(j, s.log);
  if (!s.log_digest.empty()) j.Field("log_digest", s.log_digest);
  // Rover time by activity (scenario/rover_time.hpp); null on a real-clock log.
  j.Key("rover_time_breakdown");
  if (s.rover_time.virtual_time) {
    const auto& b = s.rover_time;
    j.BeginObject();
    j.Field("span_s", b.span_s).Field("driving_s", b.driving_s).Field("imaging_s", b.imaging_s);
    j.Field("vo_s", b.vo_s).Field("mapping_s", b.mapping_s).Field("busy_s", b.busy_s).Field("waiting_s", b.waiting_s);
    j.Field("planning_s", b.planning_s);
    j.Field("steps", b.steps).Field("steps_thought_ahead", b.steps_thought_ahead);
    j.EndObject();
  } else {
    j.Null();
    j.Field("rover_time_breakdown_reason",
            "not a virtual-time log: on a real clock its stamps are wall times (README, \"Simulated time\")");
  }
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
  if (!s.cpu_s.empty() && s.rover_time_s > 0) {
    double total = 0;
    for (const auto& [name, cpu] : s.cpu_s) total += cpu;
    os << "  CPU (user + sys, every process): " << std::setprecision(1) << total << " s, "
       << total / (s.rover_time_s / 3600.0) << " s per rover-hour\n" << std::setprecision(3);
  }
  os << "  position error: " << s.position_error_m << " m (" << std::setprecision(2)
     << s.position_error_pct << " % of distance)\n" << std::setprecision(3);
  if (s.min_keepout_clearance_m) {
    os << "  closest approach to a keep-out zone (truth): " << *s.min_keepout_clearance_m << " m\n";
  }
  if (s.min_rock_clearance_m) {
    os << "  closest approach to a rock over the collision height (truth): " << *s.min_rock_clearance_m << " m ("
       << s.min_rock_clearance_rock << ", " << s.rocks_over_limit << " such rocks)\n";
  }
  if (s.vo_updates > 0) {
    os << "  VO updates: " << s.vo_updates << ", accepted " << s.vo_updates_accepted
       << ", false (NEES > " << kChi2Dof6ThreeSigma << ") " << s.false_updates;
    if (s.nees_mean) os << ", NEES mean " << std::setprecision(2) << *s.nees_mean << std::setprecision(3);
    os << "\n";
  }
  if (const auto& h = s.pose_honesty) {
    os << std::setprecision(2) << "  pose honesty (POSE against truth, " << h->poses << " poses): heading NEES mean "
       << h->heading_nees_mean << " (1 is honest), " << std::setprecision(1) << h->heading_beyond_pct
       << " % beyond 3 sigma; horizontal NEES mean " << std::setprecision(2) << h->horizontal_nees_mean
       << " (2 is honest), " << std::setprecision(1) << h->horizontal_beyond_pct << " % beyond its 99.7 % bound; "
       << std::setprecision(3) << "last pose: 3-sigma " << h->final_horizontal_3sigma_m << " m, error "
       << h->final_horizontal_error_m << " m\n";
  }
  for (const auto& c : s.rest_checks) {
    os << std::setprecision(1) << "  after " << c.rested_s << " s " << (c.after == "pause" ? "paused" : "parked")
       << ": estimate against truth " << std::setprecision(3) << c.position_error_m << " m, heading "
       << c.heading_error_deg << " deg (sigma " << c.heading_sigma_deg << " deg); NEES heading " << std::setprecision(2)
       << c.heading_nees << ", horizontal " << c.horizontal_nees << "\n"
       << std::setprecision(3);
  }
  for (const auto& e : s.process_events) os << "  " << e << "\n";
  os << "  log: " << s.log.messages << " messages, " << s.log.lost << " lost; complete: "
     << (s.log.complete ? "yes" : "no (" + s.log.verdict_reason + ")") << "\n";
  if (s.rover_time.virtual_time) {
    const auto& b = s.rover_time;
    os << std::setprecision(1) << "  rover time of the sequence: " << b.span_s << " s: driving " << b.driving_s
       << " s, imaging " << b.imaging_s << " s, VO " << b.vo_s << " s, mapping " << b.mapping_s
       << " s (VO and mapping at once), planning " << b.planning_s << " s, waiting " << b.waiting_s << " s";
    if (b.span_s > 0) os << "; drive rate " << s.distance_travelled_m / (b.span_s / 3600.0) << " m/h of rover time";
    if (b.steps_thought_ahead > 0)
      os << "; " << b.steps_thought_ahead << " of " << b.steps << " steps chosen while driving";
    os << "\n" << std::setprecision(3);
  }
  if (!s.log_digest.empty()) os << "  log digest: " << s.log_digest << " (sha256, less VO's ms_* wall times)\n";
  for (const auto& w : s.log.warnings) os << "  log warning: " << w << "\n";
  std::map<std::string, std::string> figures_by_reason;  // one line per reason
  for (const auto& [key, why] : s.missing) {
    if (key == "nees_mean" || why == "no keep-out zone was defined") continue;
    auto& keys = figures_by_reason[why];
    keys += (keys.empty() ? "" : ", ") + key;
  }
  for (const auto& [why, keys] : figures_by_reason) os << "  no " << keys << ": " << why << "\n";
  return os.str();
}

bool AsExpected(const ScenarioSpec& spec, const ScenarioSummary& s, std::string* why) {
  std::ostringstream miss;
  miss << std::setprecision(4);
  if (!spec.expect_outcome.empty() && s.outcome != spec.expect_outcome) {
    miss << "outcome " << s.outcome << ", expected " << spec.expect_outcome << "; ";
  }
  if (!spec.expect_abort_reasons.empty() &&
      std::find(spec.expect_abort_reasons.begin(), spec.expect_abort_reasons.end(), s.abort_reason) ==
          spec.expect_abort_reasons.end()) {
    miss << "abort reason " << (s.abort_reason.empty() ? "none" : s.abort_reason) << ", expected "
         << spec.expect_abort_reason << "; ";
  }
  if (spec.expect_min_clearance_m &&
      (!s.min_keepout_clearance_m || *s.min_keepout_clearance_m < *spec.expect_min_clearance_m)) {
    miss << "truth clearance ";
    if (s.min_keepout_clearance_m) {
      miss << *s.min_keepout_clearance_m << " m";
    } else {
      miss << "unknown (no zone)";
    }
    miss << ", expected >= " << *spec.expect_min_clearance_m << " m; ";
  }
  if (spec.expect_max_position_error_pct && !(s.position_error_pct <= *spec.expect_max_position_error_pct)) {
    miss << "position error " << s.position_error_pct << " %, expected <= "
         << *spec.expect_max_position_error_pct << " %; ";
  }
  if (spec.expect_max_false_updates && s.false_updates > *spec.expect_max_false_updates) {
    miss << s.false_updates << " false VO updates, expected <= " << *spec.expect_max_false_updates << "; ";
  }
  auto nees = [&](const char* what, const std::optional<std::pair<double, double>>& range, double PoseHonesty::*mean) {
    if (!range) return;
    if (!s.pose_honesty) {
      miss << what << " NEES unknown (no pose judged), expected in [" << range->first << ", " << range->second << "]; ";
      return;
    }
    const double value = (*s.pose_honesty).*mean;
    if (!(value >= range->first && value <= range->second)) {
      miss << what << " NEES mean " << value << ", expected in [" << range->first << ", " << range->second << "]; ";
    }
  };
  nees("horizontal", spec.expect_horizontal_nees, &PoseHonesty::horizontal_nees_mean);
  nees("heading", spec.expect_heading_nees, &PoseHonesty::heading_nees_mean);
  if (spec.expect_max_final_3sigma_m &&
      !(s.pose_honesty && s.pose_honesty->final_horizontal_3sigma_m <= *spec.expect_max_final_3sigma_m)) {
    miss << "final 3-sigma ";
    if (s.pose_honesty) {
      miss << s.pose_honesty->final_horizontal_3sigma_m << " m";
    } else {
      miss << "unknown (no pose judged)";
    }
    miss << ", expected <= " << *spec.expect_max_final_3sigma_m << " m; ";
  }
  std::string text = miss.str();
  if (text.size() >= 2) text.resize(text.size() - 2);
  if (why) *why = text;
  return text.empty();
}

}  // namespace rover::tools
