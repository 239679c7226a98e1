#include "navbench/navbench_metrics.hpp"

#include "report/json_writer.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <unordered_map>

namespace rover::navbench {

namespace {

// A bounding circle of a zone: centre and radius.
std::pair<Eigen::Vector2d, double> Bounds(const hazards::KeepOutZone& zone) {
  if (zone.shape == hazards::KeepOutZone::Shape::kCircle) return {zone.center, zone.radius_m};
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& v : zone.vertices) c += v;
  c /= static_cast<double>(std::max<std::size_t>(1, zone.vertices.size()));
  double r = 0;
  for (const auto& v : zone.vertices) r = std::max(r, (v - c).norm());
  return {c, r};
}

// Obstacles by grid cell: each is listed in every cell a pose could touch it from (its
// bounding circle grown by the footprint's reach), so a pose looks at one cell only. A
// hand-written hash grid: the obstacles never move, and this is all the lookup needs.
class ObstacleGrid {
 public:
  ObstacleGrid(const std::vector<hazards::KeepOutZone>& obstacles, double reach_m) {
    for (std::size_t i = 0; i < obstacles.size(); ++i) {
      const auto [c, r] = Bounds(obstacles[i]);
      const double grow = r + reach_m;
      for (long gx = Cell(c.x() - grow); gx <= Cell(c.x() + grow); ++gx) {
        for (long gy = Cell(c.y() - grow); gy <= Cell(c.y() + grow); ++gy) cells_[Key(gx, gy)].push_back(i);
      }
    }
  }
  const std::vector<std::size_t>& Near(double x, double y) const {
    const auto it = cells_.find(Key(Cell(x), Cell(y)));
    return it == cells_.end() ? none_ : it->second;
  }

