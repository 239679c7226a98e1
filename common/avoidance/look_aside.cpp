#include "avoidance/look_aside.hpp"

#include <algorithm>
#include <cmath>

namespace rover::avoidance {

UnknownBeside CountUnknownBeside(const Grid& g, const Footprint& footprint, const Pose2& pose,
                                 double behind_reach_m, double min_bearing_rad) {
  // The disc a whole turn in place sweeps, grown by half a cell (as Grid::MarkTurnKnown).
  const double disc = footprint.TurnRadius(0.5 * g.cell_m);
  const double radius = disc + std::max(0.0, behind_reach_m);
  // Rover X forward, Y right; site X north, Y east; yaw clockwise from north.
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  UnknownBeside out;
  const int i0 = std::max(0, static_cast<int>(std::floor((pose.x - radius - g.origin_x) / g.cell_m)));
  const int j0 = std::max(0, static_cast<int>(std::floor((pose.y - radius - g.origin_y) / g.cell_m)));
  for (int i = i0; i < g.rows && g.CellCentreX(i) <= pose.x + radius; ++i)
    for (int j = j0; j < g.cols && g.CellCentreY(j) <= pose.y + radius; ++j) {
      if (g.state[static_cast<std::size_t>(i) * g.cols + j] != CellClass::kUnknown) continue;
      const double dx = g.CellCentreX(i) - pose.x, dy = g.CellCentreY(j) - pose.y;
      const double r = std::hypot(dx, dy);
      if (r > radius) continue;
      const double forward = c * dx + s * dy, right = -s * dx + c * dy;
      const double bearing = std::atan2(std::abs(right), forward);  // 0 ahead .. pi behind
      if (bearing > M_PI - min_bearing_rad) {
        ++out.behind;
      } else if (bearing >= min_bearing_rad && r <= disc) {
        ++(right > 0.0 ? out.right : out.left);
      }
    }
  return out;
}

}  // namespace rover::avoidance
