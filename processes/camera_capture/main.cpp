// camera_capture: takes a stereo pair on request (or at a fixed rate) and publishes a
// STEREO_FRAME with both images, both camera models, a frame id and the pose estimate at
// capture. Sources:
//   sim      render the world at the TRUE pose (SIM_TRUTH); nothing else comes from truth.
//            With `capture.hazcam` it also renders the front HAZCAM pair at the same pose
//            and instant and publishes it on HAZCAM_FRAME just before the STEREO_FRAME.
//   dataset  a KITTI-layout directory (image_0/, image_1/, calib.txt), played in order
//   genicam, gstreamer  real cameras (common/camera_hw; README "Camera hardware")
// A request may point the mast (pan_rad, tilt_rad): the sim source renders the NAVCAM pair
// from the pointed rig, sends the pointed models and no HAZCAM frame; the others refuse it
// (capture failed, no frame sent).
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/image_encode.hpp"
#include "bus/process.hpp"
#include "camera_hw/sources.hpp"
#include "capture/capture_options.hpp"
#include "capture/rendered_cameras.hpp"
#include "config/file_read.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/kitti_calib.hpp"
#include "imaging/image_check.hpp"
#include "imaging/png_codec.hpp"
#include "terrain/world.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <future>
#include <mutex>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <tuple>

using namespace rover;
namespace fs = std::filesystem;

namespace {

// The front HAZCAM pair of a capture (sim source only).
struct HazcamPair {
  cv::Mat left, right;
  geometry::StereoRig rig;
};

struct CapturedPair {
  cv::Mat left, right;
  geometry::StereoRig rig;
  // The HAZCAM pair exposed with this one; when it could not be taken, the reason (the
  // NAVCAM pair is still delivered: VO needs it, the map can wait for the next).
  std::optional<HazcamPair> hazcam;
  std::string hazcam_error;
  std::int64_t utime = 0;  // 0: the request's bus time
  // Real cameras: each image's own timestamp (ns, the camera's clock), to carry their
  // difference into the frame's left_utime and right_utime. Unset: both at the capture time.
  std::optional<camera_hw::StereoFrames> timestamps;
  // Real cameras: the exposure on the system clock (camera_hw::ExposureSystemUtime; 0:
  // unknown), which stamps the frame instead of the request's time.
  std::int64_t system_utime = 0;
};

using capture::Pointing;

// A source of stereo pairs. `truth` is given only to the simulator source.
class ImageSource {
 public:
  virtual ~ImageSource() = default;
  // Whether a pair can be taken for a request stamped `request_utime` now.
  virtual bool Ready(std::int64_t request_utime) const = 0;
  // A pair with the mast pointed as asked; a source that cannot point throws for a
  // pointed request (RefusePointing).
  virtual CapturedPair Capture(std::int64_t frame_id, const Pointing& pointing) = 0;
  virtual void OnTruth(const rover_msgs::sim_truth_t&) {}
  // Called on the bus thread when a capture is decided, before Capture runs on a worker:
  // the moment of exposure (the sim source takes the truth of this instant, not of
  // whatever instant the worker happens to start in).
  virtual void Expose() {}
};

// The one line a source without a pan-tilt mast answers a pointed request with.
void RefusePointing(const Pointing& pointing) {
  if (!pointing.pointed()) return;
  char angles[96];
  std::snprintf(angles, sizeof(angles), "pan %.1f deg, tilt %.1f deg", pointing.pan_rad * 180 / M_PI,
                pointing.tilt_rad * 180 / M_PI);
  throw std::runtime_error(std::string("this camera source cannot point the mast (") + angles +
                           " requested); pointed captures need the simulator's cameras");
}

class SimulatedCameras : public ImageSource {
 public:
  SimulatedCameras(const std::string& world_path, capture::RenderedCameras cameras)
      : world_(terrain::WorldOptions::LoadFile(world_path)), cameras_(std::move(cameras)) {}
  bool Ready(std::int64_t request_utime) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return truth_ && truth_->utime >= request_utime;
  }
  void OnTruth(const rover_msgs::sim_truth_t& t) override {
    std::lock_guard<std::mutex> lock(mutex_);
    truth_ = t;
  }
  void Expose() override {
    std::lock_guard<std::mutex> lock(mutex_);
    exposed_ = truth_;
  }
  CapturedPair Capture(std::int64_t /*frame_id*/, const Pointing& pointing) override {
    rover_msgs::sim_truth_t truth;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      truth = exposed_ ? *exposed_ : *truth_;
    }
    geometry::Pose T = geometry::Pose::Identity();
    T.linear() = bus::QuaternionFromArray(truth.orientation).toRotationMatrix();
    T.translation() = Eigen::Vector3d(truth.position[0], truth.position[1], truth.position[2]);
    // The read noise is seeded by this pair's place in the process's renders (1 for the
    // first) and capture.render.noise_seed, not by its frame id: on a real clock the
    // executor's ids come from the wall clock, and every run drew other noise for the same
    // first view (the fault suite's first step past a cobble was refused now and then).
    // A pointed pair counts as any other, so that the pairs after it draw the noise they
    // would have drawn had it been an unpointed one.
    auto exposure = cameras_.Expose(world_, T, ++rendered_, pointing);
    const auto& navcam = exposure.navcam;
    CapturedPair pair{navcam.left, navcam.right, navcam.rig, {}, exposure.hazcam_error, truth.utime, std::nullopt};
    if (exposure.hazcam) pair.hazcam = HazcamPair{exposure.hazcam->left, exposure.hazcam->right, exposure.hazcam->rig};
    return pair;
  }

 private:
  terrain::World world_;
  capture::RenderedCameras cameras_;
  mutable std::mutex mutex_;  // truth arrives on the bus thread while a render runs
  std::optional<rover_msgs::sim_truth_t> truth_, exposed_;
  std::int64_t rendered_ = 0;  // pairs rendered so far: the noise's frame seed
};

