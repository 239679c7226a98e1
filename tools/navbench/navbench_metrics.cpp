#include "navbench/navbench_metrics.hpp"

#include "planner/global_planner.hpp"
#include "report/json_writer.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <sstream>
#include <limits>
#include <stdexcept>
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

// JudgeCollisions with an overlap judged by `hits` (obstacle index, clearance < 0): contacts
// are entries into a hit; overlaps never hit are the report's grazes.
CollisionReport Judge(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                      const std::vector<hazards::KeepOutZone>& obstacles,
                      const std::function<bool(std::size_t, double)>& hits) {
  CollisionReport report;
  // The farthest a footprint point lies from the rover origin, margin included.
  const double reach = std::abs(footprint.center_forward_m) +
                       std::hypot(0.5 * footprint.length_m, 0.5 * footprint.width_m) + footprint.margin_m;
  const ObstacleGrid grid(obstacles, reach);
  std::vector<char> inside(obstacles.size(), 0), seen(obstacles.size(), 0), overlapped(obstacles.size(), 0);
  std::vector<std::size_t> was_inside, overlap_order;
  for (std::size_t k = 0; k < track.size(); ++k) {
    const auto& pose = track[k];
    std::vector<std::size_t> now_inside;
    for (const std::size_t i : grid.Near(pose.x, pose.y)) {
      const double c = hazards::Clearance(obstacles[i], footprint, pose);
      if (!report.min_clearance_m || c < *report.min_clearance_m) {
        report.min_clearance_m = c;
        report.closest = obstacles[i].name;
      }
      if (c >= 0) continue;
      if (!overlapped[i]) overlap_order.push_back(i);
      overlapped[i] = 1;
      if (!hits(i, c)) continue;
      if (!inside[i]) {
        ++report.contacts;
        report.contact_samples.push_back(k);
        if (!seen[i]) report.touched.push_back(obstacles[i].name);
        seen[i] = 1;
      }
      now_inside.push_back(i);
    }
    for (const std::size_t i : was_inside) inside[i] = 0;
    for (const std::size_t i : now_inside) inside[i] = 1;
    was_inside = std::move(now_inside);
  }
  for (const std::size_t i : overlap_order)
    if (!seen[i]) report.grazed.push_back(obstacles[i].name);
  return report;
}

}  // namespace

CollisionReport JudgeCollisions(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                                const std::vector<hazards::KeepOutZone>& obstacles) {
  return Judge(track, footprint, obstacles, [](std::size_t, double) { return true; });
}

