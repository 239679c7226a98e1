#include "plot/plots.hpp"

#include "plot/gnuplot.hpp"
#include "plot/plot_series.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace rover::plot {
namespace {

// Colours of the traverse picture (a colour-blind-safe set).
constexpr const char* kBlindColour = "#d55e00";
constexpr const char* kVoColour = "#0072b2";
constexpr const char* kWheelColour = "#777777";
constexpr const char* kTruthColour = "#000000";
constexpr const char* kZoneColour = "#e69f00";
constexpr const char* kAvoidColour = "#cc79a7";
constexpr const char* kSteerColour = "#56b4e9";
constexpr const char* kRockColour = "#8c8c8c";
constexpr const char* kGoalColour = "#009e73";

// Site x is north and y east: a map puts east across and north up.
std::string MapRow(const Eigen::Vector3d& p) { return Num(p.x()) + " " + Num(p.y()); }

struct Bounds {
  double min_n = std::numeric_limits<double>::infinity(), max_n = -min_n;
  double min_e = min_n, max_e = -min_n;
  void Add(double n, double e) {
    min_n = std::min(min_n, n);
    max_n = std::max(max_n, n);
    min_e = std::min(min_e, e);
    max_e = std::max(max_e, e);
  }
  bool empty() const { return !(min_n <= max_n); }
};

std::vector<Eigen::Vector2d> Outline(const hazards::KeepOutZone& z) {
  std::vector<Eigen::Vector2d> pts;
  if (z.shape == hazards::KeepOutZone::Shape::kCircle) {
    for (int i = 0; i <= 72; ++i) {
      const double a = 2 * M_PI * i / 72;
      pts.push_back(z.center + z.radius_m * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
  } else {
    pts = z.vertices;
    if (!pts.empty()) pts.push_back(pts.front());
  }
  return pts;
}

Eigen::Vector2d LabelPoint(const hazards::KeepOutZone& z) {
  if (z.shape == hazards::KeepOutZone::Shape::kCircle) return z.center;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& v : z.vertices) c += v;
  return z.vertices.empty() ? c : Eigen::Vector2d(c / double(z.vertices.size()));
}

std::string Header(const PlotPlace& place, const std::string& png, int width, int height) {
  std::ostringstream gp;
  gp << "# Written by ./rover plot (tools/plot); re-run with: gnuplot " << png.substr(0, png.size() - 4)
     << ".gp\n"
     << "set terminal " << place.terminal << " size " << width << "," << height << " noenhanced"
     << (place.terminal == "pngcairo" ? " font 'sans,10'" : "") << "\n"
     << "set output " << Quoted("../" + png) << "\n"
     << "set datafile missing '?'\n";
  return gp.str();
}

PlotOutcome Finish(const PlotPlace& place, const std::string& png, const std::string& script_text) {
  PlotOutcome out;
  out.file = place.out_dir + "/" + png;
  const std::string script = png.substr(0, png.size() - 4) + ".gp";
  std::ofstream(place.data_dir + "/" + script) << script_text;
  const std::string error = RunGnuplot(place.data_dir, script);
  out.written = error.empty();
  out.failed = !error.empty();
  out.note = error;
  return out;
}

// A "final error" line for the titles, when the log has truth.
std::string FinalErrorLine(const DriveLog& log) {
  const auto errors = ErrorSeries(log);
  if (errors.empty()) return "";
  const auto& e = errors.back();
  std::ostringstream os;
  os.precision(3);
  os << std::fixed << "after " << e.distance_m << " m: on-board estimate off by " << e.estimate_error_m
     << " m, wheel odometry alone by " << e.wheel_only_error_m << " m";
  return os.str();
}

std::string StatusText(const rover_msgs::sequence_status_t& st) {
  static const char* names[] = {"idle", "running", "paused", "completed", "aborted", "rejected"};
  const int s = st.state;
  std::string text = s >= 0 && s < 6 ? names[s] : "state " + std::to_string(s);
  if (!st.abort_reason.empty()) text += " (" + st.abort_reason + ")";
  return text;
}

// How each sequence in the log ended; with several, each is named.
std::string OutcomeText(const DriveLog& log) {
  if (log.runs.size() <= 1) {
    return log.final_status ? StatusText(*log.final_status) : "no final sequence status in the log";
  }
  std::string text;
  for (const auto& r : log.runs) {
    text += (text.empty() ? "" : "; ") + std::filesystem::path(r.name).filename().string() + " " +
            (r.final_status ? StatusText(*r.final_status) : std::string("without a final status"));
  }
  return text;
}

}  // namespace

TicSpacing TicsFor(double span_m) {
  for (const double label : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0}) {
    if (span_m / label <= 12) {
      const int minor = span_m <= 150 ? static_cast<int>(label) : 1;
      return {label, std::max(1, minor)};
    }
  }
  return {std::ceil(span_m / 10000) * 1000, 1};
}

