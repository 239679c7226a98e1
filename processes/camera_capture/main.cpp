// camera_capture: takes a stereo pair on request (or at a fixed rate) and publishes a
// STEREO_FRAME with both images, both camera models, a frame id and the pose estimate at
// capture. Sources:
//   sim      render the world at the TRUE pose (SIM_TRUTH); nothing else comes from truth.
//            With `capture.hazcam` it also renders the front HAZCAM pair at the same pose
//            and instant and publishes it on HAZCAM_FRAME just before the STEREO_FRAME.
//   dataset  a KITTI-layout directory (image_0/, image_1/, calib.txt), played in order
//   genicam, gstreamer  real cameras (common/camera_hw; README "Camera hardware")
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/image_encode.hpp"
#include "bus/process.hpp"
#include "camera_hw/sources.hpp"
#include "config/file_read.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/kitti_calib.hpp"
#include "imaging/image_check.hpp"
#include "render/render_options.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <deque>
#include <future>
#include <mutex>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
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
};

// A source of stereo pairs. `truth` is given only to the simulator source.
class ImageSource {
 public:
  virtual ~ImageSource() = default;
  // Whether a pair can be taken for a request stamped `request_utime` now.
  virtual bool Ready(std::int64_t request_utime) const = 0;
  virtual CapturedPair Capture(std::int64_t frame_id) = 0;
  virtual void OnTruth(const rover_msgs::sim_truth_t&) {}
  // Called on the bus thread when a capture is decided, before Capture runs on a worker:
  // the moment of exposure (the sim source takes the truth of this instant, not of
  // whatever instant the worker happens to start in).
  virtual void Expose() {}
};

// The front HAZCAMs' rig and renderer. The rover's mast in their shadow stands under the
// NAVCAM rig (render::MastUnderRig), not under the HAZCAMs.
struct SimulatedHazcams {
  geometry::StereoRig rig;
  render::StereoRenderer renderer;
};

