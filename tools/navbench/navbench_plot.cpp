#include "navbench/navbench_plot.hpp"

#include "plot/gnuplot.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace rover::navbench {

namespace {

using plot::Num;
using plot::Quoted;

// Circles as gnuplot's `with circles` reads them: east, north, radius (plots are east
// across, north up, as ./rover plot draws them).
void WriteCircles(const std::string& path, const std::vector<hazards::KeepOutZone>& zones, double min_radius_m) {
  std::ofstream out(path);
  out << "# east_m north_m radius_m\n";
  for (const auto& z : zones) {
    if (z.shape == hazards::KeepOutZone::Shape::kCircle && z.radius_m >= min_radius_m) {
      out << Num(z.center.y()) << " " << Num(z.center.x()) << " " << Num(z.radius_m) << "\n";
    }
  }
}

}  // namespace

std::string PlotRun(const RunPlan& plan, const RunFigures& figures, const RunTrack& track,
                    const std::string& plots_dir) {
  const std::string terminal = plot::PngTerminal();
  if (terminal.empty()) return "gnuplot is not installed (Debian gnuplot-nox)";
  const std::string dir = plots_dir + "/" + plan.id;
  fs::create_directories(dir);
  WriteCircles(dir + "/rocks_over_limit.dat", track.rocks_over_limit, 0);
  WriteCircles(dir + "/rocks_small.dat", track.small_rocks, 0.1);
  WriteCircles(dir + "/zone_circles.dat", track.zones, 0);
  {
    std::ofstream out(dir + "/zone_polygons.dat");
    out << "# east_m north_m; one block per polygon zone\n";
    for (const auto& z : track.zones) {
      if (z.shape != hazards::KeepOutZone::Shape::kPolygon) continue;
      for (std::size_t i = 0; i <= z.vertices.size(); ++i) {
        const auto& v = z.vertices[i % z.vertices.size()];
        out << Num(v.y()) << " " << Num(v.x()) << "\n";
      }
      out << "\n\n";
    }
  }
  {
    std::ofstream out(dir + "/path.dat");
    out << "# east_m north_m (truth)\n";
    for (const auto& p : track.truth) out << Num(p.y) << " " << Num(p.x) << "\n";
  }
  {
    // The footprint where the run ended (block 0) and where each collision began (1, ...).
    std::ofstream out(dir + "/footprints.dat");
    out << "# east_m north_m; one block per footprint\n";
    std::vector<hazards::Pose2> poses = track.contact_poses;
    if (!track.truth.empty()) poses.insert(poses.begin(), track.truth.back());
    for (const auto& pose : poses) {
      const auto corners = track.footprint.Corners(pose);
      for (std::size_t i = 0; i <= corners.size(); ++i) {
        out << Num(corners[i % corners.size()].y()) << " " << Num(corners[i % corners.size()].x()) << "\n";
      }
      out << "\n\n";
    }
  }
  {
    std::ofstream out(dir + "/shortest.dat");
    out << "# east_m north_m (the shortest safe way on the true world)\n";
    for (const auto& p : track.shortest) out << Num(p.y()) << " " << Num(p.x()) << "\n";
  }
  std::ofstream(dir + "/goal.dat") << Num(plan.goal_y) << " " << Num(plan.goal_x) << " " << Num(plan.goal_radius_m)
                                   << "\n";
  std::ofstream(dir + "/start.dat") << "0 0\n";
  // The view: start, goal and path, with a margin, inside the map.
  double e0 = std::min(0.0, plan.goal_y), e1 = std::max(0.0, plan.goal_y);
  double n0 = std::min(0.0, plan.goal_x), n1 = std::max(0.0, plan.goal_x);
  for (const auto& p : track.truth) {
    e0 = std::min(e0, p.y), e1 = std::max(e1, p.y), n0 = std::min(n0, p.x), n1 = std::max(n1, p.x);
  }
  e0 = std::max(e0 - 3, track.map.min_y), e1 = std::min(e1 + 3, track.map.max_y);
  n0 = std::max(n0 - 3, track.map.min_x), n1 = std::min(n1 + 3, track.map.max_x);

  std::string result = figures.Verdict();
  if (figures.collided()) result += ": " + std::to_string(figures.rock_contacts + figures.zone_contacts) + " contact(s)";
  if (figures.collided() && figures.off_map_samples > 0) result += ", a wheel off the map";
  std::ostringstream title;
  title << plan.id << ": " << result << "; straight " << Num(std::round(figures.straight_m * 10) / 10)
        << " m, driven " << Num(std::round(figures.driven_m * 10) / 10) << " m";
  std::ostringstream gp;
  gp << "set terminal " << terminal << " size 900,900 noenhanced\nset output '../" << plan.id << ".png'\n"
     << "set title " << Quoted(title.str()) << "\n"
     << "set xlabel 'east (site y), m'\nset ylabel 'north (site x), m'\nset size ratio -1\n"
     << "set xrange [" << Num(e0) << ":" << Num(e1) << "]\nset yrange [" << Num(n0) << ":" << Num(n1) << "]\n"
     << "set grid back lc rgb '#dddddd'\nset key below center box\nset style fill solid 0.8 noborder\n"
     << "set object 1 rect from " << Num(track.map.min_y) << "," << Num(track.map.min_x) << " to "
     << Num(track.map.max_y) << "," << Num(track.map.max_x) << " fs empty border lc rgb '#000000' lw 2 back\n"
     << "plot 'rocks_small.dat' using 1:2:3 with circles lc rgb '#999999' fs empty title 'rocks under the step limit (>= 0.2 m)', \\\n"
     << "     'rocks_over_limit.dat' using 1:2:3 with circles lc rgb '#cc2222' title 'rocks over the collision height', \\\n"
     << "     'zone_circles.dat' using 1:2:3 with circles fs transparent solid 0.3 lc rgb '#e69f00' title 'keep-out zones', \\\n"
     << "     'zone_polygons.dat' using 1:2 with lines lw 2 lc rgb '#e69f00' notitle, \\\n"
     << "     'goal.dat' using 1:2:3 with circles fs transparent solid 0.25 border lc rgb '#009e73' title 'goal disc', \\\n"
     << "     'shortest.dat' using 1:2 with lines lw 1.5 dt 2 lc rgb '#555555' title 'shortest way round the rocks over the map step limit', \\\n"
     << "     'path.dat' using 1:2 with lines lw 2.5 lc rgb '#0072b2' title 'path (truth)', \\\n"
     << "     'start.dat' using 1:2 with points pt 5 ps 1.5 lc rgb '#009e73' title 'start'";
  if (!track.truth.empty()) {
    gp << ", \\\n     'footprints.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#000000' title 'footprint at the end'";
  }
  if (!track.contact_poses.empty()) {
    gp << ", \\\n     'footprints.dat' index 1:" << track.contact_poses.size()
       << " using 1:2 with lines lw 2 lc rgb '#ff00ff' title 'footprint at a collision'";
  }
  gp << "\n";
  std::ofstream(dir + "/navbench.gp") << gp.str();
  return plot::RunGnuplot(dir, "navbench.gp");
}

}  // namespace rover::navbench