PlotOutcome WriteTraversePlot(const DriveLog& log, const PlotPlace& place) {
  PlotOutcome out;
  out.file = place.out_dir + "/traverse.png";
  if (log.estimate.empty() && log.truth.empty()) {
    out.note = "traverse.png: not written: the log has neither POSE nor SIM_TRUTH";
    return out;
  }
  const std::string dir = place.data_dir + "/";
  Bounds b;
  std::vector<std::string> plots;

  // The world's rocks (simulation), under everything; they do not widen the picture.
  if (!log.rocks.empty()) {
    std::ofstream rocks(dir + "traverse_rocks.dat"), labels(dir + "traverse_rock_labels.dat");
    for (const auto& r : log.rocks) {
      rocks << Num(r.position.x()) << " " << Num(r.position.y()) << " " << Num(0.5 * r.diameter_m) << "\n";
      if (!r.name.empty()) labels << Num(r.position.x()) << " " << Num(r.position.y()) << " \"" << r.name << "\"\n";
    }
    plots.push_back(std::string("'traverse_rocks.dat' using 2:1:3 with circles fc rgb '") + kRockColour +
                    "' fs transparent solid 0.55 noborder title 'rocks of the world (taller than 10 cm)'");
    plots.push_back("'traverse_rock_labels.dat' using 2:1:3 with labels offset 0,-0.9 tc rgb '#555555' notitle");
  }
  // Each goto's goal disc, and its target.
  if (!log.goals.empty()) {
    std::ofstream goals(dir + "traverse_goals.dat");
    for (const auto& g : log.goals) {
      goals << Num(g.target.x()) << " " << Num(g.target.y()) << " " << Num(g.radius_m) << "\n";
      b.Add(g.target.x() + g.radius_m, g.target.y() + g.radius_m);
      b.Add(g.target.x() - g.radius_m, g.target.y() - g.radius_m);
    }
    plots.push_back(std::string("'traverse_goals.dat' using 2:1:3 with circles lw 2 lc rgb '") + kGoalColour +
                    "' fs empty title 'goto goal disc'");
    plots.push_back(std::string("'traverse_goals.dat' using 2:1 with points pt 1 ps 1.5 lw 2 lc rgb '") + kGoalColour +
                    "' notitle");
  }
  // Keep-out zones, so the paths are drawn over them.
  if (!log.zones.empty()) {
    std::ofstream zones(dir + "traverse_zones.dat"), labels(dir + "traverse_zone_labels.dat");
    for (const auto& z : log.zones) {
      zones << "# " << z.zone.name << "\n";
      for (const auto& p : Outline(z.zone)) {
        zones << Num(p.x()) << " " << Num(p.y()) << "\n";
        b.Add(p.x(), p.y());
      }
      zones << "\n\n";
      const auto c = LabelPoint(z.zone);
      labels << Num(c.x()) << " " << Num(c.y()) << " \"" << z.zone.name << "\"\n";
    }
    plots.push_back("for [i=0:" + std::to_string(log.zones.size() - 1) +
                    "] 'traverse_zones.dat' index i using 2:1 with filledcurves closed fc rgb '" +
                    kZoneColour + "' fs transparent solid 0.35 border lc rgb '" + kZoneColour +
                    "' title (i == 0 ? 'keep-out zone' : '')");
    plots.push_back("'traverse_zone_labels.dat' using 2:1:3 with labels tc rgb '#8a5a00' notitle");
  }
  if (!log.truth.empty()) {
    std::ofstream f(dir + "traverse_truth.dat");
    Eigen::Vector3d last = log.truth.front().p;
    f << MapRow(last) << "\n";
    for (const auto& t : log.truth) {
      b.Add(t.p.x(), t.p.y());
      if ((t.p - last).norm() < 0.01 && &t != &log.truth.back()) continue;
      f << MapRow(t.p) << "\n";
      last = t.p;
    }
    plots.push_back(std::string("'traverse_truth.dat' using 2:1 with lines lw 2.5 lc rgb '") +
                    kTruthColour + "' title 'true path (SIM_TRUTH)'");
  }
  if (!log.wheel_only.empty()) {
    std::ofstream f(dir + "traverse_wheel_only.dat");
    const Eigen::Vector3d* last = nullptr;
    for (const auto& w : log.wheel_only) {
      b.Add(w.p.x(), w.p.y());
      if (last != nullptr && (w.p - *last).norm() < 0.01 && &w != &log.wheel_only.back()) continue;
      f << MapRow(w.p) << "\n";
      last = &w.p;
    }
    plots.push_back(std::string("'traverse_wheel_only.dat' using 2:1 with lines lw 1.5 dt 2 lc rgb '") +
                    kWheelColour + "' title 'wheel odometry + IMU only'");
  }
  // The on-board estimate, one file per mode; segments are separated by blank lines.
  const auto segments = EstimateSegments(log);
  for (const Mode mode : {Mode::kBlind, Mode::kVo}) {
    const bool vo = mode == Mode::kVo;
    const std::string file = vo ? "traverse_estimate_vo.dat" : "traverse_estimate_blind.dat";
    std::ofstream f(dir + file);
    int points = 0;
    for (const auto& s : segments) {
      if (s.mode != mode) continue;
      for (const auto& p : s.points) {
        f << MapRow(p) << "\n";
        b.Add(p.x(), p.y());
        ++points;
      }
      f << "\n";
    }
    if (points == 0) continue;
    plots.push_back("'" + file + "' using 2:1 with lines lw 2 lc rgb '" + (vo ? kVoColour : kBlindColour) +
                    "' title '" +
                    (vo ? "on-board estimate: VO-corrected steps"
                        : "on-board estimate: blind steps (wheel odometry + IMU)") +
                    "'");
  }
  // Steps of hazard avoidance (`goto ... avoid on`): their own colours over the estimate,
  // from each step's start to its end: those arc voting chose, and those that steered
  // straight at the goal because the way was clear (each step report's `choice`).
  {
    // And where a step began without waiting for the map of the pair taken there: chosen on
    // the map in hand and driven while that pair was mapped (thinking while driving).
    std::ofstream voted(dir + "traverse_avoid.dat"), steered(dir + "traverse_steer.dat"),
        ahead(dir + "traverse_ahead.dat");
    int n_voted = 0, n_steered = 0, n_ahead = 0;
    for (const auto& s : log.steps) {
      if (s.choice == rover_msgs::step_report_t::CHOICE_COMMAND) continue;
      const bool steer = s.choice == rover_msgs::step_report_t::CHOICE_STEER_AT_GOAL;
      (steer ? steered : voted) << Num(s.pose_before[0]) << " " << Num(s.pose_before[1]) << "\n"
                                << Num(s.pose_after[0]) << " " << Num(s.pose_after[1]) << "\n\n";
      b.Add(s.pose_after[0], s.pose_after[1]);
      ++(steer ? n_steered : n_voted);
      if (s.thought_ahead) {
        ahead << Num(s.pose_before[0]) << " " << Num(s.pose_before[1]) << "\n";
        ++n_ahead;
      }
    }
    if (n_voted > 0) {
      plots.push_back(std::string("'traverse_avoid.dat' using 2:1 with lines lw 4 lc rgb '") + kAvoidColour +
                      "' title 'hazard-avoidance steps (arc voting)'");
    }
    if (n_steered > 0) {
      plots.push_back(std::string("'traverse_steer.dat' using 2:1 with lines lw 4 lc rgb '") + kSteerColour +
                      "' title 'avoid on, way clear: steered straight at the goal (no vote)'");
    }
    if (n_ahead > 0) {
      plots.push_back(
          "'traverse_ahead.dat' using 2:1 with points pt 9 ps 1.5 lc rgb '#332288' title 'step chosen while driving "
          "(no stop to think)'");
    }
  }
  if (!log.estimate.empty()) {
    std::ofstream(dir + "traverse_start.dat") << MapRow(log.estimate.front().p) << "\n";
    plots.push_back("'traverse_start.dat' using 2:1 with points pt 5 ps 1.6 lc rgb '#009e73' title 'start'");
  }
  if (!log.steps.empty()) {
    std::ofstream f(dir + "traverse_step_ends.dat");
    for (const auto& s : log.steps) {
      f << Num(s.pose_after[0]) << " " << Num(s.pose_after[1]) << "\n";
      b.Add(s.pose_after[0], s.pose_after[1]);
    }
    plots.push_back("'traverse_step_ends.dat' using 2:1 with points pt 6 ps 0.9 lw 1.2 lc rgb '#333333' "
                    "title 'step ends (on-board estimate)'");
  }
  // Where each aborted sequence stopped.
  std::vector<std::pair<std::string, rover_msgs::sequence_status_t>> aborts;  // sequence name, status
  for (const auto& r : log.runs) {
    if (r.final_status && r.final_status->state == rover_msgs::sequence_status_t::STATE_ABORTED) {
      aborts.emplace_back(r.name, *r.final_status);
    }
  }
  if (log.runs.empty() && log.final_status && log.final_status->state == rover_msgs::sequence_status_t::STATE_ABORTED) {
    aborts.emplace_back(log.final_status->sequence_name, *log.final_status);
  }
  for (std::size_t i = 0; i < aborts.size(); ++i) {
    const auto& [name, st] = aborts[i];
    const std::string file = "traverse_abort" + (i ? std::to_string(i + 1) : std::string()) + ".dat";
    std::ofstream(dir + file) << Num(st.pose[0]) << " " << Num(st.pose[1]) << "\n";
    b.Add(st.pose[0], st.pose[1]);
    plots.push_back("'" + file + "' using 2:1 with points pt 2 ps 3 lw 3 lc rgb '#cc0000' title " +
                    Quoted("abort: " + (log.runs.size() > 1 ? name + ": " : std::string()) + st.abort_reason));
  }

  // Equal axes over everything shown, with half a metre around it.
  const double margin = 0.5;
  double e0 = std::floor(b.min_e - margin), e1 = std::ceil(b.max_e + margin);
  double n0 = std::floor(b.min_n - margin), n1 = std::ceil(b.max_n + margin);
  // A square window (the picture is square): the narrower side grows about its middle.
  const double side = std::max(e1 - e0, n1 - n0);
  const auto widen = [side](double& lo, double& hi) {
    const double grow = side - (hi - lo);
    lo -= std::floor(grow / 2);
    hi += grow - std::floor(grow / 2);
  };
  widen(e0, e1);
  widen(n0, n1);
  const TicSpacing tics = TicsFor(std::max(e1 - e0, n1 - n0));
  std::ostringstream gp;
  gp << Header(place, "traverse.png", 900, 950);
  const std::string final_line = FinalErrorLine(log);
  gp << "set title " << Quoted(WrapTitle(place.title + ": traverse, " + OutcomeText(log) +
                                             (final_line.empty() ? "" : "\n" + final_line),
                                         TitleChars(900)))
     << "\n"
     << "set xlabel 'east (site y), m'\nset ylabel 'north (site x), m'\n"
     << "set size ratio -1\n"
     << "set xrange [" << Num(e0) << ":" << Num(e1) << "]\n"
     << "set yrange [" << Num(n0) << ":" << Num(n1) << "]\n"
     << "set xtics " << Num(tics.label_m) << "\nset ytics " << Num(tics.label_m) << "\n"
     << "set mxtics " << tics.minor_per_label << "\nset mytics " << tics.minor_per_label << "\n"
     << "set grid xtics ytics mxtics mytics back lt 1 lw 1 lc rgb '#bbbbbb', lt 1 lw 1 lc rgb '#dddddd'\n"
     << "set key below center box\n"
     << "plot ";
  for (std::size_t i = 0; i < plots.size(); ++i) gp << (i ? ", \\\n     " : "") << plots[i];
  gp << "\n";
  out = Finish(place, "traverse.png", gp.str());
  if (out.written) {
    int vo_steps = 0;
    for (const auto& s : log.steps) vo_steps += s.vo_status == rover_msgs::vo_update_t::STATUS_OK;
    out.note = std::to_string(log.steps.size()) + " steps (" + std::to_string(vo_steps) +
               " VO-corrected), " + std::to_string(log.zones.size()) + " keep-out zones, " +
               std::to_string(log.goals.size()) + " goal discs, " + std::to_string(log.rocks.size()) + " rocks" +
               (log.runs.size() > 1 ? ", " + std::to_string(log.runs.size()) + " sequences" : "") +
               (log.truth.empty() ? ", no truth" : "");
  }
  return out;
}

