// The executor's options (YAML section `executor:`): defaults in executor.hpp, a sample
// in executor_example.yaml.
#include "sequence/executor.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rover::sequence {

planner::RefusalOptions RefusalOptionsOf(const ExecutorOptions& o) {
  planner::RefusalOptions r;
  r.cost_per_m = o.planner_refusal_cost;
  r.ahead_m = o.planner_refusal_ahead_m;
  r.radius_m = o.planner_refusal_radius_m;
  return r;
}

void ValidateExecutorOptions(const ExecutorOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("executor option ") + name + " must be > 0, got " +
                                  std::to_string(v));
    }
  };
  positive(o.heartbeat_timeout_s, "heartbeat_timeout_s");
  positive(o.hazard_reply_wait_s, "hazard_reply_wait_s");
  positive(o.hazard_status_wait_s, "hazard_status_wait_s");
  positive(o.vo_wait_s, "vo_wait_s");
  positive(o.pose_wait_s, "pose_wait_s");
  positive(o.mobility_wait_s, "mobility_wait_s");
  positive(o.capture_wait_s, "capture_wait_s");
  positive(o.site_wait_s, "site_wait_s");
  positive(o.mobility_timeout_factor, "mobility_timeout_factor");
  positive(o.speed_mps, "speed_mps");
  positive(o.turn_rate_rps, "turn_rate_rps");
  positive(o.default_step_m, "default_step_m");
  positive(o.default_max_turn_deg, "default_max_turn_deg");
  positive(o.goto_turn_threshold_deg, "goto_turn_threshold_deg");
  positive(o.goto_default_distance_factor, "goto_default_distance_factor");
  positive(o.path_sample_spacing_m, "path_sample_spacing_m");
  positive(o.path_sample_turn_deg, "path_sample_turn_deg");
  positive(o.status_period_s, "status_period_s");
  positive(o.blind_slope_deg, "blind_slope_deg");
  positive(o.blind_slip_pct, "blind_slip_pct");
  positive(o.lost_min_step_m, "lost_min_step_m");
  positive(o.margin_sigma_multiplier, "margin_sigma_multiplier");
  positive(o.map_wait_s, "map_wait_s");
  positive(o.avoid_lookahead_m, "avoid_lookahead_m");
  positive(o.avoid_max_curvature_per_m, "avoid_max_curvature_per_m");
  if (o.avoid_num_arcs < 1 || !(o.avoid_backup_m >= 0.0) || !(o.avoid_margin_m >= 0.0)) {
    throw std::invalid_argument("executor options avoid_num_arcs must be >= 1, avoid_backup_m and avoid_margin_m >= 0");
  }
  if (!std::isfinite(o.avoid_squeeze_margin_m))
    throw std::invalid_argument("executor options avoid_squeeze_margin_m must be finite (negative: off)");
  if (!(o.avoid_zone_sigma_multiplier >= 0.0) || !(o.planner_unknown_cost >= 1.0) || !(o.planner_caution_cost >= 1.0) || !(o.planner_near_cost >= 1.0) ||
      !(o.planner_margin_m >= 0.0) || o.planner_unreachable_plans < 1 || !(o.goto_arrival_sigmas >= 0.0) ||
      !(o.goto_min_arrival_fraction > 0.0) || !(o.goto_min_arrival_fraction <= 1.0)) {
    throw std::invalid_argument(
        "executor options: avoid_zone_sigma_multiplier, planner_margin_m and goto_arrival_sigmas must be >= 0, "
        "planner_*_cost >= 1, planner_unreachable_plans >= 1, goto_min_arrival_fraction in (0, 1]");
  }
  planner::BlockOptions blocks;
  blocks.stall_steps = o.planner_block_after_steps;
  blocks.min_gain_m = o.planner_block_min_gain_m;
  blocks.ahead_m = o.planner_block_ahead_m;
  blocks.radius_m = o.planner_block_radius_m;
  try {
    blocks.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("executor options planner_block_*: ") + e.what());
  }
  try {
    RefusalOptionsOf(o).Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("executor options planner_refusal_*: ") + e.what());
  }
  if (o.recent_steps < 1) {
    throw std::invalid_argument("executor option recent_steps must be >= 1, got " +
                                std::to_string(o.recent_steps));
  }
  if (!(o.step_sigma_growth_pct >= 0.0) || !std::isfinite(o.step_sigma_growth_pct)) {
    throw std::invalid_argument("executor option step_sigma_growth_pct must be >= 0, got " +
                                std::to_string(o.step_sigma_growth_pct));
  }
  if (!(o.start_wait_s >= 0.0)) {
    throw std::invalid_argument("executor option start_wait_s must be >= 0, got " +
                                std::to_string(o.start_wait_s));
  }
  for (const auto& p : o.required_processes) {
    if (p.empty()) throw std::invalid_argument("executor option required_processes holds an empty name");
  }
}

