#include "mobility/mobility_options.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rover::mobility {

namespace {

using config::ConfigNode;
constexpr double kDeg = M_PI / 180.0;

const char* const kWheelNames[kNumWheels] = {"left_front",  "left_middle",  "left_rear",
                                             "right_front", "right_middle", "right_rear"};

SoilSlip MakeSoil(std::vector<Eigen::Vector2d> slip, std::vector<Eigen::Vector2d> drift, double turn,
                  double noise) {
  SoilSlip s;
  s.slip_vs_pitch = std::move(slip);
  s.drift_vs_cross_slope = std::move(drift);
  s.turn_slip = turn;
  s.noise_std = noise;
  return s;
}

// A list of [x, y] pairs sorted by x, x in [x_lo, x_hi] and y in [y_lo, y_hi].
std::vector<Eigen::Vector2d> LoadTable(const ConfigNode& t, const char* what, double x_lo, double x_hi,
                                       double y_lo, double y_hi) {
  if (!t.IsSequence() || t.size() < 1) {
    t.Fail(std::string("expected a list of [") + what + "] pairs sorted by the first");
  }
  std::vector<Eigen::Vector2d> table;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const ConfigNode pair = t.at(i);
    const auto v = pair.AsVector(2);
    if (v[0] < x_lo || v[0] > x_hi || v[1] < y_lo || v[1] > y_hi) {
      char buf[160];
      std::snprintf(buf, sizeof(buf), "expected [%s] with the first in [%g, %g] and the second in [%g, %g]",
                    what, x_lo, x_hi, y_lo, y_hi);
      pair.Fail(buf);
    }
    if (!table.empty() && v[0] <= table.back().x()) pair.Fail("expected the first numbers in increasing order");
    table.emplace_back(v[0], v[1]);
  }
  return table;
}

void LoadSoilSlip(const ConfigNode& n, SoilSlip& s) {
  if (n.IsNull()) return;
  n.CheckKeys({"slip_vs_pitch", "drift_vs_cross_slope", "drift_per_deg", "turn_slip", "noise_std"});
  if (n.Has("slip_vs_pitch")) {
    s.slip_vs_pitch = LoadTable(n["slip_vs_pitch"], "pitch_deg, slip", -90.0, 90.0, -5.0, 5.0);
  }
  if (n.Has("drift_vs_cross_slope") && n.Has("drift_per_deg")) {
    n["drift_per_deg"].Fail("give either drift_vs_cross_slope or drift_per_deg, not both");
  }
  if (n.Has("drift_vs_cross_slope")) {
    s.drift_vs_cross_slope =
        LoadTable(n["drift_vs_cross_slope"], "cross_slope_deg, drift per m", 0.0, 90.0, 0.0, 5.0);
  }
  if (n.Has("drift_per_deg")) {
    s.drift_vs_cross_slope.clear();  // the linear form replaces the default table
    n.Get("drift_per_deg", s.drift_per_deg, 0.0, 0.2);
  }
  n.Get("turn_slip", s.turn_slip, -0.5, 0.9);
  n.Get("noise_std", s.noise_std, 0.0, 1.0);
}

}  // namespace

double Interpolate(const std::vector<Eigen::Vector2d>& table, double x) {
  if (table.empty()) return 0.0;
  if (x <= table.front().x()) return table.front().y();
  if (x >= table.back().x()) return table.back().y();
  for (std::size_t i = 1; i < table.size(); ++i) {
    if (x <= table[i].x()) {
      const double t = (x - table[i - 1].x()) / (table[i].x() - table[i - 1].x());
      return table[i - 1].y() + t * (table[i].y() - table[i - 1].y());
    }
  }
  return table.back().y();
}

double SoilSlip::DriftAt(double cross_slope_deg) const {
  const double deg = std::abs(cross_slope_deg);
  return drift_vs_cross_slope.empty() ? drift_per_deg * deg : Interpolate(drift_vs_cross_slope, deg);
}

const char* WheelName(int wheel) {
  if (wheel < 0 || wheel >= kNumWheels) return "none";
  return kWheelNames[wheel];
}