 private:
  static constexpr double kCellM = 2.0;
  static long Cell(double v) { return static_cast<long>(std::floor(v / kCellM)); }
  static long long Key(long gx, long gy) { return (static_cast<long long>(gx) << 32) ^ (gy & 0xffffffffLL); }
  std::unordered_map<long long, std::vector<std::size_t>> cells_;
  std::vector<std::size_t> none_;
};

std::string Fixed(double v, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

std::string Pct(int part, int whole) { return whole > 0 ? Fixed(100.0 * part / whole, 1) + " %" : "-"; }

}  // namespace

CollisionReport JudgeCollisions(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                                const std::vector<hazards::KeepOutZone>& obstacles) {
  CollisionReport report;
  // The farthest a footprint point lies from the rover origin, margin included.
  const double reach = std::abs(footprint.center_forward_m) +
                       std::hypot(0.5 * footprint.length_m, 0.5 * footprint.width_m) + footprint.margin_m;
  const ObstacleGrid grid(obstacles, reach);
  std::vector<char> inside(obstacles.size(), 0), seen(obstacles.size(), 0);
  std::vector<std::size_t> was_inside;
  for (std::size_t k = 0; k < track.size(); ++k) {
    const auto& pose = track[k];
    std::vector<std::size_t> now_inside;
    for (const std::size_t i : grid.Near(pose.x, pose.y)) {
      const double c = hazards::Clearance(obstacles[i], footprint, pose);
      if (!report.min_clearance_m || c < *report.min_clearance_m) {
        report.min_clearance_m = c;
        report.closest = obstacles[i].name;
      }
      if (c < 0) {
        if (!inside[i]) {
          ++report.contacts;
          report.contact_samples.push_back(k);
          if (!seen[i]) report.touched.push_back(obstacles[i].name);
          seen[i] = 1;
        }
        now_inside.push_back(i);
      }
    }
    for (const std::size_t i : was_inside) inside[i] = 0;
    for (const std::size_t i : now_inside) inside[i] = 1;
    was_inside = std::move(now_inside);
  }
  return report;
}

std::vector<Eigen::Vector2d> SixWheels(double wheelbase_m, double track_m) {
  std::vector<Eigen::Vector2d> wheels;
  for (const double x : {0.5 * wheelbase_m, 0.0, -0.5 * wheelbase_m}) {
    for (const double y : {-0.5 * track_m, 0.5 * track_m}) wheels.emplace_back(x, y);
  }
  return wheels;
}

OffMapReport WheelsOffMap(const std::vector<hazards::Pose2>& track, const std::vector<Eigen::Vector2d>& wheels,
                          const MapBounds& map) {
  OffMapReport report;
  for (const auto& pose : track) {
    // Rover frame to site plane, as hazards::Footprint::Corners: x forward, y right.
    const Eigen::Vector2d fwd(std::cos(pose.yaw), std::sin(pose.yaw));
    const Eigen::Vector2d right(-std::sin(pose.yaw), std::cos(pose.yaw));
    bool off = false;
    for (const auto& w : wheels) {
      const Eigen::Vector2d p = Eigen::Vector2d(pose.x, pose.y) + w.x() * fwd + w.y() * right;
      if (!map.Contains(p)) {
        if (!report.first) report.first = p;
        off = true;
      }
    }
    report.samples += off;
  }
  return report;
}

double PathLength(const std::vector<hazards::Pose2>& track) {
  double length = 0;
  for (std::size_t i = 1; i < track.size(); ++i) {
    length += std::hypot(track[i].x - track[i - 1].x, track[i].y - track[i - 1].y);
  }
  return length;
}

std::optional<double> PathRatio(double driven_m, const Eigen::Vector2d& start, const Eigen::Vector2d& goal) {
  const double straight = (goal - start).norm();
  if (straight <= 0) return std::nullopt;
  return driven_m / straight;
}

std::optional<double> Median(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

GroupFigures Aggregate(const std::string& group, const std::vector<RunFigures>& runs) {
  GroupFigures g;
  g.group = group;
  std::vector<double> ratios;
  for (const auto& r : runs) {
    if (r.group != group) continue;
    ++g.runs;
    g.successes += r.success();
    g.completed += r.outcome == "completed";
    g.runs_with_collision += r.collided();
    g.contacts += r.rock_contacts + r.zone_contacts;
    g.runs_off_map += r.off_map_samples > 0;
    if (!r.collided() && r.off_map_samples == 0) {
      if (r.outcome == "aborted") ++g.safe_aborts[r.abort_reason.empty() ? "unknown" : r.abort_reason];
      if (r.outcome == "incomplete") ++g.safe_aborts["incomplete"];
    }
    if (r.success() && r.path_ratio) ratios.push_back(*r.path_ratio);
    if (!r.ran) continue;
    g.driven_m += r.driven_m;
    g.rover_time_s += r.rover_time_s;
    g.driving_s += r.driving_s;
    g.imaging_s += r.imaging_s;
    g.vo_s += r.vo_s;
    g.mapping_s += r.mapping_s;
    g.planning_s += r.planning_s;
    g.waiting_s += r.waiting_s;
    g.vo_accepted += r.vo_accepted;
    g.vo_false += r.vo_false;
  }
  g.median_path_ratio = Median(ratios);
  if (g.rover_time_s > 0) g.drive_rate_m_per_h = g.driven_m / g.rover_time_s * 3600.0;
  return g;
}

std::string TableText(const std::vector<GroupFigures>& groups) {
  std::ostringstream os;
  os << std::left << std::setw(11) << "world" << std::setw(6) << "runs" << std::setw(15) << "success"
     << std::setw(10) << "completed" << std::setw(12) << "collisions" << std::setw(9) << "off map"
     << std::setw(11) << "path ratio" << std::setw(9) << "m/h" << std::setw(18) << "VO false/accepted"
     << "safe aborts\n";
  for (const auto& g : groups) {
    std::string aborts;
    for (const auto& [reason, n] : g.safe_aborts) aborts += (aborts.empty() ? "" : ", ") + reason + " " + std::to_string(n);
    os << std::left << std::setw(11) << g.group << std::setw(6) << g.runs << std::setw(15)
       << (std::to_string(g.successes) + " (" + Pct(g.successes, g.runs) + ")") << std::setw(10) << g.completed
       << std::setw(12)
       << (std::to_string(g.runs_with_collision) + (g.contacts > 0 ? " (" + std::to_string(g.contacts) + " hits)" : ""))
       << std::setw(9) << g.runs_off_map << std::setw(11)
       << (g.median_path_ratio ? Fixed(*g.median_path_ratio, 2) : "-") << std::setw(9)
       << (g.drive_rate_m_per_h ? Fixed(*g.drive_rate_m_per_h, 1) : "-") << std::setw(18)
       << (std::to_string(g.vo_false) + "/" + std::to_string(g.vo_accepted) + " (" + Pct(g.vo_false, g.vo_accepted) + ")")
       << (aborts.empty() ? "-" : aborts) << "\n";
  }
  os << "\nrover time (share of the sequences' span; VO and mapping overlap):\n";
  os << std::left << std::setw(11) << "world" << std::setw(10) << "hours" << std::setw(10) << "driving"
     << std::setw(10) << "imaging" << std::setw(10) << "VO" << std::setw(10) << "mapping" << std::setw(10)
     << "planning" << "waiting\n";
  for (const auto& g : groups) {
    auto share = [&](double s) { return g.rover_time_s > 0 ? Fixed(100.0 * s / g.rover_time_s, 1) + " %" : "-"; };
    os << std::left << std::setw(11) << g.group << std::setw(10) << Fixed(g.rover_time_s / 3600.0, 2)
       << std::setw(10) << share(g.driving_s) << std::setw(10) << share(g.imaging_s) << std::setw(10)
       << share(g.vo_s) << std::setw(10) << share(g.mapping_s) << std::setw(10) << share(g.planning_s)
       << share(g.waiting_s) << "\n";
  }
  return os.str();
}

std::string ResultsJson(const std::vector<GroupFigures>& groups, const std::vector<RunFigures>& runs,
                        const std::string& command) {
  tools::JsonWriter j;
  auto optional = [&](const std::string& key, const std::optional<double>& v) {
    j.Key(key);
    if (v) {
      j.Value(*v);
    } else {
      j.Null();
    }
  };
  j.BeginObject();
  j.Field("command", command);
  j.Key("groups").BeginArray();
  for (const auto& g : groups) {
    j.BeginObject();
    j.Field("group", g.group).Field("runs", g.runs).Field("successes", g.successes).Field("success_pct", g.success_pct());
    j.Field("completed", g.completed).Field("runs_with_collision", g.runs_with_collision).Field("contacts", g.contacts);
    j.Field("runs_off_map", g.runs_off_map);
    j.Key("safe_aborts").BeginObject();
    for (const auto& [reason, n] : g.safe_aborts) j.Field(reason, n);
    j.EndObject();
    optional("median_path_ratio", g.median_path_ratio);
    j.Field("driven_m", g.driven_m).Field("rover_time_s", g.rover_time_s);
    optional("drive_rate_m_per_h", g.drive_rate_m_per_h);
    j.Key("rover_time_breakdown").BeginObject();
    j.Field("driving_s", g.driving_s).Field("imaging_s", g.imaging_s).Field("vo_s", g.vo_s);
    j.Field("mapping_s", g.mapping_s).Field("planning_s", g.planning_s).Field("waiting_s", g.waiting_s);
    j.EndObject();
    j.Field("vo_updates_accepted", g.vo_accepted).Field("false_updates", g.vo_false);
    j.EndObject();
  }
  j.EndArray();
  j.Key("runs").BeginArray();
  for (const auto& r : runs) {
    j.BeginObject();
    j.Field("group", r.group).Field("id", r.id).Field("ran", r.ran).Field("outcome", r.outcome);
    j.Field("abort_reason", r.abort_reason).Field("in_goal_disc", r.in_goal_disc).Field("success", r.success());
    j.Field("rock_contacts", r.rock_contacts).Field("zone_contacts", r.zone_contacts);
    j.Field("off_map_samples", r.off_map_samples);
    j.Field("goal_x", r.goal_x).Field("goal_y", r.goal_y).Field("goal_radius_m", r.goal_radius_m);
    j.Key("final_truth");
    if (r.final_truth) {
      j.BeginArray().Value(r.final_truth->x()).Value(r.final_truth->y()).EndArray();
    } else {
      j.Null();
    }
    j.Field("straight_m", r.straight_m).Field("driven_m", r.driven_m);
    optional("path_ratio", r.path_ratio);
    j.Field("rover_time_s", r.rover_time_s).Field("vo_updates_accepted", r.vo_accepted).Field("false_updates", r.vo_false);
    j.EndObject();
  }
  j.EndArray();
  j.EndObject();
  return j.str();
}

}  // namespace rover::navbench