// What a dataset image's PNG header says; throws ConfigError naming the file when it is
// not a gray 8- or 16-bit PNG within the imaging limits.
imaging::PngHeader DatasetPngHeader(const std::string& path) {
  config::CheckRegularFile(path, config::kMaxImageFileBytes, "PNG image");  // not a FIFO
  std::ifstream in(path, std::ios::binary);
  std::uint8_t bytes[imaging::kPngHeaderBytes] = {};
  in.read(reinterpret_cast<char*>(bytes), sizeof(bytes));
  imaging::PngHeader header;
  std::string bad = imaging::ReadPngHeader(bytes, static_cast<std::size_t>(in.gcount()), header);
  if (bad.empty()) bad = imaging::CheckPngHeader(header, header.width, header.height);
  const imaging::ImageLimits limits;
  if (bad.empty() && std::int64_t{header.width} * header.height > limits.max_pixels) {
    bad = "PNG is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
          " (expected at most " + std::to_string(limits.max_pixels) + " px)";
  }
  if (!bad.empty()) throw config::ConfigError(path + ": " + bad);
  return header;
}

class DatasetCameras : public ImageSource {
 public:
  // Every image's header is read before the first capture: a pair of the wrong size,
  // depth or colour stops the process at start with one line, not in the middle of a drive.
  explicit DatasetCameras(const std::string& dir) : dir_(dir) {
    for (int i = 0;; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      if (!fs::exists(dir_ + "/image_0/" + name)) break;
      names_.push_back(name);
    }
    if (names_.empty()) {
      throw config::ConfigError(dir_ + "/image_0: no images (expected 000000.png, 000001.png, ...)");
    }
    const std::string first = dir_ + "/image_0/" + names_[0];
    const imaging::PngHeader size = DatasetPngHeader(first);
    for (const auto& name : names_) {
      for (const char* side : {"/image_0/", "/image_1/"}) {
        const std::string path = dir_ + side + name;
        const imaging::PngHeader h = DatasetPngHeader(path);
        if (h.width != size.width || h.height != size.height || h.bit_depth != size.bit_depth) {
          throw config::ConfigError(path + ": " + std::to_string(h.width) + "x" + std::to_string(h.height) +
                                    ", " + std::to_string(h.bit_depth) + "-bit (expected " +
                                    std::to_string(size.width) + "x" + std::to_string(size.height) + ", " +
                                    std::to_string(size.bit_depth) + "-bit like " + first + ")");
        }
      }
    }
    width_ = static_cast<int>(size.width);
    height_ = static_cast<int>(size.height);
    rig_ = geometry::LoadKittiCalib(dir_ + "/calib.txt", width_, height_);
  }
  bool Ready(std::int64_t) const override { return true; }
  // A refused request takes no pair: the replay goes on where it was.
  CapturedPair Capture(std::int64_t, const Pointing& pointing) override {
    RefusePointing(pointing);
    const std::string& name = names_[next_ % names_.size()];
    ++next_;
    CapturedPair pair;
    for (const auto& [side, image] : {std::pair{"/image_0/", &pair.left}, std::pair{"/image_1/", &pair.right}}) {
      const std::string png = config::ReadBoundedRegularFile(dir_ + side + name, config::kMaxImageFileBytes, "PNG image");
      if (std::string bad = imaging::DecodeGrayPng(reinterpret_cast<const std::uint8_t*>(png.data()), png.size(), *image);
          !bad.empty()) {
        throw std::runtime_error(dir_ + side + name + ": " + bad);
      }
    }
    // The files were checked at start; one replaced since is caught here.
    for (const cv::Mat* m : {&pair.left, &pair.right}) {
      if (m->cols != width_ || m->rows != height_ || m->channels() != 1) {
        throw std::runtime_error(dir_ + ": pair " + name + " is " + std::to_string(m->cols) + "x" +
                                 std::to_string(m->rows) + " with " + std::to_string(m->channels()) +
                                 " channels (expected " + std::to_string(width_) + "x" +
                                 std::to_string(height_) + " gray, as at start)");
      }
    }
    pair.rig = rig_;
    return pair;
  }

