#include "plot/plot_series.hpp"

#include <cmath>

namespace rover::plot {
namespace {

bool MeasuredByVo(const rover_msgs::step_report_t& s) {
  return s.vo_status == rover_msgs::vo_update_t::STATUS_OK;
}

}  // namespace

std::vector<Segment> EstimateSegments(const DriveLog& log) {
  std::vector<Segment> segments;
  std::size_t next_step = 0;  // steps are reported in time order
  Mode mode = Mode::kBlind;
  for (const auto& e : log.estimate) {
    // The step this pose belongs to, or the last one before it.
    while (next_step < log.steps.size() && log.steps[next_step].utime_before < e.utime) {
      mode = MeasuredByVo(log.steps[next_step]) ? Mode::kVo : Mode::kBlind;
      ++next_step;
    }
    if (segments.empty() || segments.back().mode != mode) {
      Segment s;
      s.mode = mode;
      if (!segments.empty()) s.points.push_back(segments.back().points.back());
      segments.push_back(std::move(s));
    }
    // One point per centimetre of change is plenty for a picture (the jumps VO makes stay,
    // and so does the latest point).
    auto& points = segments.back().points;
    if (points.size() >= 2 && (points.back() - points[points.size() - 2]).norm() < 0.01) {
      points.back() = e.p;
    } else {
      points.push_back(e.p);
    }
  }
  return segments;
}

std::vector<ErrorSample> ErrorSeries(const DriveLog& log) {
  std::vector<ErrorSample> out;
  if (log.truth.empty() || log.estimate.empty()) return out;
  const std::int64_t start = log.estimate.front().utime;
  std::optional<double> odometer0;
  for (const auto& t : log.truth) {
    if (t.utime < start) continue;
    if (!odometer0) odometer0 = t.odometer_m;
    const double distance = t.odometer_m - *odometer0;
    if (!out.empty() && distance - out.back().distance_m < 0.02 && &t != &log.truth.back()) continue;
    const auto est = PositionAt(log.estimate, t.utime);
    const auto wheel = PositionAt(log.wheel_only, t.utime);
    if (!est || !wheel) continue;
    out.push_back({distance, (*wheel - t.p).norm(), (*est - t.p).norm()});
  }
  return out;
}

std::vector<SlipRow> SlipRows(const DriveLog& log) {
  std::vector<SlipRow> rows;
  for (const auto& s : log.steps) {
    SlipRow r;
    r.number = static_cast<int>(rows.size()) + 1;
    r.command_index = s.command_index;
    r.step_index = s.step_index;
    r.commanded_m = s.commanded_distance_m;
    r.measured_m = s.estimated_distance_m;
    r.vo = MeasuredByVo(s);
    const bool drove = std::abs(s.commanded_distance_m) > 1e-6;
    if (drove) r.measured_slip_pct = s.slip_pct;
    if (const auto it = log.slip_limit_pct.find(s.command_index); it != log.slip_limit_pct.end()) {
      r.limit_pct = it->second;
    }
    // True progress along the heading the step started with, as summary.json computes it.
    if (!log.truth.empty()) {
      const auto nearest = [&](std::int64_t u) -> const TruthPoint& {
        auto it = std::lower_bound(log.truth.begin(), log.truth.end(), u,
                                   [](const TruthPoint& p, std::int64_t v) { return p.utime < v; });
        if (it == log.truth.end()) return log.truth.back();
        if (it != log.truth.begin() && u - (it - 1)->utime < it->utime - u) --it;
        return *it;
      };
      const TruthPoint& before = nearest(s.utime_before);
      const TruthPoint& after = nearest(s.utime_after);
      const Eigen::Vector2d forward(std::cos(before.yaw), std::sin(before.yaw));
      r.true_m = (after.p - before.p).head<2>().dot(forward);
      if (drove) r.true_slip_pct = 100.0 * (1.0 - *r.true_m / s.commanded_distance_m);
    }
    rows.push_back(r);
  }
  return rows;
}

std::vector<VoStepChoice> ChooseVoSteps(const DriveLog& log, int max_steps) {
  std::vector<VoStepChoice> measured;
  for (std::size_t i = 0; i < log.steps.size(); ++i) {
    const auto& s = log.steps[i];
    if (!MeasuredByVo(s)) continue;
    // The step's update: the last accepted one whose later frame was taken during the step.
    const rover_msgs::vo_update_t* found = nullptr;
    for (const auto& u : log.vo_updates) {
      if (u.status == rover_msgs::vo_update_t::STATUS_OK && u.to_utime > s.utime_before &&
          u.to_utime <= s.utime_after) {
        found = &u;
      }
    }
    if (found != nullptr) measured.push_back({static_cast<int>(i) + 1, s, *found});
  }
  if (max_steps <= 0 || measured.empty()) return {};
  const int n = static_cast<int>(measured.size());
  if (n <= max_steps) return measured;
  std::vector<VoStepChoice> chosen;
  for (int k = 0; k < max_steps; ++k) {
    const int i = max_steps == 1 ? 0 : static_cast<int>(std::lround(double(k) * (n - 1) / (max_steps - 1)));
    chosen.push_back(measured[i]);
  }
  return chosen;
}

}  // namespace rover::plot
