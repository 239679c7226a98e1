// Camera models: the one interface VO, the renderer and the messages share.
//
// A model maps a 3-D point expressed in its reference frame to a pixel. For CAHV and
// CAHVOR the reference frame is the one the C, A, H, V vectors are given in (for a rover,
// the rover frame); a pinhole model carries its own pose in that frame (T_ref_cam), so
// that a stereo rig's two models share one reference frame.
// Pixels are (x, y) = (sample, line), 0-based; (0,0) is the centre of the top-left pixel.
//
// Implementations (pinhole with OpenCV-style distortion, CAHV, CAHVOR, CAHVORE) live beside this
// header. Each can be serialised as (type, width, height, params) for LCM messages and
// YAML configs.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace rover::geometry {

class CameraModel {
 public:
  virtual ~CameraModel() = default;

  // "pinhole", "cahv", "cahvor" (and "cahvore" where implemented).
  virtual std::string type() const = 0;
  virtual int width() const = 0;
  virtual int height() const = 0;

  // Projects a point in the reference frame. Returns false when the point is behind the
  // camera (or projection is undefined). `J` (optional) is d(pixel)/d(point).
  virtual bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
                       Eigen::Matrix<double, 2, 3>* J = nullptr) const = 0;

  // The ray through a pixel: origin (camera centre) and unit direction, in the reference
  // frame. `J_dir` (optional) is d(direction)/d(pixel).
  virtual void BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                           Eigen::Vector3d* direction,
                           Eigen::Matrix<double, 3, 2>* J_dir = nullptr) const = 0;

  // The same camera for an image resampled by `factor` (0.5 = half size). A pixel centre
  // convention of (0,0) at the centre of the top-left pixel is preserved.
  virtual std::unique_ptr<CameraModel> Scaled(double factor) const = 0;

  // The camera centre in the reference frame.
  virtual Eigen::Vector3d Center() const = 0;

  // Flat parameters for messages; FromParams(type(), width(), height(), Params())
  // rebuilds an identical model.
  virtual std::vector<double> Params() const = 0;

  virtual std::unique_ptr<CameraModel> Clone() const = 0;

  // The same camera after the rigid motion T of the reference frame's points: a point p
  // seen at pixel u before is seen at u after at T * p (the camera moved with the point).
  // Lens and image are unchanged; only where the camera stands and looks.
  virtual std::unique_ptr<CameraModel> Moved(const Eigen::Isometry3d& T) const = 0;
};

// Rebuilds a model from its serialised form. Throws std::invalid_argument with a message
// naming the type and the expected parameter count when they do not fit.
std::unique_ptr<CameraModel> CameraModelFromParams(const std::string& type, int width,
                                                   int height,
                                                   const std::vector<double>& params);

// A stereo pair: two models in one reference frame.
struct StereoRig {
  std::shared_ptr<const CameraModel> left;
  std::shared_ptr<const CameraModel> right;
  double Baseline() const { return (right->Center() - left->Center()).norm(); }
};

}  // namespace rover::geometry