 private:
  std::string dir_;
  std::vector<std::string> names_;
  std::size_t next_ = 0;
  int width_ = 0, height_ = 0;
  geometry::StereoRig rig_;
};

// Real cameras (camera_hw): a pair is taken when asked, so a source is always ready. The
// rig file's models must be for the images the cameras deliver (region and binning).
class HardwareCameras : public ImageSource {
 public:
  HardwareCameras(std::unique_ptr<camera_hw::StereoSource> source, geometry::StereoRig rig)
      : source_(std::move(source)), rig_(std::move(rig)) {}
  bool Ready(std::int64_t) const override { return true; }
  // The rig file is the cameras as mounted, with no pan-tilt unit to drive: refused
  // before the cameras are triggered.
  CapturedPair Capture(std::int64_t, const Pointing& pointing) override {
    RefusePointing(pointing);
    auto frames = source_->Capture();
    for (const auto& [image, model, side] : {std::tuple{&frames.left.image, rig_.left.get(), "left"},
                                             std::tuple{&frames.right.image, rig_.right.get(), "right"}}) {
      if (image->cols != model->width() || image->rows != model->height()) {
        throw std::runtime_error(std::string(side) + " image is " + std::to_string(image->cols) + "x" +
                                 std::to_string(image->rows) + " but its camera model is " +
                                 std::to_string(model->width()) + "x" + std::to_string(model->height()) +
                                 " (capture.rig against the region and binning)");
      }
    }
    // Stamped with the exposure on the system clock; each image's from its own timestamp.
    CapturedPair pair{frames.left.image, frames.right.image, rig_, {}, {}, 0, std::nullopt,
                      camera_hw::ExposureSystemUtime(frames)};
    frames.left.image.release();
    frames.right.image.release();
    pair.timestamps = std::move(frames);
    return pair;
  }

 private:
  std::unique_ptr<camera_hw::StereoSource> source_;
  geometry::StereoRig rig_;
};