CollisionReport JudgeRockCollisions(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                                    const std::vector<hazards::KeepOutZone>& rocks, const SurfaceHeight& surface,
                                    double clearance_m) {
  // For a circle, Clearance is the footprint's distance from the centre less the radius
  // (negative inside the footprint as well), so the footprint's point nearest the centre
  // lies max(0, c + radius) from it.
  return Judge(track, footprint, rocks, [&](std::size_t i, double c) {
    return surface(i, std::max(0.0, c + rocks[i].radius_m)) > clearance_m;
  });
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

namespace {

// How far `a`..`b` keeps from every obstacle (negative: it crosses one): circles exactly,
// polygons by points along the segment every `spacing_m`.
double SegmentClearance(const std::vector<hazards::KeepOutZone>& obstacles, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b, double spacing_m) {
  hazards::Footprint point;
  point.length_m = point.width_m = 1e-4;
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  double out = std::numeric_limits<double>::infinity();
  for (const auto& z : obstacles) {
    if (z.shape == hazards::KeepOutZone::Shape::kCircle) {
      const double t = len2 > 0 ? std::clamp((z.center - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      out = std::min(out, (a + t * ab - z.center).norm() - z.radius_m);
      continue;
    }
    const int n = std::max(1, static_cast<int>(std::ceil(std::sqrt(len2) / spacing_m)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector2d p = a + (static_cast<double>(k) / n) * ab;
      out = std::min(out, hazards::Clearance(z, point, p.x(), p.y(), 0.0));
    }
  }
  return out;
}

}  // namespace

ShortestPath ShortestSafePath(const std::vector<hazards::KeepOutZone>& obstacles, double clearance_m,
                              const Eigen::Vector2d& start, const Eigen::Vector2d& goal, double goal_radius_m,
                              const MapBounds& map, double cell_m) {
  if (!(clearance_m >= 0) || !(cell_m > 0) || !(goal_radius_m >= 0) || !(map.max_x > map.min_x) ||
      !(map.max_y > map.min_y))
    throw std::invalid_argument("navbench: the shortest path needs clearance >= 0, a cell > 0 and a map");
  const int rows = static_cast<int>(std::ceil((map.max_x - map.min_x) / cell_m));
  const int cols = static_cast<int>(std::ceil((map.max_y - map.min_y) / cell_m));
  const avoidance::Grid grid =
      avoidance::Grid::Filled(map.min_x, map.min_y, cell_m, rows, cols, avoidance::CellClass::kSafe, 1.0f);
  planner::PlanRequest request;
  request.start_x = start.x(), request.start_y = start.y();
  request.goal_x = goal.x(), request.goal_y = goal.y();
  request.goal_radius_m = goal_radius_m;
  request.zones = obstacles;  // cells whose centre lies in one: obstacles
  planner::PlannerOptions options;
  // Only the distance counts: the centre keeps clearance_m off every obstacle cell, and
  // nothing costs more than open ground.
  options.inscribed_radius_m = options.circumscribed_radius_m = clearance_m;
  options.near_cost = 1.0;
  options.max_cells = std::max(options.max_cells, rows * cols + 1);
  const planner::GlobalPlan plan = planner::PlanOnGrid(grid, request, options);
  ShortestPath out;
  if (!plan.reachable()) return out;
  // The grid's way, cut where it first enters the goal disc (a run ends there too).
  std::vector<Eigen::Vector2d> way;
  for (const auto& p : plan.path()) {
    way.push_back(p);
    if ((p - goal).norm() <= goal_radius_m) break;
  }
  // Pulled taut: from each kept point, straight to the farthest point of the way before the
  // first one the straight line cannot reach with the clearance (a cell-centre way may pass
  // a disc up to half a cell's diagonal closer than clearance_m: that much is allowed, and
  // the next point is always reachable). The grid's way bends where Dijkstra's ties fell,
  // not on the taut line, so the taut way is cut into cell-long pieces and pulled again,
  // until it shortens by less than a millimetre.
  const double allowance = clearance_m - 0.75 * cell_m;
  auto taut = [&](const std::vector<Eigen::Vector2d>& in) {
    std::vector<Eigen::Vector2d> pulled{in.front()};
    std::size_t a = 0;
    while (a + 1 < in.size()) {
      std::size_t next = a + 1;
      for (std::size_t j = a + 2; j < in.size(); ++j) {
        if (SegmentClearance(obstacles, in[a], in[j], 0.5 * cell_m) < allowance) break;
        next = j;
      }
      pulled.push_back(in[next]);
      a = next;
    }
    return pulled;
  };
  auto polyline = [](const std::vector<Eigen::Vector2d>& v) {
    double l = 0;
    for (std::size_t k = 1; k < v.size(); ++k) l += (v[k] - v[k - 1]).norm();
    return l;
  };
  out.path = taut(way);
  for (int pass = 0; pass < 20; ++pass) {
    std::vector<Eigen::Vector2d> dense{out.path.front()};
    for (std::size_t k = 1; k < out.path.size(); ++k) {
      const int n = std::max(1, static_cast<int>(std::ceil((out.path[k] - out.path[k - 1]).norm() / cell_m)));
      for (int m = 1; m <= n; ++m) dense.push_back(out.path[k - 1] + (static_cast<double>(m) / n) * (out.path[k] - out.path[k - 1]));
    }
    std::vector<Eigen::Vector2d> again = taut(dense);
    const bool done = polyline(again) > polyline(out.path) - 1e-3;
    out.path = std::move(again);
    if (done) break;
  }
  double length = 0;
  for (std::size_t k = 1; k < out.path.size(); ++k) length += (out.path[k] - out.path[k - 1]).norm();
  // The last leg ends where it meets the disc, not at the cell inside it.
  if (out.path.size() >= 2) {
    const Eigen::Vector2d p = out.path[out.path.size() - 2], q = out.path.back();
    if ((p - goal).norm() > goal_radius_m && (q - goal).norm() < goal_radius_m) {
      // The point of p..q on the disc's edge.
      const Eigen::Vector2d d = q - p, f = p - goal;
      const double A = d.squaredNorm(), B = 2 * f.dot(d), C = f.squaredNorm() - goal_radius_m * goal_radius_m;
      const double t = (-B - std::sqrt(std::max(0.0, B * B - 4 * A * C))) / (2 * A);
      length -= (1 - t) * d.norm();
      out.path.back() = p + t * d;
    }
  }
  out.length_m = length;
  return out;
}

std::optional<double> Median(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string RunFigures::Verdict() const {
  if (collided()) return "collision";
  if (left_map()) return "left the map";
  if (success()) return "success";
  if (outcome == "completed") return "missed the goal";
  if (outcome == "aborted") return "aborted (" + (abort_reason.empty() ? std::string("unknown") : abort_reason) + ")";
  return outcome;
}

GroupFigures Aggregate(const std::string& group, const std::vector<RunFigures>& runs) {
  GroupFigures g;
  g.group = group;
  std::vector<double> ratios, shortest, over_shortest;
  double nees_sum = 0, beyond_sum = 0;  // over the horizontal poses
  for (const auto& r : runs) {
    if (r.group != group) continue;
    ++g.runs;
    g.successes += r.success();
    g.completed += r.outcome == "completed";
    g.runs_with_collision += r.collided();
    g.contacts += r.rock_contacts + r.zone_contacts;
    g.runs_with_graze += r.rock_grazes > 0;
    g.runs_off_map += r.off_map_samples > 0;
    g.runs_left_map += r.left_map();
    if (r.perfect_way) {
      ++g.runs_way_checked;
      if (*r.perfect_way) {
        ++g.runs_with_way;
        g.successes_with_way += r.success();
        g.navigation_runs_with_way += !r.left_map();
      }
    }
    if (!r.collided() && r.off_map_samples == 0) {
      if (r.outcome == "aborted") ++g.safe_aborts[r.abort_reason.empty() ? "unknown" : r.abort_reason];
      if (r.outcome == "incomplete") ++g.safe_aborts["incomplete"];
    }
    if (r.success() && r.path_ratio) {
      ratios.push_back(*r.path_ratio);
      if (const auto best = r.shortest_ratio()) {
        shortest.push_back(*best);
        over_shortest.push_back(r.driven_m / *r.shortest_m);
      }
    }
    if (!r.ran) continue;
    g.driven_m += r.driven_m;
    g.rover_time_s += r.rover_time_s;
    g.driving_s += r.driving_s;
    g.imaging_s += r.imaging_s;
    g.vo_s += r.vo_s;
    g.mapping_s += r.mapping_s;
    g.planning_s += r.planning_s;
    g.waiting_s += r.waiting_s;
    g.steps += r.steps;
    g.steps_thought_ahead += r.steps_thought_ahead;
    g.vo_accepted += r.vo_accepted;
    g.vo_false += r.vo_false;
    g.horizontal_poses += r.horizontal_poses;
    nees_sum += r.horizontal_nees_mean * r.horizontal_poses;
    beyond_sum += r.horizontal_beyond_pct / 100.0 * r.horizontal_poses;
  }
  if (g.horizontal_poses > 0) {
    g.horizontal_nees_mean = nees_sum / g.horizontal_poses;
    g.horizontal_beyond_pct = 100.0 * beyond_sum / g.horizontal_poses;
  }
  g.median_path_ratio = Median(ratios);
  g.median_shortest_ratio = Median(shortest);
  g.median_over_shortest = Median(over_shortest);
  if (g.rover_time_s > 0) g.drive_rate_m_per_h = g.driven_m / g.rover_time_s * 3600.0;
  return g;
}

std::string TableText(const std::vector<GroupFigures>& groups) {
  std::ostringstream os;
  os << std::left << std::setw(11) << "world" << std::setw(6) << "runs" << std::setw(20) << "success"
     << std::setw(10) << "completed" << std::setw(12) << "collisions" << std::setw(10) << "left map"
     << std::setw(11) << "path ratio" << std::setw(9) << "m/h" << std::setw(18) << "VO false/accepted"
     << "safe aborts\n";
  for (const auto& g : groups) {
    std::string aborts;
    for (const auto& [reason, n] : g.safe_aborts) aborts += (aborts.empty() ? "" : ", ") + reason + " " + std::to_string(n);
    os << std::left << std::setw(11) << g.group << std::setw(6) << g.runs << std::setw(20)
       << (std::to_string(g.successes) + " of " + std::to_string(g.navigation_runs()) + " (" +
           Pct(g.successes, g.navigation_runs()) + ")")
       << std::setw(10) << g.completed
       << std::setw(12)
       << (std::to_string(g.runs_with_collision) + (g.contacts > 0 ? " (" + std::to_string(g.contacts) + " hits)" : ""))
       << std::setw(10) << g.runs_left_map << std::setw(11)
       << (g.median_path_ratio ? Fixed(*g.median_path_ratio, 2) : "-") << std::setw(9)
       << (g.drive_rate_m_per_h ? Fixed(*g.drive_rate_m_per_h, 1) : "-") << std::setw(18)
       << (std::to_string(g.vo_false) + "/" + std::to_string(g.vo_accepted) + " (" + Pct(g.vo_false, g.vo_accepted) + ")")
       << (aborts.empty() ? "-" : aborts) << "\n";
  }
  std::string grazed;
  for (const auto& g : groups)
    if (g.runs_with_graze > 0) grazed += (grazed.empty() ? "" : ", ") + g.group + " " + std::to_string(g.runs_with_graze);
  if (!grazed.empty()) {
    os << "\nruns whose footprint grazed a rock over the collision height (its rim under the footprint,\n"
          "lower there than the belly's clearance: no collision; in the runs above): "
       << grazed << "\n";
  }
  bool any_shortest = false;
  for (const auto& g : groups) any_shortest |= g.median_shortest_ratio.has_value();
  if (any_shortest) {
    os << "\nshortest safe way on the true world (round every rock over the map's step limit, the centre half\n"
          "the body's width off it; medians over the successful runs):\n";
    os << std::left << std::setw(11) << "world" << std::setw(16) << "shortest ratio" << "driven / shortest\n";
    for (const auto& g : groups) {
      os << std::left << std::setw(11) << g.group << std::setw(16)
         << (g.median_shortest_ratio ? Fixed(*g.median_shortest_ratio, 2) : "-")
         << (g.median_over_shortest ? Fixed(*g.median_over_shortest, 2) : "-") << "\n";
    }
  }
  bool any_way = false;
  for (const auto& g : groups) any_way |= g.runs_way_checked > 0;
  if (any_way) {
    os << "\nthe plan on a perfect map (the stack's planner, its clearance and costs, on the world's exact\n"
          "surface rated by the map's rules; a world without a way cannot be crossed with this clearance):\n";
    os << std::left << std::setw(11) << "world" << std::setw(22) << "worlds with a way" << "success where there is one\n";
    for (const auto& g : groups) {
      if (g.runs_way_checked == 0) continue;
      os << std::left << std::setw(11) << g.group << std::setw(22)
         << (std::to_string(g.runs_with_way) + " of " + std::to_string(g.runs_way_checked))
         << (std::to_string(g.successes_with_way) + " of " + std::to_string(g.navigation_runs_with_way) + " (" +
             Pct(g.successes_with_way, g.navigation_runs_with_way) + ")")
         << "\n";
    }
  }
  os << "\nrover time (share of the sequences' span; VO and mapping overlap):\n";
  os << std::left << std::setw(11) << "world" << std::setw(10) << "hours" << std::setw(10) << "driving"
     << std::setw(10) << "imaging" << std::setw(10) << "VO" << std::setw(10) << "mapping" << std::setw(10)
     << "planning" << std::setw(10) << "waiting" << "steps chosen while driving\n";
  for (const auto& g : groups) {
    auto share = [&](double s) { return g.rover_time_s > 0 ? Fixed(100.0 * s / g.rover_time_s, 1) + " %" : "-"; };
    os << std::left << std::setw(11) << g.group << std::setw(10) << Fixed(g.rover_time_s / 3600.0, 2)
       << std::setw(10) << share(g.driving_s) << std::setw(10) << share(g.imaging_s) << std::setw(10)
       << share(g.vo_s) << std::setw(10) << share(g.mapping_s) << std::setw(10) << share(g.planning_s)
       << std::setw(10) << share(g.waiting_s)
       << (g.steps > 0 ? std::to_string(g.steps_thought_ahead) + " of " + std::to_string(g.steps) : "-") << "\n";
  }
  os << "\npose honesty (POSE against truth over every run's poses; horizontal NEES 2 is honest):\n";
  os << std::left << std::setw(11) << "world" << std::setw(10) << "poses" << std::setw(16) << "NEES mean"
     << "beyond the 99.7 % bound\n";
  for (const auto& g : groups) {
    os << std::left << std::setw(11) << g.group << std::setw(10) << g.horizontal_poses << std::setw(16)
       << (g.horizontal_nees_mean ? Fixed(*g.horizontal_nees_mean, 2) : "-")
       << (g.horizontal_beyond_pct ? Fixed(*g.horizontal_beyond_pct, 2) + " %" : "-") << "\n";
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
    j.Field("runs_with_graze", g.runs_with_graze);
    j.Field("runs_off_map", g.runs_off_map).Field("runs_left_map", g.runs_left_map);
    j.Field("navigation_runs", g.navigation_runs());
    j.Key("safe_aborts").BeginObject();
    for (const auto& [reason, n] : g.safe_aborts) j.Field(reason, n);
    j.EndObject();
    optional("median_path_ratio", g.median_path_ratio);
    optional("median_shortest_ratio", g.median_shortest_ratio);
    optional("median_driven_over_shortest", g.median_over_shortest);
    j.Field("driven_m", g.driven_m).Field("rover_time_s", g.rover_time_s);
    optional("drive_rate_m_per_h", g.drive_rate_m_per_h);
    j.Key("rover_time_breakdown").BeginObject();
    j.Field("driving_s", g.driving_s).Field("imaging_s", g.imaging_s).Field("vo_s", g.vo_s);
    j.Field("mapping_s", g.mapping_s).Field("planning_s", g.planning_s).Field("waiting_s", g.waiting_s);
    j.EndObject();
    j.Field("steps", g.steps).Field("steps_thought_ahead", g.steps_thought_ahead);
    j.Field("vo_updates_accepted", g.vo_accepted).Field("false_updates", g.vo_false);
    j.Field("runs_way_checked", g.runs_way_checked).Field("runs_with_way", g.runs_with_way);
    j.Field("successes_with_way", g.successes_with_way).Field("navigation_runs_with_way", g.navigation_runs_with_way);
    j.Field("horizontal_poses", g.horizontal_poses);
    optional("horizontal_nees_mean", g.horizontal_nees_mean);
    optional("horizontal_beyond_bound_pct", g.horizontal_beyond_pct);
    j.EndObject();
  }
  j.EndArray();
  j.Key("runs").BeginArray();
  for (const auto& r : runs) {
    j.BeginObject();
    j.Field("group", r.group).Field("id", r.id).Field("ran", r.ran).Field("outcome", r.outcome);
    j.Field("abort_reason", r.abort_reason).Field("in_goal_disc", r.in_goal_disc).Field("success", r.success());
    j.Field("verdict", r.Verdict()).Field("left_map", r.left_map());
    j.Field("rock_contacts", r.rock_contacts).Field("rock_grazes", r.rock_grazes).Field("zone_contacts", r.zone_contacts);
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
    optional("shortest_m", r.shortest_m);
    optional("shortest_ratio", r.shortest_ratio());
    j.Key("perfect_way");
    if (r.perfect_way) {
      j.Value(*r.perfect_way);
    } else {
      j.Null();
    }
    optional("perfect_way_m", r.perfect_way && *r.perfect_way ? std::optional<double>(r.perfect_way_m) : std::nullopt);
    j.Field("rover_time_s", r.rover_time_s).Field("vo_updates_accepted", r.vo_accepted).Field("false_updates", r.vo_false);
    j.EndObject();
  }
  j.EndArray();
  j.EndObject();
  return j.str();
}

}  // namespace rover::navbench