int WheelFromName(const std::string& name) {
  for (int i = 0; i < kNumWheels; ++i) {
    if (name == kWheelNames[i]) return i;
  }
  throw std::invalid_argument("unknown wheel \"" + name +
                              "\" (expected left_front, left_middle, left_rear, right_front, "
                              "right_middle or right_rear)");
}

Eigen::Vector2d RoverGeometry::WheelPosition(int wheel) const {
  const int side = wheel / 3;  // 0 left, 1 right
  const int axle = wheel % 3;  // 0 front, 1 middle, 2 rear
  return {0.5 * wheelbase_m * (1 - axle), (side == 0 ? -0.5 : 0.5) * track_m};
}

// Defaults follow the MER record: loose sand slips ~10-20 % at 10 deg and passes 100 %
// above ~25 deg (Sol 206); a 20 deg outcrop was climbed with little slip (Sol 304);
// sand downslope runs ahead of the wheels and drifts sideways (Wopmay). Sideways slip
// grows steeply past 15 deg of cross slope on loose ground: Spirit on the Columbia Hills
// (Sols 188 to 191) slid down and across the slope so far that it travelled 1.6 m more
// than its wheels said over 19 m.
SlipOptions::SlipOptions() {
  For(terrain::Soil::kBedrock) = MakeSoil({{-35, -0.06}, {0, 0.0}, {15, 0.02}, {25, 0.06}, {35, 0.15}},
                                          {{0, 0.0}, {30, 0.06}}, 0.02, 0.005);
  For(terrain::Soil::kPackedSoil) =
      MakeSoil({{-35, -0.2}, {-15, -0.05}, {0, 0.02}, {10, 0.07}, {20, 0.25}, {30, 0.7}},
               {{0, 0.0}, {10, 0.06}, {15, 0.15}, {20, 0.45}, {25, 0.75}, {30, 1.1}}, 0.05, 0.02);
  For(terrain::Soil::kSand) = MakeSoil({{-35, -0.5},
                                        {-20, -0.2},
                                        {-10, -0.05},
                                        {0, 0.05},
                                        {10, 0.15},
                                        {15, 0.25},
                                        {20, 0.45},
                                        {25, 1.0},
                                        {28, 1.3},
                                        {35, 2.0}},
                                       {{0, 0.0}, {10, 0.12}, {15, 0.18}, {20, 0.35}, {25, 0.7}, {30, 1.2}},
                                       0.1, 0.04);
}

MobilityOptions MobilityOptions::LoadFile(const std::string& path) {
  return Load(ConfigNode::LoadFile(path));
}