PlotOutcome WriteErrorPlot(const DriveLog& log, const PlotPlace& place) {
  PlotOutcome out;
  out.file = place.out_dir + "/error.png";
  if (log.truth.empty()) {
    out.note = "error.png: not written: no SIM_TRUTH in the log (the error needs the true path)";
    return out;
  }
  const auto series = ErrorSeries(log);
  if (series.size() < 2) {
    out.note = "error.png: not written: the log has too few poses alongside the truth";
    return out;
  }
  {
    std::ofstream f(place.data_dir + "/error.dat");
    f << "# distance_travelled_m wheel_only_error_m estimate_error_m\n";
    for (const auto& e : series) {
      f << Num(e.distance_m) << " " << Num(e.wheel_only_error_m) << " " << Num(e.estimate_error_m) << "\n";
    }
  }
  std::ostringstream gp;
  gp << Header(place, "error.png", 900, 600);
  gp << "set title "
     << Quoted(WrapTitle(place.title + ": position error against distance travelled\n" + FinalErrorLine(log),
                         TitleChars(900)))
     << "\n"
     << "set xlabel 'distance travelled (truth), m'\nset ylabel 'position error (3-D), m'\n"
     << "set xrange [0:*]\nset yrange [0:*]\nset grid\nset key top left box opaque\n"
     << "plot 'error.dat' using 1:2 with lines lw 2 dt 2 lc rgb '" << kWheelColour
     << "' title 'wheel odometry + IMU only', \\\n"
     << "     'error.dat' using 1:3 with lines lw 2 lc rgb '" << kVoColour
     << "' title 'on-board estimate', \\\n"
     << "     0.1 * x with lines lw 1.5 dt 4 lc rgb '#cc0000' title '10 % of distance (design requirement)'\n";
  out = Finish(place, "error.png", gp.str());
  if (out.written) out.note = FinalErrorLine(log);
  return out;
}