// Both images encoded and both models, as STEREO_FRAME and HAZCAM_FRAME carry them.
void SetImages(rover_msgs::stereo_frame_t& frame, const cv::Mat& left, const cv::Mat& right,
               const geometry::StereoRig& rig, bool png) {
  // The two images compress at once on two cores (PNG encoding is most of a
  // full-size frame's latency).
  auto right_encoded = std::async(std::launch::async, [&right, png] { return bus::EncodeImage(right, png); });
  frame.left = bus::EncodeImage(left, png);
  frame.right = right_encoded.get();
  frame.left_model = bus::CameraModelToMsg(*rig.left);
  frame.right_model = bus::CameraModelToMsg(*rig.right);
}

// What one capture publishes: the NAVCAM pair, and the HAZCAM pair taken with it.
struct CaptureFrames {
  rover_msgs::stereo_frame_t navcam{};
  std::optional<rover_msgs::stereo_frame_t> hazcam;
  std::string hazcam_error;  // why a configured HAZCAM pair is missing
};

// The cameras the config names: rendered from the world (sim), GenICam or GStreamer
// hardware, or a recorded dataset.
std::unique_ptr<ImageSource> MakeCameras(const bus::Process& proc, const capture::CaptureOptions& options,
                                         const config::ConfigNode& section) {
  if (options.source == "sim") {
    const auto world = proc.option("--world");
    if (!world) throw config::ConfigError("camera_capture: missing argument --world FILE (expected the world the simulator drives on)");
    auto navcam_rig = geometry::LoadStereoRigFile(options.rig_path);
    return std::make_unique<SimulatedCameras>(
        *world, options.hazcam ? capture::RenderedCameras(std::move(navcam_rig), options.render,
                                                          geometry::LoadStereoRigFile(options.hazcam->rig_path),
                                                          options.hazcam->render)
                               : capture::RenderedCameras(std::move(navcam_rig), options.render));
  }
  if (options.source == "genicam" || options.source == "gstreamer") {
    auto hardware = options.source == "genicam"
                        ? camera_hw::MakeGenicamSource(camera_hw::GenicamOptions::Load(section["genicam"]))
                        : camera_hw::MakeGstreamerSource(camera_hw::GstreamerOptions::Load(section["gstreamer"]));
    return std::make_unique<HardwareCameras>(std::move(hardware), geometry::LoadStereoRigFile(options.rig_path));
  }
  const auto dir = proc.option("--dataset");
  if (!dir) throw config::ConfigError("camera_capture: missing argument --dataset DIR (expected a KITTI-layout directory)");
  return std::make_unique<DatasetCameras>(*dir);
}

// One capture, on the worker thread: the pair (and the HAZCAM pair taken with it) as
// messages stamped with the request and the pose at capture.
// `now` is rover time when the capture started and `system_now` the system clock then (they
// are one on a rover): a real camera's exposure on the system clock is moved into rover time
// by their difference.
CaptureFrames CaptureFrame(ImageSource& cameras, bool png, const rover_msgs::capture_request_t& request,
                           const rover_msgs::pose_t& pose, std::int64_t now, std::int64_t system_now) {
  const auto pair = cameras.Capture(request.frame_id, Pointing{request.pan_rad, request.tilt_rad});
  CaptureFrames out;
  rover_msgs::stereo_frame_t& frame = out.navcam;
  // Before rover time is known (now 0: a real clock not decided yet) a real camera's pair
  // carries its exposure on the system clock.
  const std::int64_t exposed = now > 0 ? now + (pair.system_utime - system_now) : pair.system_utime;
  frame.utime = pair.utime != 0 ? pair.utime : pair.system_utime != 0 ? exposed : now;
  frame.left_utime = frame.right_utime = frame.utime;  // one renderer, one dataset pair: at once
  if (pair.timestamps) {
    const auto exposed = camera_hw::ExposureUtimes(*pair.timestamps, frame.utime);
    frame.left_utime = exposed.left_utime;
    frame.right_utime = exposed.right_utime;
  }
  frame.frame_id = request.frame_id;
  frame.purpose = request.purpose;
  frame.pose_at_capture = pose;
  // The HAZCAM frame says the same of its exposure: id, purpose, instants and pose.
  if (pair.hazcam) {
    out.hazcam = frame;
    SetImages(*out.hazcam, pair.hazcam->left, pair.hazcam->right, pair.hazcam->rig, png);
  }
  SetImages(frame, pair.left, pair.right, pair.rig, png);
  out.hazcam_error = pair.hazcam_error;
  return out;
}