MobilityOptions MobilityOptions::Load(const ConfigNode& root) {
  MobilityOptions o;
  const ConfigNode m = root["mobility"];
  m.CheckKeys({"seed", "geometry", "speed_mps", "turn_rate_deg_s", "max_curvature_per_m",
               "max_substep_s", "slip", "rock_collision",
               "deadman_s"});  // deadman_s: read by LoadDeadmanOptions (deadman.hpp)
  m.Get("seed", o.seed);
  if (m.Has("geometry")) {
    const ConfigNode g = m["geometry"];
    g.CheckKeys({"wheelbase_m", "track_m", "wheel_radius_m", "footprint_length_m",
                 "footprint_width_m", "origin_height_m"});
    g.Get("wheelbase_m", o.geometry.wheelbase_m, 0.1, 10.0);
    g.Get("track_m", o.geometry.track_m, 0.1, 10.0);
    g.Get("wheel_radius_m", o.geometry.wheel_radius_m, 0.01, 2.0);
    g.Get("footprint_length_m", o.geometry.footprint_length_m, 0.1, 20.0);
    g.Get("footprint_width_m", o.geometry.footprint_width_m, 0.1, 20.0);
    g.Get("origin_height_m", o.geometry.origin_height_m, -5.0, 5.0);
  }
  m.Get("speed_mps", o.geometry.speed_mps, 1e-4, 2.0);
  double turn_deg_s = o.geometry.turn_rate_rps / kDeg;
  m.Get("turn_rate_deg_s", turn_deg_s, 0.01, 90.0);
  o.geometry.turn_rate_rps = turn_deg_s * kDeg;
  m.Get("max_curvature_per_m", o.geometry.max_curvature_per_m, 0.0, 100.0);
  m.Get("max_substep_s", o.max_substep_s, 1e-4, 1.0);

  if (m.Has("slip")) {
    const ConfigNode s = m["slip"];
    s.CheckKeys({"soils", "noise_time_s", "rock_climb_grade", "rock_stall_slip", "dragged_wheel"});
    if (s.Has("soils")) {
      const ConfigNode soils = s["soils"];
      soils.CheckKeys({"bedrock", "packed_soil", "sand"});
      for (int k = 0; k < terrain::kNumSoils; ++k) {
        const auto soil = static_cast<terrain::Soil>(k);
        LoadSoilSlip(soils[terrain::SoilName(soil)], o.slip.For(soil));
      }
    }
    s.Get("noise_time_s", o.slip.noise_time_s, 0.01, 1e4);
    s.Get("rock_climb_grade", o.slip.rock_climb_grade, 0.0, 10.0);
    s.Get("rock_stall_slip", o.slip.rock_stall_slip, 0.0, 1.0);
    if (s.Has("dragged_wheel")) {
      const ConfigNode d = s["dragged_wheel"];
      d.CheckKeys({"wheel", "encoder", "extra_slip", "yaw_per_m"});
      std::string wheel = "none";
      d.GetEnum("wheel", wheel,
                {"none", "left_front", "left_middle", "left_rear", "right_front", "right_middle",
                 "right_rear"});
      o.slip.dragged.wheel = wheel == "none" ? -1 : WheelFromName(wheel);
      std::string encoder = "zero";
      d.GetEnum("encoder", encoder, {"zero", "commanded"});
      o.slip.dragged.encoder =
          encoder == "zero" ? DraggedWheel::Encoder::kZero : DraggedWheel::Encoder::kCommanded;
      d.Get("extra_slip", o.slip.dragged.extra_slip, -0.5, 1.0);
      d.Get("yaw_per_m", o.slip.dragged.yaw_per_m, -1.0, 1.0);
    }
  }
  if (m.Has("rock_collision")) {
    const ConfigNode r = m["rock_collision"];
    r.CheckKeys({"fault", "max_height_m"});
    r.Get("fault", o.rock_collision.fault);
    r.Get("max_height_m", o.rock_collision.max_height_m, 0.0, 10.0);
  }

  // sensors: may hold other sections (cameras) read by other modules.
  const ConfigNode sensors = root["sensors"];
  if (!sensors.IsNull() && !sensors.IsMap()) sensors.Fail("expected a mapping (key: value)");
  if (sensors.Has("imu")) {
    const ConfigNode i = sensors["imu"];
    i.CheckKeys({"rate_hz", "yaw_drift_deg_per_hour", "yaw_random_walk_deg_per_sqrt_hour",
                 "tilt_noise_deg", "rate_noise_deg_s", "accel_noise_mps2", "gravity_mps2"});
    i.Get("rate_hz", o.imu.rate_hz, 0.1, 2000.0);
    i.Get("yaw_drift_deg_per_hour", o.imu.yaw_drift_deg_per_hour, -3600.0, 3600.0);
    i.Get("yaw_random_walk_deg_per_sqrt_hour", o.imu.yaw_random_walk_deg_per_sqrt_hour, 0.0, 100.0);
    i.Get("tilt_noise_deg", o.imu.tilt_noise_deg, 0.0, 10.0);
    i.Get("rate_noise_deg_s", o.imu.rate_noise_deg_s, 0.0, 10.0);
    i.Get("accel_noise_mps2", o.imu.accel_noise_mps2, 0.0, 10.0);
    i.Get("gravity_mps2", o.imu.gravity_mps2, 0.1, 30.0);
  }
  if (sensors.Has("wheel_encoders")) {
    const ConfigNode e = sensors["wheel_encoders"];
    e.CheckKeys({"rate_hz", "resolution_m"});
    e.Get("rate_hz", o.encoders.rate_hz, 8.0, 2000.0);
    e.Get("resolution_m", o.encoders.resolution_m, 0.0, 0.1);
  }
  return o;
}

}  // namespace rover::mobility