class SimulatedCameras : public ImageSource {
 public:
  SimulatedCameras(const std::string& world_path, geometry::StereoRig rig,
                   render::RenderOptions options, std::optional<SimulatedHazcams> hazcams)
      : world_(terrain::WorldOptions::LoadFile(world_path)),
        rig_(std::move(rig)),
        renderer_(std::move(options)),
        hazcams_(std::move(hazcams)) {}
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
  CapturedPair Capture(std::int64_t frame_id) override {
    rover_msgs::sim_truth_t truth;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      truth = exposed_ ? *exposed_ : *truth_;
    }
    geometry::Pose T = geometry::Pose::Identity();
    T.linear() = bus::QuaternionFromArray(truth.orientation).toRotationMatrix();
    T.translation() = Eigen::Vector3d(truth.position[0], truth.position[1], truth.position[2]);
    auto images = renderer_.RenderPair(world_, rig_, T, frame_id);
    CapturedPair pair{images.left, images.right, images.rig, {}, {}, truth.utime, std::nullopt};
    // Both pairs at the same true pose: the same instant, as one exposure command on MER.
    if (hazcams_) {
      try {
        auto near = hazcams_->renderer.RenderPair(world_, hazcams_->rig, T, frame_id);
        pair.hazcam = HazcamPair{near.left, near.right, near.rig};
      } catch (const std::exception& e) {
        pair.hazcam_error = e.what();
      }
    }
    return pair;
  }

 private:
  terrain::World world_;
  geometry::StereoRig rig_;
  render::StereoRenderer renderer_;
  std::optional<SimulatedHazcams> hazcams_;
  mutable std::mutex mutex_;  // truth arrives on the bus thread while a render runs
  std::optional<rover_msgs::sim_truth_t> truth_, exposed_;
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
  CapturedPair Capture(std::int64_t) override {
    const std::string& name = names_[next_ % names_.size()];
    ++next_;
    CapturedPair pair;
    for (const char* side : {"/image_0/", "/image_1/"}) {
      config::CheckRegularFile(dir_ + side + name, config::kMaxImageFileBytes, "PNG image");
    }
    pair.left = cv::imread(dir_ + "/image_0/" + name, cv::IMREAD_UNCHANGED);
    pair.right = cv::imread(dir_ + "/image_1/" + name, cv::IMREAD_UNCHANGED);
    if (pair.left.empty() || pair.right.empty()) {
      throw std::runtime_error(dir_ + ": cannot read pair " + name);
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
  CapturedPair Capture(std::int64_t) override {
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
    // Stamped with the bus time of the request; each image's exposure from its own timestamp.
    CapturedPair pair{frames.left.image, frames.right.image, rig_, {}, {}, 0, std::nullopt};
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

// A relative path in the config is relative to the config file, so that configs/ in the
// repository and /etc/rover on a rover computer both work.
std::string RelativeToConfig(const std::string& path, const std::string& config_path) {
  if (path.empty() || path[0] == '/' || config_path.empty()) return path;
  return (fs::path(config_path).parent_path() / path).string();
}

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
    section.CheckKeys({"source", "rig", "encoding", "rate_hz", "render", "hazcam", "genicam", "gstreamer"});
    std::string source = "sim", rig_path = "configs/cameras/navcam_pinhole.yaml", encoding = "png";
    double rate_hz = 0.0;
    section.GetEnum("source", source, {"sim", "dataset", "genicam", "gstreamer"});
    section.Get("rig", rig_path);
    section.GetEnum("encoding", encoding, {"png", "raw"});
    section.Get("rate_hz", rate_hz, 0.0, 100.0);
    if (proc.option("--dataset")) source = "dataset";
    rig_path = RelativeToConfig(rig_path, proc.config_path());
    // The front HAZCAM pair: empty or absent rig, none.
    const auto hazcam_section = section["hazcam"];
    std::string hazcam_rig_path;
    if (!hazcam_section.IsNull()) {
      hazcam_section.CheckKeys({"rig", "render"});
      hazcam_section.Get("rig", hazcam_rig_path);
      hazcam_rig_path = RelativeToConfig(hazcam_rig_path, proc.config_path());
    }
    // Refused rather than ignored: a map that was configured to see the near field must
    // not go blind there without a word. camera_hw takes one synchronised pair, and a
    // dataset has no HAZCAM images.
    if (!hazcam_rig_path.empty() && source != "sim") {
      hazcam_section.Fail("expected no HAZCAM rig with source " + source +
                          " (only the sim source takes a HAZCAM pair; remove capture.hazcam)");
    }

    std::unique_ptr<ImageSource> cameras;
    if (source == "sim") {
      const auto world = proc.option("--world");
      if (!world) throw config::ConfigError("camera_capture: missing argument --world FILE (expected the world the simulator drives on)");
      const render::RenderOptions navcam_render = render::LoadRenderOptions(section["render"]);
      geometry::StereoRig navcam_rig = geometry::LoadStereoRigFile(rig_path);
      std::optional<SimulatedHazcams> hazcams;
      if (!hazcam_rig_path.empty()) {
        // The NAVCAM's render options, overridden key by key by capture.hazcam.render.
        render::RenderOptions options = render::LoadRenderOptions(hazcam_section["render"], navcam_render);
        options.rover_shadow = render::MastUnderRig(options.rover_shadow, navcam_rig);
        hazcams.emplace(SimulatedHazcams{geometry::LoadStereoRigFile(hazcam_rig_path),
                                         render::StereoRenderer(std::move(options))});
      }
      cameras = std::make_unique<SimulatedCameras>(*world, std::move(navcam_rig), navcam_render, std::move(hazcams));
    } else if (source == "genicam" || source == "gstreamer") {
      auto hardware = source == "genicam"
                          ? camera_hw::MakeGenicamSource(camera_hw::GenicamOptions::Load(section["genicam"]))
                          : camera_hw::MakeGstreamerSource(camera_hw::GstreamerOptions::Load(section["gstreamer"]));
      cameras = std::make_unique<HardwareCameras>(std::move(hardware), geometry::LoadStereoRigFile(rig_path));
    } else {
      const auto dir = proc.option("--dataset");
      if (!dir) throw config::ConfigError("camera_capture: missing argument --dataset DIR (expected a KITTI-layout directory)");
      cameras = std::make_unique<DatasetCameras>(*dir);
    }
    const bool png = encoding == "png";

    std::optional<rover_msgs::pose_t> pose;
    std::deque<rover_msgs::capture_request_t> pending;
    std::int64_t next_auto_id = 1, next_auto_utime = 0;
    proc.bus().Subscribe<rover_msgs::pose_t>(channels::kPose, [&](const rover_msgs::pose_t& m) { pose = m; }, 100);
    proc.bus().Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth, [&](const rover_msgs::sim_truth_t& m) {
      proc.ObserveTime(m.utime);
      cameras->OnTruth(m);
    }, 100);
    proc.bus().Subscribe<rover_msgs::capture_request_t>(
        channels::kCaptureRequest, [&](const rover_msgs::capture_request_t& m) { pending.push_back(m); });

    // A capture (a render takes seconds) runs on a worker thread, so that the loop keeps
    // answering and heartbeating: the executor takes a silent process for a dead one.
    std::future<CaptureFrames> job;
    auto capture_frame = [&cameras, png](rover_msgs::capture_request_t request, rover_msgs::pose_t pose,
                                         std::int64_t now) {
      const auto pair = cameras->Capture(request.frame_id);
      CaptureFrames out;
      rover_msgs::stereo_frame_t& frame = out.navcam;
      frame.utime = pair.utime != 0 ? pair.utime : now;
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
    };
    // The frame is published when the render is done and, in virtual time, not before the
    // compute profile's capture time has passed since the request (Process::DueAt); the
    // HAZCAM frame with it, just before, from the same publisher, so that every reader has it
    // first: the hazard monitor's map holds it before the executor, woken by the
    // STEREO_FRAME, asks about the next step.
    std::int64_t job_due = 0;
    auto start = [&](const rover_msgs::capture_request_t& request) {
      rover_msgs::pose_t at_capture{};
      at_capture.orientation[0] = 1.0;
      if (pose) at_capture = *pose;
      cameras->Expose();
      job = std::async(std::launch::async, capture_frame, request, at_capture, proc.now());
      job_due = proc.DueAt(proc.now(), proc.compute().capture_s);
    };
    // Publishes a finished frame that is due; true while a frame due by now is unfinished.
    auto finish = [&]() -> bool {
      if (!job.valid() || proc.now() < job_due) return false;
      if (job.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return true;
      try {
        const CaptureFrames frames = job.get();  // rethrows a capture error
        if (frames.hazcam) proc.bus().Publish(channels::kHazcamFrame, *frames.hazcam);
        proc.bus().Publish(channels::kStereoFrame, frames.navcam);
        if (frames.hazcam_error.empty()) {
          proc.SetHealth(rover_msgs::heartbeat_t::STATE_OK, "");
        } else {
          // The NAVCAM frame went out (VO needs it); the map misses this near-field view.
          std::cerr << "camera_capture: HAZCAM capture failed, no HAZCAM_FRAME " << frames.navcam.frame_id
                    << ": " << frames.hazcam_error << "\n";
          proc.SetHealth(rover_msgs::heartbeat_t::STATE_DEGRADED, "HAZCAM capture failed: " + frames.hazcam_error);
        }
      } catch (const std::exception& e) {
        // No frame for this request: the executor counts a VO failure; the process goes on,
        // and its heartbeat says DEGRADED with the failure until a capture succeeds again
        // (the camera contract, docs/HARDWARE.md).
        std::cerr << "camera_capture: capture failed, no frame sent: " << e.what() << "\n";
        proc.SetHealth(rover_msgs::heartbeat_t::STATE_DEGRADED, std::string("capture failed: ") + e.what());
      }
      return false;
    };
    proc.set_pending_work(finish);

    proc.Run(
        [&] {
          finish();
          if (job.valid()) return;
          if (!pending.empty() && cameras->Ready(pending.front().utime)) {
            start(pending.front());
            pending.pop_front();
          } else if (pending.empty() && rate_hz > 0 && proc.now() >= next_auto_utime &&
                     cameras->Ready(proc.now())) {
            rover_msgs::capture_request_t r{};
            r.utime = proc.now();
            r.frame_id = next_auto_id++;
            r.purpose = "periodic";
            start(r);
            next_auto_utime = proc.now() + static_cast<std::int64_t>(1e6 / rate_hz);
          }
        },
        5);
    if (job.valid()) job.wait();
    return 0;
  });
}
