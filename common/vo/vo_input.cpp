// VO-1 input: the checks on a call's images, models and prior; the new pair at the working
// resolution with its band-passed pyramid; the pair it is measured against.
#include "vo/vo_state.hpp"

#include <opencv2/imgproc.hpp>

#include <sstream>

namespace rover::vo {

namespace {

void ToFloat(const cv::Mat& image, double scale_to_working, cv::Mat* out, cv::Mat* scratch) {
  const double unit = image.depth() == CV_16U ? 1.0 / 65535.0 : 1.0 / 255.0;
  if (scale_to_working == 1.0) {
    image.convertTo(*out, CV_32F, unit);
    return;
  }
  image.convertTo(*scratch, CV_32F, unit);
  const cv::Size size(static_cast<int>(std::lround(image.cols * scale_to_working)),
                      static_cast<int>(std::lround(image.rows * scale_to_working)));
  cv::resize(*scratch, *out, size, 0, 0, cv::INTER_AREA);
}

}  // namespace

std::string VisualOdometry::State::InputProblem(const StereoImages& im) const {
  if (!im.rig.left || !im.rig.right) return "stereo rig has no camera model";
  if (im.left.empty() || im.right.empty()) return "empty image";
  for (const cv::Mat* m : {&im.left, &im.right}) {
    if (m->type() != CV_8UC1 && m->type() != CV_16UC1) {
      return "image type " + std::to_string(m->type()) + " (expected CV_8UC1 or CV_16UC1)";
    }
  }
  if (im.left.size() != im.right.size()) return "left and right images differ in size";
  if (im.left.cols != im.rig.left->width() || im.left.rows != im.rig.left->height() ||
      im.right.cols != im.rig.right->width() || im.right.rows != im.rig.right->height()) {
    std::ostringstream os;
    os << "image size " << im.left.cols << "x" << im.left.rows << " does not match camera "
       << im.rig.left->width() << "x" << im.rig.left->height();
    return os.str();
  }
  const int min_side = static_cast<int>(std::min(im.left.cols, im.left.rows) * o.working_scale);
  if (min_side < 2 * o.feature_border_px + 8) return "image too small for the working scale";
  return "";
}

bool VisualOdometry::State::CheckInput(Step* st) {
  if (std::string bad = InputProblem(st->images); !bad.empty()) {
    return st->Stop(VoStatus::kBadInput, bad);
  }
  if (!st->prior.matrix().allFinite() || !st->prior_covariance.allFinite()) {
    return st->Stop(VoStatus::kBadInput, "prior motion or covariance is not finite");
  }
  ++calls;  // a call that gets this far counts (RANSAC's seed follows the count)
  return true;
}

void VisualOdometry::State::LoadPair(Step* st) {
  const StereoImages& im = st->images;
  st->cur = spare ? std::move(spare) : std::make_unique<Pair>();
  Pair* pair = st->cur.get();
  pair->features.clear();
  if (o.working_scale == 1.0) {
    pair->rig = im.rig;
  } else {
    pair->rig.left = im.rig.left->Scaled(o.working_scale);
    pair->rig.right = im.rig.right->Scaled(o.working_scale);
  }
  ToFloat(im.left, o.working_scale, &pair->left, &pair->scratch);
  ToFloat(im.right, o.working_scale, &pair->right, &pair->scratch);
  pair->width = pair->left.cols;
  pair->height = pair->left.rows;
  Eigen::Vector3d c, d0, d1;
  const Eigen::Vector2d centre(0.5 * (pair->left.cols - 1), 0.5 * (pair->left.rows - 1));
  pair->rig.left->BackProject(centre, &c, &d0);
  pair->rig.left->BackProject(centre + Eigen::Vector2d(1, 0), &c, &d1);
  pair->pixel_angle = std::max(1e-9, std::acos(std::clamp(d0.dot(d1), -1.0, 1.0)));
  const double baseline = pair->rig.Baseline();
  pair->far_range = o.stereo_min_disparity_px > 0
                        ? baseline / (o.stereo_min_disparity_px * pair->pixel_angle)
                        : 1e6 * baseline;
  BuildPyramid(pair);
  pair->frame_id = im.frame_id;
}

// Pyramid of the left image, band-passed level by level (VO-3 prefilter), for
// coarse-to-fine tracking (VO-6); the right image band-passed, and at half resolution
// for coarse-to-fine stereo when that is on.
void VisualOdometry::State::BuildPyramid(Pair* pair) {
  const cv::Mat& left = pair->left;
  const cv::Mat& right = pair->right;
  const int n = o.match_template_px;
  pair->left_band.resize(o.track_pyramid_levels);
  pair->left_levels.resize(o.track_pyramid_levels);
  int levels = 0;
  for (int l = 0; l < o.track_pyramid_levels; ++l) {
    const cv::Mat& level = l == 0 ? left : pair->left_levels[l];
    if (l > 0) {
      const cv::Mat& finer = l == 1 ? left : pair->left_levels[l - 1];
      if (finer.cols / 2 < n + 4 || finer.rows / 2 < n + 4) break;
      cv::resize(finer, pair->left_levels[l], cv::Size(finer.cols / 2, finer.rows / 2), 0, 0,
                 cv::INTER_AREA);
    }
    BandPass(level, o.match_prefilter_sigma, o.match_prefilter_box_px, &pair->left_band[l],
             &pair->scratch);
    ++levels;
  }
  pair->left_band.resize(levels);
  BandPass(right, o.match_prefilter_sigma, o.match_prefilter_box_px, &pair->right_band,
           &pair->scratch);
  if (o.stereo_coarse_to_fine && pair->left_band.size() > 1) {
    cv::resize(right, pair->right_half, pair->left_band[1].size(), 0, 0, cv::INTER_AREA);
    BandPass(pair->right_half, o.match_prefilter_sigma, o.match_prefilter_box_px,
             &pair->right_band_half, &pair->scratch);
  } else {
    pair->right_band_half.release();
  }
}

void VisualOdometry::State::TakeReference(Step* st) {
  st->ref = std::move(prev);
  // Frame-to-frame, every outcome from here on makes the new pair the previous one.
  if (!Windowed()) prev = std::move(st->cur);
  st->c = Windowed() ? st->cur.get() : prev.get();
  // Windowed mode: the prior from the reference pair (the last keyframe).
  st->prior_ref = Windowed() && st->ref && window.size() > 0
                      ? window.pose(window.size() - 1).inverse() * T_w_last * st->prior
                      : st->prior;
}

bool VisualOdometry::State::CheckReference(Step* st) {
  if (!st->ref) return st->Stop(VoStatus::kBaseline, "first pair: features kept for the next");
  if (static_cast<int>(st->ref->features.size()) < o.min_features) {
    return st->Stop(VoStatus::kTooFewFeatures,
                    Format("previous pair has %.0f stereo features (need %.0f)",
                           st->ref->features.size(), o.min_features));
  }
  return true;
}

}  // namespace rover::vo
