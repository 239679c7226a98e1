#include "vo_eval/trajectory_plot.hpp"

#include "plot/gnuplot.hpp"

#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rover::vo_eval {
namespace {

// A scratch folder for the data, the script and the picture, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "vo_eval_plot.XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("DrawTopView: cannot make a scratch folder in /tmp");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Writes the finite points, one "x y" per line; false when there are none.
bool WritePoints(const std::string& path, const std::vector<Eigen::Vector2d>& pts) {
  std::ofstream out(path);
  int n = 0;
  for (const auto& p : pts) {
    if (!p.allFinite()) continue;
    out << plot::Num(p.x()) << " " << plot::Num(p.y()) << "\n";
    ++n;
  }
  return n > 0;
}

}  // namespace

double GridSpacing(double range, int target_lines) {
  if (!(range > 0.0) || target_lines < 1) return 1.0;
  const double raw = range / target_lines;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

cv::Mat DrawTopView(const PoseList& truth, const PoseList& estimate,
                    const TopViewOptions& options) {
  const Eigen::Vector3d down = options.down.normalized();
  Eigen::Vector3d fwd = options.forward - options.forward.dot(down) * down;
  if (fwd.norm() < 1e-6) throw std::invalid_argument("DrawTopView: down and forward are parallel");
  fwd.normalize();
  const Eigen::Vector3d right = down.cross(fwd);

  auto to2d = [&](const PoseList& poses) {
    std::vector<Eigen::Vector2d> pts;
    for (const auto& T : poses) pts.emplace_back(T.translation().dot(right), T.translation().dot(fwd));
    return pts;
  };
  const std::vector<Eigen::Vector2d> pt = to2d(truth), pe = to2d(estimate);

  Eigen::Vector2d lo(0, 0), hi(0, 0);
  bool first = true;
  for (const auto* v : {&pt, &pe}) {
    for (const Eigen::Vector2d& p : *v) {
      if (!p.allFinite()) continue;
      lo = first ? p : lo.cwiseMin(p);
      hi = first ? p : hi.cwiseMax(p);
      first = false;
    }
  }
  // Equal scale: a square window around the data, at least 2 m wide.
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 2.0}) * 1.1;
  const double x0 = centre.x() - 0.5 * span, y0 = centre.y() - 0.5 * span;
  const double spacing = GridSpacing(span);

  // gnuplot draws it (Debian gnuplot-nox): the data and a script in a scratch folder.
  const std::string terminal = plot::PngTerminal();
  if (terminal.empty()) {
    throw std::runtime_error("DrawTopView: gnuplot cannot be run (install gnuplot-nox; ./rover setup does)");
  }
  const ScratchDir dir;
  const bool has_truth = WritePoints(dir.path() + "/truth.dat", pt);
  const bool has_estimate = WritePoints(dir.path() + "/estimate.dat", pe);
  std::vector<std::string> plots;
  // Truth wider and first (underneath), so it stays visible where the two agree; a circle
  // at each start.
  if (has_truth) {
    plots.push_back("'truth.dat' using 1:2 with lines lw 5 lc rgb '#289628' title 'ground truth'");
    plots.push_back("'truth.dat' every ::0::0 using 1:2 with points pt 6 ps 2 lw 2 lc rgb '#289628' notitle");
  }
  if (has_estimate) {
    plots.push_back("'estimate.dat' using 1:2 with lines lw 3 lc rgb '#dc1e1e' title 'VO estimate'");
    plots.push_back("'estimate.dat' every ::0::0 using 1:2 with points pt 6 ps 2 lw 2 lc rgb '#dc1e1e' notitle");
  }
  if (plots.empty()) plots.push_back("1/0 notitle");  // axes and grid only
  const int size = std::max(200, options.size_px);
  std::ostringstream gp;
  gp << "set terminal " << terminal << " size " << size << "," << size << " noenhanced\n"
     << "set output 'top.png'\n"
     << "set title " << plot::Quoted(options.title) << "\n"
     << "set xlabel 'right of start heading, m'\nset ylabel 'forward, m'\n"
     << "set size ratio -1\n"
     << "set xrange [" << plot::Num(x0) << ":" << plot::Num(x0 + span) << "]\n"
     << "set yrange [" << plot::Num(y0) << ":" << plot::Num(y0 + span) << "]\n"
     << "set xtics " << plot::Num(spacing) << "\nset ytics " << plot::Num(spacing) << "\n"
     << "set grid lt 1 lc rgb '#dddddd'\n"
     << "set key below horizontal\n"
     << "plot ";
  for (std::size_t i = 0; i < plots.size(); ++i) gp << (i ? ", \\\n     " : "") << plots[i];
  gp << "\n";
  std::ofstream(dir.path() + "/top.gp") << gp.str();
  if (const std::string error = plot::RunGnuplot(dir.path(), "top.gp"); !error.empty()) {
    throw std::runtime_error("DrawTopView: " + error);
  }
  cv::Mat img = cv::imread(dir.path() + "/top.png", cv::IMREAD_COLOR);
  if (img.empty()) throw std::runtime_error("DrawTopView: gnuplot wrote no readable picture");
  return img;
}

}  // namespace rover::vo_eval
