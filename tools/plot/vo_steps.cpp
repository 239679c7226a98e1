#include "plot/vo_steps.hpp"

#include "bus/convert.hpp"
#include "bus/stereo_frame_convert.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_model.hpp"
#include "imaging/image_check.hpp"
#include "plot/gnuplot.hpp"
#include "plot/plot_series.hpp"
#include "vo/motion_prior.hpp"
#include "vo/visual_odometry.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <iomanip>
#include <sstream>

namespace fs = std::filesystem;

namespace rover::plot {
namespace {

vo::VoResult Recompute(const vo::VoOptions& options, const vo::MotionPriorOptions& prior,
                       const vo::StereoImages& prev, const rover_msgs::stereo_frame_t& prev_frame,
                       const vo::StereoImages& curr, const rover_msgs::stereo_frame_t& curr_frame) {
  vo::VisualOdometry vo(options);
  const Eigen::Matrix<double, 6, 6> unit = Eigen::Matrix<double, 6, 6>::Identity();
  vo.Process(prev, Eigen::Isometry3d::Identity(), unit);
  const Eigen::Isometry3d T = bus::PoseFromMsg(prev_frame.pose_at_capture).inverse() *
                              bus::PoseFromMsg(curr_frame.pose_at_capture);
  const Eigen::Matrix<double, 6, 6> cov = vo::MotionPriorCovariance(T, prior);
  return vo.Process(curr, T, cov);
}

// A working-resolution pixel at full size ((0,0) is the centre of the top-left pixel).
Eigen::Vector2d FullSize(const Eigen::Vector2d& u, double scale) {
  return (u.array() + 0.5) / scale - 0.5;
}

std::string TwoDigits(int n) {
  std::ostringstream os;
  os << std::setw(2) << std::setfill('0') << n;
  return os.str();
}

}  // namespace

VoStepsOutcome WriteVoSteps(const DriveLog& log, const std::string& vo_config, int max_steps,
                            const PlotPlace& place) {
  VoStepsOutcome out;
  const std::string dir = place.out_dir + "/vo_steps";
  fs::create_directories(dir);
  for (const auto& old : fs::directory_iterator(dir)) {
    if (old.path().extension() == ".png") fs::remove(old.path());
  }
  std::ofstream readme(dir + "/README.txt");
  readme << "Written by ./rover plot (tools/plot/vo_steps.hpp). Each step_NN.png is the left image of\n"
            "a step's later VO frame with the features tracked from the earlier frame: a line from\n"
            "where the feature was to where it was found, inliers of the motion estimate in one\n"
            "colour, outliers in another. The tracks are recomputed with common/vo from the two\n"
            "frames in the log; the title gives the logged and the recomputed counts.\n\n";
  const auto choices = ChooseVoSteps(log, max_steps);
  if (choices.empty()) {
    out.note = "vo_steps/: no picture: " +
               std::string(max_steps == 0 ? "--vo-steps 0"
                           : log.steps.empty() ? "no step was driven"
                                               : "no step was measured by VO (VO off, or every update failed)");
    readme << out.note << "\n";
    return out;
  }
  // Which steps: not every one, but up to max_steps spread evenly over the drive.
  const std::size_t measured = ChooseVoSteps(log, std::numeric_limits<int>::max()).size();
  readme << "These are " << choices.size() << " of the " << measured << " steps VO measured";
  if (choices.size() < measured) {
    readme << ", spread evenly over the drive (about every "
           << static_cast<int>(std::lround(double(measured - 1) / std::max<std::size_t>(1, choices.size() - 1)))
           << " steps)";
  }
  readme << "; ./rover plot --vo-steps N draws N of them (default 6).\n\n";
  vo::VoOptions options;
  vo::MotionPriorOptions prior;
  try {
    const auto root = config::ConfigNode::LoadFile(vo_config);
    options = vo::LoadVoOptions(root["vo"]);
    prior = vo::LoadMotionPriorOptions(root["visual_odometry"]);
  } catch (const std::exception& e) {
    out.failed = true;
    out.note = std::string("vo_steps/: no picture: ") + e.what();
    readme << out.note << "\n";
    return out;
  }
  std::set<std::int64_t> ids;
  for (const auto& c : choices) {
    ids.insert(c.update.from_frame_id);
    ids.insert(c.update.to_frame_id);
  }
  const auto frames = ReadStereoFrames(log.path, ids);
  std::vector<std::string> problems;
  for (const auto& c : choices) {
    const std::string name = "step_" + TwoDigits(c.number);
    const auto from = frames.find(c.update.from_frame_id);
    const auto to = frames.find(c.update.to_frame_id);
    if (from == frames.end() || to == frames.end()) {
      problems.push_back(name + ": frame " +
                         std::to_string(from == frames.end() ? c.update.from_frame_id : c.update.to_frame_id) +
                         " is not in the log");
      continue;
    }
    vo::StereoImages prev, curr;
    const imaging::ImageLimits limits;
    std::string bad = bus::ToStereoImages(from->second, limits, prev);
    if (!bad.empty()) bad = "frame " + std::to_string(from->second.frame_id) + ": " + bad;
    if (bad.empty()) {
      bad = bus::ToStereoImages(to->second, limits, curr);
      if (!bad.empty()) bad = "frame " + std::to_string(to->second.frame_id) + ": " + bad;
    }
    if (!bad.empty()) {
      problems.push_back(name + ": " + bad);
      continue;
    }
    vo::VoResult r;
    try {
      r = Recompute(options, prior, prev, from->second, curr, to->second);
    } catch (const std::exception& e) {
      problems.push_back(name + ": VO failed: " + e.what());
      continue;
    }
    // The image, and the tracks at full size: from where, to where, inlier.
    cv::imwrite(place.data_dir + "/" + name + "_left.png", curr.left);
    int inliers = 0;
    {
      std::ofstream f(place.data_dir + "/" + name + "_tracks.dat");
      f << "# prev_u prev_v curr_u curr_v inlier (full-size pixels of the left image)\n";
      for (const auto& t : r.tracks) {
        const Eigen::Vector2d a = FullSize(t.prev_left, options.working_scale);
        const Eigen::Vector2d b = FullSize(t.curr_left, options.working_scale);
        f << Num(a.x()) << " " << Num(a.y()) << " " << Num(b.x()) << " " << Num(b.y()) << " "
          << (t.inlier ? 1 : 0) << "\n";
        inliers += t.inlier;
      }
    }
    const int w = curr.left.cols, h = curr.left.rows;
    const int outliers = static_cast<int>(r.tracks.size()) - inliers;
    std::ostringstream title;
    title << place.title << ": step " << c.number << " (command " << c.step.command_index + 1 << ", step "
          << c.step.step_index + 1 << ")\nframes " << c.update.from_frame_id << " -> " << c.update.to_frame_id
          << "\nlogged: " << c.update.num_tracked << " tracked, " << c.update.num_inliers
          << " inliers; recomputed: " << r.tracks.size() << " tracked, " << inliers << " inliers ("
          << vo::ToString(r.status) << ")";
    std::ostringstream gp;
    gp << "# Written by ./rover plot (tools/plot/vo_steps.cpp); re-run with: gnuplot " << name << ".gp\n"
       << "set terminal " << place.terminal << " size " << std::max(720, w + 100) << "," << std::max(400, h + 170)
       << " noenhanced" << (place.terminal == "pngcairo" ? " font 'sans,10'" : "") << "\n"
       << "set output " << Quoted("../vo_steps/" + name + ".png") << "\n"
       << "set title " << Quoted(WrapTitle(title.str(), TitleChars(std::max(720, w + 100)))) << "\n"
       << "set size ratio -1\nunset colorbox\nset palette gray\n"
       // Image rows grow downward: the y axis is reversed so (u, v) is where the pixel is.
       << "set xrange [-0.5:" << w - 0.5 << "]\nset yrange [" << h - 0.5 << ":-0.5]\n"
       << "set xlabel 'u, px'\nset ylabel 'v, px'\n"
       << "set key below horizontal\n"
       << "plot " << Quoted(name + "_left.png") << " binary filetype=png flipy with rgbimage notitle, \\\n"
       << "     " << Quoted(name + "_tracks.dat")
       << " using 1:2:($3-$1):($4-$2):($5 == 1 ? 1/0 : 1) with vectors nohead lw 1.5 lc rgb '#ff3030' notitle, \\\n"
       << "     " << Quoted(name + "_tracks.dat")
       << " using 3:($5 == 1 ? 1/0 : $4) with points pt 6 ps 0.8 lw 1.5 lc rgb '#ff3030' title "
       << Quoted("outliers (" + std::to_string(outliers) + ")") << ", \\\n"
       << "     " << Quoted(name + "_tracks.dat")
       << " using 1:2:($3-$1):($4-$2):($5 == 1 ? 1 : 1/0) with vectors nohead lw 1.5 lc rgb '#30ff30' notitle, \\\n"
       << "     " << Quoted(name + "_tracks.dat")
       << " using 3:($5 == 1 ? $4 : 1/0) with points pt 7 ps 0.6 lc rgb '#30ff30' title "
       << Quoted("inliers (" + std::to_string(inliers) + "): line from the previous position") << "\n";
    std::ofstream(place.data_dir + "/" + name + ".gp") << gp.str();
    if (std::string error = RunGnuplot(place.data_dir, name + ".gp"); !error.empty()) {
      problems.push_back(name + ": " + error);
      continue;
    }
    ++out.written;
    readme << name << ".png: step " << c.number << " (command " << c.step.command_index + 1 << ", step "
           << c.step.step_index + 1 << "), frames " << c.update.from_frame_id << " -> "
           << c.update.to_frame_id << ": logged " << c.update.num_tracked << " tracked / "
           << c.update.num_inliers << " inliers, recomputed " << r.tracks.size() << " / " << inliers << "\n";
  }
  for (const auto& p : problems) readme << p << "\n";
  out.failed = !problems.empty();
  out.note = "wrote " + std::to_string(out.written) + " of " + std::to_string(choices.size()) +
             " pictures of VO steps in " + dir + "/" + (problems.empty() ? "" : "; " + problems.front());
  return out;
}

}  // namespace rover::plot