PlotOutcome WriteSlipPlot(const DriveLog& log, const PlotPlace& place) {
  PlotOutcome out;
  out.file = place.out_dir + "/slip.png";
  const auto rows = SlipRows(log);
  if (rows.empty()) {
    // The picture is still there (every run leaves one), and says why it is empty.
    std::ostringstream gp;
    gp << Header(place, "slip.png", 900, 400)
       << "set title " << Quoted(WrapTitle(place.title + ": progress and slip per step, " + OutcomeText(log), TitleChars(900)))
       << "\n"
       << "set xrange [0:1]\nset yrange [0:1]\nunset xtics\nunset ytics\n"
       << "set label 'no step was driven (no STEP_REPORT in the log)' at graph 0.5, 0.5 center\n"
       << "plot 1/0 notitle\n";
    out = Finish(place, "slip.png", gp.str());
    if (out.written) out.note = "no step was driven: the picture says so";
    return out;
  }
  bool any_limit = false, any_truth = false, any_slip = false, any_true_slip = false;
  {
    std::ofstream f(place.data_dir + "/slip.dat");
    f << "# step command step_in_command commanded_m measured_m true_m measured_slip_pct true_slip_pct "
         "limit_pct measured_by_vo\n";
    const auto opt = [](const std::optional<double>& v) { return v ? Num(*v) : std::string("?"); };
    for (const auto& r : rows) {
      f << r.number << " " << r.command_index + 1 << " " << r.step_index + 1 << " " << Num(r.commanded_m)
        << " " << Num(r.measured_m) << " " << opt(r.true_m) << " " << opt(r.measured_slip_pct) << " "
        << opt(r.true_slip_pct) << " " << opt(r.limit_pct) << " " << (r.vo ? 1 : 0) << "\n";
      any_limit = any_limit || r.limit_pct.has_value();
      any_truth = any_truth || r.true_m.has_value();
      any_slip = any_slip || r.measured_slip_pct.has_value();
      any_true_slip = any_true_slip || r.true_slip_pct.has_value();
    }
  }
  std::ostringstream gp;
  gp << Header(place, "slip.png", 900, 850);
  gp << "set multiplot layout 2,1 title "
     << Quoted(WrapTitle(place.title + ": progress and slip per step, " + OutcomeText(log), TitleChars(900)))
     << "\n"
     << "set grid\nset key below horizontal maxrows 2\nset xrange [0.5:" << rows.size() << ".5]\n"
     << "set offsets 0, 0, graph 0.05, graph 0.05\n"
     << "set xtics 1\n" << (rows.size() > 30 ? "set xtics 5\n" : "")
     << "unset xlabel\n"
     << "set ylabel 'progress along the commanded direction, m'\n"
     << "plot 'slip.dat' using 1:4 with points pt 5 ps 1.2 lc rgb '#555555' title 'commanded', \\\n"
     << "     'slip.dat' using 1:($10 == 1 ? $5 : 1/0) with points pt 7 ps 1.2 lc rgb '" << kVoColour
     << "' title 'measured (VO-corrected)', \\\n"
     << "     'slip.dat' using 1:($10 == 1 ? 1/0 : $5) with points pt 6 ps 1.2 lc rgb '" << kBlindColour
     << "' title 'measured (blind: wheel odometry)'";
  if (any_truth) gp << ", \\\n     'slip.dat' using 1:6 with points pt 2 ps 1.4 lw 2 lc rgb '#000000' title 'true'";
  gp << "\n"
     << "set xlabel 'step (in order)'\nset ylabel 'slip, %'\n";
  std::vector<std::string> slip_plots;
  if (any_slip) {
    slip_plots.push_back(std::string("'slip.dat' using 1:($10 == 1 ? $7 : 1/0) with linespoints pt 7 lc rgb '") +
                         kVoColour + "' title 'measured slip (VO)'");
    slip_plots.push_back(std::string("'slip.dat' using 1:($10 == 1 ? 1/0 : $7) with points pt 6 ps 1.2 lc rgb '") +
                         kBlindColour + "' title 'blind step: wheel odometry cannot see slip'");
  }
  if (any_true_slip) {
    slip_plots.push_back("'slip.dat' using 1:8 with linespoints pt 2 lw 2 dt 2 lc rgb '#000000' title 'true slip'");
  }
  if (any_limit) {
    slip_plots.push_back("'slip.dat' using 1:9 with steps lw 2 dt 4 lc rgb '#cc0000' title 'slip limit'");
  }
  if (slip_plots.empty()) {
    gp << "set yrange [-10:110]\n";
    slip_plots.push_back("0 with lines lc rgb '#999999' title 'no step commanded a distance (turns only)'");
  }
  gp << "plot ";
  for (std::size_t i = 0; i < slip_plots.size(); ++i) gp << (i ? ", \\\n     " : "") << slip_plots[i];
  gp << "\nunset multiplot\n";
  out = Finish(place, "slip.png", gp.str());
  if (out.written) out.note = std::to_string(rows.size()) + " steps" + (any_limit ? "" : ", no slip limit in force");
  return out;
}

}  // namespace rover::plot
