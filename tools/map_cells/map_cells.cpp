#include "map_cells/map_cells.hpp"

#include "avoidance/tops_over_ground.hpp"
#include "bus/channels.hpp"
#include "bus/traversability_convert.hpp"
#include "bus/validate.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/traversability_map_t.hpp>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>

namespace rover::map_cells {
namespace {

MapReading ReadMap(const rover_msgs::traversability_map_t& m, const Query& q) {
  const avoidance::Grid g = bus::GridFromMsg(m);
  MapReading r;
  r.utime = m.utime;
  r.last_frame_id = m.last_frame_id;
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double cx = g.CellCentreX(i), cy = g.CellCentreY(j);
      if (std::hypot(cx - q.x, cy - q.y) > q.radius_m) continue;
      const int k = i * g.cols + j;
      CellReading c;
      c.x = cx;
      c.y = cy;
      c.state = static_cast<int>(g.state[k]);
      c.step_m = g.step_m[k];
      c.goodness = g.goodness[k];
      if (g.HasHeights()) {
        c.elevation_m = g.elevation_m[k];
        c.sigma_m = g.sigma_m[k];
        c.top_over_ground_m = avoidance::TopOverGround(g, k, q.ground_radius_m, q.band_m);
      }
      r.cells.push_back(c);
    }
  return r;
}

const char* StateName(int s) {
  switch (s) {
    case rover_msgs::traversability_map_t::STATE_SAFE: return "safe";
    case rover_msgs::traversability_map_t::STATE_CAUTION: return "caution";
    case rover_msgs::traversability_map_t::STATE_UNSAFE: return "unsafe";
    default: return "unknown";
  }
}

}  // namespace

History ReadHistory(const std::string& log_path, const Query& q) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error(log_path + ": cannot open the log (expected an LCM log file)");
  History h;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel != channels::kTraversabilityMap) continue;
    rover_msgs::traversability_map_t m;
    if (m.decode(ev->data, 0, ev->datalen) < 0 || !bus::Problem(m).empty()) {
      ++h.undecodable;
      continue;
    }
    h.maps.push_back(ReadMap(m, q));
  }
  return h;
}

void Print(const History& h, const Query& q, std::ostream& out) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "map cells within %.2f m of (%.2f, %.2f): %zu maps", q.radius_m, q.x, q.y,
                h.maps.size());
  out << buf;
  if (h.undecodable > 0) out << ", " << h.undecodable << " undecodable (left out)";
  out << "\neach cell: centre x,y  state  step m  top m (sigma)  top over the ground round it m\n";
  std::map<int, int> maps_rating;  // state -> maps in which some cell had it
  for (const MapReading& r : h.maps) {
    std::snprintf(buf, sizeof buf, "t %.3f s  frame %lld:", r.utime * 1e-6, static_cast<long long>(r.last_frame_id));
    out << buf;
    if (r.cells.empty()) out << " (outside the map)";
    std::map<int, bool> seen;
    for (const CellReading& c : r.cells) {
      seen[c.state] = true;
      std::snprintf(buf, sizeof buf, "  %.1f,%.1f %s %.2f", c.x, c.y, StateName(c.state), c.step_m);
      out << buf;
      if (c.sigma_m >= 0) {
        std::snprintf(buf, sizeof buf, " %.2f (%.2f)", c.elevation_m, c.sigma_m);
        out << buf;
        if (c.top_over_ground_m >= 0) {
          std::snprintf(buf, sizeof buf, " +%.2f", c.top_over_ground_m);
          out << buf;
        }
      }
    }
    out << "\n";
    for (const auto& [s, yes] : seen) maps_rating[s] += yes;
  }
  for (int s = 0; s <= 3; ++s) out << "maps with a cell " << StateName(s) << ": " << maps_rating[s] << "\n";
}

}  // namespace rover::map_cells