ExecutorOptions LoadExecutorOptions(const config::ConfigNode& root) {
  ExecutorOptions o;
  const config::ConfigNode n = root["executor"];
  if (n.IsNull()) return o;
  if (!n.IsMap()) n.Fail("expected a mapping of executor options");
  n.CheckKeys({"required_processes", "vo_processes", "vo_processes_required", "heartbeat_timeout_s",
               "start_wait_s", "hazard_reply_wait_s", "hazard_status_wait_s", "vo_wait_s",
               "pose_wait_s", "mobility_wait_s", "capture_wait_s", "site_wait_s",
               "mobility_timeout_factor", "mobility_timeout_margin_s", "speed_mps", "turn_rate_rps",
               "default_step_m", "default_max_turn_deg", "goto_turn_threshold_deg",
               "goto_default_distance_factor", "goto_default_distance_margin_m",
               "predictive_hazard_check", "reactive_hazard_abort", "path_sample_spacing_m",
               "path_sample_turn_deg", "slip_min_step_m", "status_period_s", "blind_slope_deg",
               "blind_slip_pct", "recent_steps", "lost_min_step_m", "vo_retry_after_m", "step_sigma_growth_pct",
               "margin_sigma_multiplier", "state_file", "map_wait_s", "think_while_driving", "avoid_lookahead_m",
               "avoid_max_curvature_per_m", "avoid_num_arcs", "avoid_backup_m", "avoid_margin_m", "avoid_squeeze_margin_m",
               "avoid_zone_sigma_multiplier", "avoid_unseen_ground_strict", "avoid_start_ring_known", "avoid_hidden_flank_step_m", "avoid_top_rise_m", "avoid_top_ground_radius_m", "avoid_top_rise_in_plan", "avoid_hidden_reach_m", "avoid_look_pan_deg", "avoid_look_tilt_deg", "avoid_look_min_cells", "avoid_look_curvature_per_m", "avoid_keep_unsafe", "avoid_good_enough", "planner_enabled", "planner_unknown_cost", "planner_caution_cost", "planner_near_cost", "planner_vote_clearance",
               "planner_margin_m", "planner_unreachable_plans", "planner_block_after_steps", "planner_block_min_gain_m",
               "planner_block_ahead_m", "planner_block_radius_m", "planner_refusal_cost", "planner_refusal_ahead_m",
               "planner_refusal_radius_m", "planner_prior_map", "goto_arrival_sigmas",
               "goto_min_arrival_fraction"});
  auto names = [&](const char* key, std::vector<std::string>& out) {
    if (!n.Has(key)) return;
    const config::ConfigNode list = n[key];
    if (!list.IsSequence()) list.Fail("expected a list of process names");
    out.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      out.push_back(list.at(i).AsString());
      if (out.back().empty()) list.at(i).Fail("expected a process name");
    }
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  names("required_processes", o.required_processes);
  names("vo_processes", o.vo_processes);
  n.Get("vo_processes_required", o.vo_processes_required);
  n.Get("heartbeat_timeout_s", o.heartbeat_timeout_s, 1e-3, kInf);
  n.Get("start_wait_s", o.start_wait_s, 0.0, kInf);
  n.Get("hazard_reply_wait_s", o.hazard_reply_wait_s, 1e-3, kInf);
  n.Get("hazard_status_wait_s", o.hazard_status_wait_s, 1e-3, kInf);
  n.Get("vo_wait_s", o.vo_wait_s, 1e-3, kInf);
  n.Get("pose_wait_s", o.pose_wait_s, 1e-3, kInf);
  n.Get("mobility_wait_s", o.mobility_wait_s, 1e-3, kInf);
  n.Get("capture_wait_s", o.capture_wait_s, 1e-3, kInf);
  n.Get("site_wait_s", o.site_wait_s, 1e-3, kInf);
  n.Get("mobility_timeout_factor", o.mobility_timeout_factor, 1.0, kInf);
  n.Get("mobility_timeout_margin_s", o.mobility_timeout_margin_s, 0.0, kInf);
  n.Get("speed_mps", o.speed_mps, 1e-4, 10.0);
  n.Get("turn_rate_rps", o.turn_rate_rps, 1e-4, 10.0);
  n.Get("default_step_m", o.default_step_m, 1e-3, 0.75);
  n.Get("default_max_turn_deg", o.default_max_turn_deg, 0.1, 90.0);
  n.Get("goto_turn_threshold_deg", o.goto_turn_threshold_deg, 0.1, 90.0);
  n.Get("goto_default_distance_factor", o.goto_default_distance_factor, 1.0, 100.0);
  n.Get("goto_default_distance_margin_m", o.goto_default_distance_margin_m, 0.0, kInf);
  n.Get("predictive_hazard_check", o.predictive_hazard_check);
  n.Get("reactive_hazard_abort", o.reactive_hazard_abort);
  n.Get("path_sample_spacing_m", o.path_sample_spacing_m, 1e-3, 1.0);
  n.Get("path_sample_turn_deg", o.path_sample_turn_deg, 0.01, 45.0);
  n.Get("slip_min_step_m", o.slip_min_step_m, 0.0, 0.75);
  n.Get("status_period_s", o.status_period_s, 1e-3, kInf);
  n.Get("blind_slope_deg", o.blind_slope_deg, 0.1, 45.0);
  n.Get("blind_slip_pct", o.blind_slip_pct, 0.1, 100.0);
  n.Get("recent_steps", o.recent_steps, 1, 100);
  n.Get("lost_min_step_m", o.lost_min_step_m, 0.01, 0.75);
  n.Get("vo_retry_after_m", o.vo_retry_after_m, 0.0, 1000.0);
  n.Get("step_sigma_growth_pct", o.step_sigma_growth_pct, 0.0, 100.0);
  n.Get("margin_sigma_multiplier", o.margin_sigma_multiplier, 0.1, 10.0);
  n.Get("state_file", o.state_file);
  n.Get("map_wait_s", o.map_wait_s, 1e-3, kInf);
  n.Get("think_while_driving", o.think_while_driving);
  n.Get("avoid_lookahead_m", o.avoid_lookahead_m, 0.1, 20.0);
  n.Get("avoid_max_curvature_per_m", o.avoid_max_curvature_per_m, 0.01, 10.0);
  n.Get("avoid_num_arcs", o.avoid_num_arcs, 1, 101);
  n.Get("avoid_backup_m", o.avoid_backup_m, 0.0, 0.75);
  n.Get("avoid_margin_m", o.avoid_margin_m, 0.0, 1.0);
  n.Get("avoid_squeeze_margin_m", o.avoid_squeeze_margin_m, -1.0, 1.0);
  n.Get("avoid_zone_sigma_multiplier", o.avoid_zone_sigma_multiplier, 0.0, 10.0);
  n.Get("avoid_unseen_ground_strict", o.avoid_unseen_ground_strict);
  n.Get("avoid_start_ring_known", o.avoid_start_ring_known);
  n.Get("avoid_hidden_flank_step_m", o.avoid_hidden_flank_step_m, 0.0, 1.0);
  n.Get("avoid_top_rise_m", o.avoid_top_rise_m, 0.0, 1.0);
  n.Get("avoid_top_ground_radius_m", o.avoid_top_ground_radius_m, 0.4, 3.0);
  n.Get("avoid_top_rise_in_plan", o.avoid_top_rise_in_plan);
  n.Get("avoid_hidden_reach_m", o.avoid_hidden_reach_m, 0.0, 1.0);
  n.Get("avoid_look_pan_deg", o.avoid_look_pan_deg, 0.0, 150.0);
  n.Get("avoid_look_tilt_deg", o.avoid_look_tilt_deg, -30.0, 60.0);
  n.Get("avoid_look_min_cells", o.avoid_look_min_cells, 1, 10000);
  n.Get("avoid_look_curvature_per_m", o.avoid_look_curvature_per_m, 0.0, 100.0);
  n.Get("avoid_keep_unsafe", o.avoid_keep_unsafe);
  n.Get("avoid_good_enough", o.avoid_good_enough, 0.0, 1.0);
  n.Get("planner_enabled", o.planner_enabled);
  n.Get("planner_unknown_cost", o.planner_unknown_cost, 1.0, 100.0);
  n.Get("planner_caution_cost", o.planner_caution_cost, 1.0, 100.0);
  n.Get("planner_near_cost", o.planner_near_cost, 1.0, 100.0);
  n.Get("planner_vote_clearance", o.planner_vote_clearance);
  n.Get("planner_margin_m", o.planner_margin_m, 0.0, 100.0);
  n.Get("planner_unreachable_plans", o.planner_unreachable_plans, 1, 1000);
  n.Get("planner_block_after_steps", o.planner_block_after_steps, 0, 100000);
  n.Get("planner_block_min_gain_m", o.planner_block_min_gain_m, 0.01, 100.0);
  n.Get("planner_block_ahead_m", o.planner_block_ahead_m, 0.1, 100.0);
  n.Get("planner_block_radius_m", o.planner_block_radius_m, 0.05, 10.0);
  n.Get("planner_refusal_cost", o.planner_refusal_cost, 0.0, 1000.0);
  n.Get("planner_refusal_ahead_m", o.planner_refusal_ahead_m, 0.1, 10.0);
  n.Get("planner_refusal_radius_m", o.planner_refusal_radius_m, 0.05, 5.0);
  n.Get("planner_prior_map", o.planner_prior_map);
  if (!o.planner_prior_map.empty() && o.planner_prior_map.front() != '/') {
    // Relative to the config file, as the camera rig is.
    const std::string& src = n.source();
    const auto slash = src.find_last_of('/');
    if (slash != std::string::npos) o.planner_prior_map = src.substr(0, slash + 1) + o.planner_prior_map;
  }
  n.Get("goto_arrival_sigmas", o.goto_arrival_sigmas, 0.0, 10.0);
  n.Get("goto_min_arrival_fraction", o.goto_min_arrival_fraction, 0.01, 1.0);
  return o;
}

ExecutorOptions LoadExecutorOptionsFile(const std::string& path) {
  return LoadExecutorOptions(config::ConfigNode::LoadFile(path));
}

}  // namespace rover::sequence