// Captures on request (and periodically with capture.rate_hz), one at a time on a worker
// thread (a render takes seconds), so that the loop keeps answering and heartbeating: the
// executor takes a silent process for a dead one.
class Capturer {
 public:
  Capturer(bus::Process& proc, std::unique_ptr<ImageSource> cameras, bool png, double rate_hz)
      : proc_(proc), cameras_(std::move(cameras)), png_(png), rate_hz_(rate_hz) {
    proc_.bus().Subscribe<rover_msgs::pose_t>(channels::kPose, [this](const rover_msgs::pose_t& m) { pose_ = m; }, 100);
    proc_.bus().Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth, [this](const rover_msgs::sim_truth_t& m) {
      proc_.ObserveTime(m.utime);
      cameras_->OnTruth(m);
    }, 100);
    proc_.bus().Subscribe<rover_msgs::capture_request_t>(
        channels::kCaptureRequest, [this](const rover_msgs::capture_request_t& m) { pending_.push_back(m); });
    proc_.set_pending_work([this] { return Finish(); });
    // Quiet (virtual time's idle strides) with no capture asked for or in hand, until the
    // next periodic one.
    proc_.set_quiet_until([this]() -> std::int64_t {
      if (job_.valid() || !pending_.empty()) return 0;
      return rate_hz_ > 0 ? next_auto_utime_ : bus::Process::kQuietForGood;
    });
  }

  // The loop's tick: a finished capture out, then the next one started.
  void Tick() {
    Finish();
    if (job_.valid()) return;
    if (!pending_.empty() && cameras_->Ready(pending_.front().utime)) {
      Start(pending_.front());
      pending_.pop_front();
    } else if (pending_.empty() && rate_hz_ > 0 && proc_.now() >= next_auto_utime_ && cameras_->Ready(proc_.now())) {
      rover_msgs::capture_request_t r{};
      r.utime = proc_.now();
      r.frame_id = next_auto_id_++;
      r.purpose = "periodic";
      Start(r);
      next_auto_utime_ = proc_.now() + static_cast<std::int64_t>(1e6 / rate_hz_);
    }
  }

  void Drain() {
    if (job_.valid()) job_.wait();
  }

 private:
  // The frame is published when the render is done and, in virtual time, not before the
  // compute profile's capture time has passed since the request (Process::DueAt); the
  // HAZCAM frame with it, just before, from the same publisher, so that every reader has it
  // first: the hazard monitor's map holds it before the executor, woken by the
  // STEREO_FRAME, asks about the next step.
  void Start(const rover_msgs::capture_request_t& request) {
    rover_msgs::pose_t at_capture{};
    at_capture.orientation[0] = 1.0;
    if (pose_) at_capture = *pose_;
    cameras_->Expose();
    job_ = std::async(std::launch::async, CaptureFrame, std::ref(*cameras_), png_, request, at_capture, proc_.now(),
                      bus::RoverClock::SystemUtime());
    job_due_ = proc_.DueAt(proc_.now(), proc_.compute().capture_s);
  }

  // Publishes a finished frame that is due; true while a frame due by now is unfinished.
  bool Finish() {
    if (!job_.valid() || proc_.now() < job_due_) return false;
    if (job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return true;
    try {
      CaptureFrames frames = job_.get();  // rethrows a capture error
      AnnounceReturn(frames.navcam.frame_id);
      Publish(std::move(frames));
    } catch (const std::exception& e) {
      // No frame for this request: the executor counts a VO failure; the process goes on,
      // and its heartbeat says DEGRADED with the failure until a capture succeeds again
      // (the camera contract, docs/HARDWARE.md). The first failure of an outage is one
      // line; the rest are counted in the heartbeat, and the return is one line.
      if (failures_ == 0) {
        std::cerr << "camera_capture: capture failed, no frame sent: " << e.what()
                  << " (the next failures are counted, not printed, until a pair is taken again)\n";
        failing_since_wall_ = proc_.wall_seconds();
      }
      ++failures_;
      proc_.SetHealth(rover_msgs::heartbeat_t::STATE_DEGRADED,
                      std::string("capture failed: ") + e.what() + " (" + std::to_string(failures_) + " in a row)");
    }
    return false;
  }

  // One line when a pair is taken after an outage: the cameras are back.
  void AnnounceReturn(std::int64_t frame_id) {
    if (failures_ == 0) return;
    std::cerr << "camera_capture: the cameras are back: frame " << frame_id << " taken after " << failures_
              << " failed capture" << (failures_ == 1 ? "" : "s") << " over "
              << static_cast<int>(std::lround(proc_.wall_seconds() - failing_since_wall_)) << " s of wall time\n";
    failures_ = 0;
  }

  void Publish(CaptureFrames frames) {
    if (frames.hazcam) {
      try {
        proc_.bus().Publish(channels::kHazcamFrame, *frames.hazcam);
      } catch (const std::exception& e) {
        frames.hazcam_error = e.what();  // not the NAVCAM frame's failure
      }
    }
    proc_.bus().Publish(channels::kStereoFrame, frames.navcam);
    if (frames.hazcam_error.empty()) {
      proc_.SetHealth(rover_msgs::heartbeat_t::STATE_OK, "");
      return;
    }
    // The NAVCAM frame went out (VO needs it); the map misses this near-field view.
    std::cerr << "camera_capture: HAZCAM capture failed, no HAZCAM_FRAME " << frames.navcam.frame_id << ": "
              << frames.hazcam_error << "\n";
    proc_.SetHealth(rover_msgs::heartbeat_t::STATE_DEGRADED, "HAZCAM capture failed: " + frames.hazcam_error);
  }

  bus::Process& proc_;
  std::unique_ptr<ImageSource> cameras_;
  const bool png_;
  const double rate_hz_;
  std::optional<rover_msgs::pose_t> pose_;
  std::deque<rover_msgs::capture_request_t> pending_;
  std::int64_t next_auto_id_ = 1, next_auto_utime_ = 0;
  std::future<CaptureFrames> job_;
  std::int64_t job_due_ = 0;
  std::int64_t failures_ = 0;  // captures failed in a row
  double failing_since_wall_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("camera_capture", [&]() -> int {
    bus::Process proc("camera_capture",
                      "Stereo pairs on request. Reads CAPTURE_REQUEST, POSE (and SIM_TRUTH for the\n"
                      "sim source); writes STEREO_FRAME, and HAZCAM_FRAME just before it when\n"
                      "capture.hazcam is set (sim source). Config: the `capture:` section.",
                      argc, argv,
                      {{"--world", "FILE", "world YAML (sim source)"},
                       {"--dataset", "DIR", "KITTI-layout directory (dataset source)"}});
    const auto section = proc.config()["capture"];
    const auto options =
        capture::CaptureOptions::Load(section, proc.config_path(), proc.option("--dataset") ? "dataset" : "");
    if (!options.notice.empty()) std::cerr << "camera_capture: " << options.notice << "\n";
    Capturer capturer(proc, MakeCameras(proc, options, section), options.encoding == "png", options.rate_hz);
    proc.DeclarePublications({{channels::kStereoFrame}, {channels::kHazcamFrame, "capture.hazcam names a rig"}});
    proc.Run([&] { capturer.Tick(); }, 5);
    capturer.Drain();
    return 0;
  });
}
