// The genicam source: two GenICam cameras (GigE Vision or USB3 Vision) through Aravis.
#include "camera_hw/sources.hpp"

#include <arv.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace rover::camera_hw {

bool GenicamAvailable() { return true; }

namespace {

using Clock = std::chrono::steady_clock;

std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// Aravis reports through GError: turn one into the capture's one line.
void Check(GError*& error, const std::string& what) {
  if (error == nullptr) return;
  const std::string message = what + ": " + OneLine(error->message);
  g_clear_error(&error);
  throw CaptureError(message);
}

const char* StatusName(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS: return "success";
    case ARV_BUFFER_STATUS_CLEARED: return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT: return "timeout (the frame's packets stopped coming)";
    case ARV_BUFFER_STATUS_MISSING_PACKETS: return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID: return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH: return "size mismatch (frame larger than the buffer)";
    case ARV_BUFFER_STATUS_FILLING: return "still filling";
    case ARV_BUFFER_STATUS_ABORTED: return "aborted";
    default: return "unknown";
  }
}

// Called on Aravis's heartbeat thread when a GigE camera stops answering.
void OnControlLost(ArvDevice*, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

struct Camera {
  std::string name;  // "genicam: left camera (serial GV01)"
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong lost_handler = 0;
  std::atomic<bool> lost{false};
  int width = 0, height = 0;

  bool answering = true;  // false once a command to it failed: nothing more is sent to it
  ClockMapping clock;     // its timestamps onto the system clock
};

// Gives up one camera's Aravis objects. A camera that no longer answers is sent nothing
// (each command to a vanished GigE camera waits out Aravis's retries, seconds), and even
// so dropping the device waits for its "leave control" command: the caller runs this on
// a thread of its own, so that a failed capture returns at once.
void Release(ArvCamera* camera, ArvStream* stream, bool answering) {
  if (camera != nullptr && answering) arv_camera_stop_acquisition(camera, nullptr);
  if (stream != nullptr) g_object_unref(stream);
  if (camera != nullptr) g_object_unref(camera);
}

class GenicamStereo : public StereoSource {
 public:
  explicit GenicamStereo(GenicamOptions options) : options_(std::move(options)) {
    // Aravis searches GigE Vision and USB3 Vision by default; its Fake interface (a camera
    // simulated inside this process) only when asked.
    if (options_.fake_interface) arv_enable_interface("Fake");
    cameras_[0].name = "genicam: left camera (" + options_.left.Describe() + ")";
    cameras_[1].name = "genicam: right camera (" + options_.right.Describe() + ")";
  }
  ~GenicamStereo() override {
    CloseAll();
    for (auto& c : closers_) c.thread.join();
  }

  StereoFrames Capture() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!open_) {
      try {
        // One discovery for both cameras (each takes about a second on GigE Vision).
        if (!options_.left.serial.empty() || !options_.right.serial.empty()) arv_update_device_list();
        Open(cameras_[0], options_.left, true);
        Open(cameras_[1], options_.right, false);
        open_ = true;
      } catch (const CaptureError&) {
        CloseAll();
        throw;
      }
    }
    reopen_ = false;
    // The budget starts once the cameras are open (finding them takes a discovery).
    const auto deadline = Clock::now() + std::chrono::microseconds(static_cast<std::int64_t>(options_.timeout_ms * 1e3));
    try {
      return CaptureOpen(deadline);
    } catch (const CaptureError&) {
      if (reopen_) CloseAll();  // reopened by the next Capture()
      throw;
    }
  }

 private:
  std::string ResolveDeviceId(const Camera& cam, const CameraId& id) {
    if (!id.device_id.empty()) return id.device_id;
    std::string seen;
    for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
      const char* serial = arv_get_device_serial_nbr(i);
      const char* device = arv_get_device_id(i);
      if (serial != nullptr && id.serial == serial && device != nullptr) return device;
      seen += std::string(seen.empty() ? "" : ", ") + (device ? device : "?") + " (serial " +
              (serial ? serial : "?") + ")";
    }
    throw CaptureError(cam.name + ": not found (cameras seen: " + (seen.empty() ? "none" : seen) + ")");
  }

  void Open(Camera& cam, const CameraId& id, bool left) {
    const std::string device = ResolveDeviceId(cam, id);
    GError* error = nullptr;
    cam.camera = arv_camera_new(device.c_str(), &error);
    Check(error, cam.name + ": cannot open " + device);
    if (cam.camera == nullptr) throw CaptureError(cam.name + ": cannot open " + device);
    cam.lost = false;
    cam.answering = true;
    cam.lost_handler = g_signal_connect(arv_camera_get_device(cam.camera), "control-lost",
                                        G_CALLBACK(OnControlLost), &cam.lost);
    ArvCamera* c = cam.camera;
    arv_camera_stop_acquisition(c, nullptr);  // a camera left streaming by a killed process

    arv_camera_set_pixel_format_from_string(c, options_.pixel_format.c_str(), &error);
    Check(error, cam.name + ": cannot set PixelFormat " + options_.pixel_format);

    // Binning before the region: the region is in binned pixels.
    const bool binning_available = arv_camera_is_binning_available(c, nullptr);
    if (options_.binning != 1 && !binning_available) {
      throw CaptureError(cam.name + ": binning " + std::to_string(options_.binning) + " asked but the camera has no binning");
    }
    if (binning_available) {
      arv_camera_set_binning(c, options_.binning, options_.binning, &error);
      Check(error, cam.name + ": cannot set binning " + std::to_string(options_.binning));
      gint bx = 0, by = 0;
      arv_camera_get_binning(c, &bx, &by, &error);
      Check(error, cam.name + ": cannot read binning");
      if (bx != options_.binning || by != options_.binning) {
        throw CaptureError(cam.name + ": binning " + std::to_string(options_.binning) + " became " +
                           std::to_string(bx) + "x" + std::to_string(by));
      }
    }

    int x = options_.roi_x, y = options_.roi_y, w = options_.roi_width, h = options_.roi_height;
    if (w == 0) {  // the whole (binned) sensor
      gint lo = 0, hi = 0;
      arv_camera_get_width_bounds(c, &lo, &hi, &error);
      Check(error, cam.name + ": cannot read Width bounds");
      w = hi;
      arv_camera_get_height_bounds(c, &lo, &hi, &error);
      Check(error, cam.name + ": cannot read Height bounds");
      h = hi;
      x = y = 0;
    }
    arv_camera_set_region(c, x, y, w, h, &error);
    Check(error, cam.name + ": cannot set region " + RegionText(x, y, w, h));
    gint gx = 0, gy = 0, gw = 0, gh = 0;
    arv_camera_get_region(c, &gx, &gy, &gw, &gh, &error);
    Check(error, cam.name + ": cannot read the region");
    // A camera rounds a region to its increments and clips it to the sensor: the rig's
    // camera models are for the region asked for, so any other one is an error.
    if (gx != x || gy != y || gw != w || gh != h) {
      throw CaptureError(cam.name + ": region " + RegionText(x, y, w, h) + " became " +
                         RegionText(gx, gy, gw, gh) + " (the camera's increments or sensor size)");
    }
    cam.width = gw;
    cam.height = gh;

    // One exposure and one gain for the pair: auto runs on the left camera only and
    // CaptureOpen copies its values to the right one.
    const bool exposure_auto_available = arv_camera_is_exposure_auto_available(c, nullptr);
    if (options_.exposure_auto && left) {
      if (!exposure_auto_available) throw CaptureError(cam.name + ": exposure_us: auto asked but the camera has no ExposureAuto");
      arv_camera_set_exposure_time_auto(c, ARV_AUTO_CONTINUOUS, &error);
      Check(error, cam.name + ": cannot set ExposureAuto Continuous");
    } else {
      if (exposure_auto_available) {
        arv_camera_set_exposure_time_auto(c, ARV_AUTO_OFF, &error);
        Check(error, cam.name + ": cannot set ExposureAuto Off");
      }
      if (!options_.exposure_auto) {
        arv_camera_set_exposure_time(c, options_.exposure_us, &error);
        Check(error, cam.name + ": cannot set exposure " + std::to_string(options_.exposure_us) + " us");
      }
    }
    const bool gain_auto_available = arv_camera_is_gain_auto_available(c, nullptr);
    if (options_.gain_auto && left) {
      if (!gain_auto_available) throw CaptureError(cam.name + ": gain: auto asked but the camera has no GainAuto");
      arv_camera_set_gain_auto(c, ARV_AUTO_CONTINUOUS, &error);
      Check(error, cam.name + ": cannot set GainAuto Continuous");
    } else {
      if (gain_auto_available) {
        arv_camera_set_gain_auto(c, ARV_AUTO_OFF, &error);
        Check(error, cam.name + ": cannot set GainAuto Off");
      }
      if (!options_.gain_auto) {
        arv_camera_set_gain(c, options_.gain, &error);
        Check(error, cam.name + ": cannot set gain " + std::to_string(options_.gain));
      }
    }

    arv_camera_set_acquisition_mode(c, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    Check(error, cam.name + ": cannot set AcquisitionMode Continuous");
    if (options_.trigger == "software") {
      arv_camera_set_trigger(c, "Software", &error);
      Check(error, cam.name + ": cannot set the software trigger");
    } else if (options_.trigger == "hardware") {
      arv_camera_set_trigger(c, options_.trigger_line.c_str(), &error);
      Check(error, cam.name + ": cannot set the hardware trigger on " + options_.trigger_line);
    } else {
      arv_camera_clear_triggers(c, &error);
      Check(error, cam.name + ": cannot turn the triggers off");
      if (arv_camera_is_frame_rate_available(c, nullptr)) {
        arv_camera_set_frame_rate(c, options_.frame_rate_hz, &error);
        Check(error, cam.name + ": cannot set the frame rate " + std::to_string(options_.frame_rate_hz) + " Hz");
      }
    }

    cam.stream = arv_camera_create_stream(c, nullptr, nullptr, &error);
    Check(error, cam.name + ": cannot open its stream");
    if (cam.stream == nullptr) throw CaptureError(cam.name + ": cannot open its stream");
    const guint payload = arv_camera_get_payload(c, &error);
    Check(error, cam.name + ": cannot read PayloadSize");
    for (int i = 0; i < options_.buffers; ++i) arv_stream_push_buffer(cam.stream, arv_buffer_new(payload, nullptr));
    arv_camera_start_acquisition(c, &error);
    Check(error, cam.name + ": cannot start acquisition");
  }

  static std::string RegionText(int x, int y, int w, int h) {
    return std::to_string(w) + "x" + std::to_string(h) + " at " + std::to_string(x) + "," + std::to_string(y);
  }

  void CloseAll() {
    // Threads that have finished releasing are joined, so that a camera that comes and
    // goes all mission long does not pile them up.
    for (auto it = closers_.begin(); it != closers_.end();) {
      if (it->done->load()) {
        it->thread.join();
        it = closers_.erase(it);
      } else {
        ++it;
      }
    }
    for (auto& cam : cameras_) {
      if (cam.camera == nullptr) continue;
      // The flag belongs to `cam`, which the next Open() reuses: no callback may reach it.
      if (cam.lost_handler != 0) g_signal_handler_disconnect(arv_camera_get_device(cam.camera), cam.lost_handler);
      auto done = std::make_shared<std::atomic<bool>>(false);
      closers_.push_back({std::thread([camera = cam.camera, stream = cam.stream, answering = cam.answering && !cam.lost,
                                       done] {
                            Release(camera, stream, answering);
                            done->store(true);
                          }),
                          done});
      cam.camera = nullptr;
      cam.stream = nullptr;
      cam.lost_handler = 0;
    }
    open_ = false;
  }

  StereoFrames CaptureOpen(Clock::time_point deadline) {
    for (auto& cam : cameras_) {
      if (cam.lost) {
        reopen_ = true;
        throw CaptureError(cam.name + ": stopped answering (control lost); reopening at the next capture");
      }
    }
    GError* error = nullptr;
    if (options_.exposure_auto || options_.gain_auto) ShareExposureAndGain();

    // Frames taken before this request are stale: give their buffers back, so that the
    // pair popped below was taken for this request (or, free-running, after it).
    for (auto& cam : cameras_) {
      while (ArvBuffer* old = arv_stream_try_pop_buffer(cam.stream)) arv_stream_push_buffer(cam.stream, old);
    }
    if (options_.trigger == "software") {
      // Back to back: the two commands are a GVCP round trip apart (well under a
      // millisecond on a direct link). A hardware trigger line makes it exact.
      for (auto& cam : cameras_) {
        arv_camera_software_trigger(cam.camera, &error);
        if (error != nullptr) reopen_ = true, cam.answering = false;
        Check(error, cam.name + ": software trigger failed");
      }
    }
    auto next = [&](Side side) { return Pop(cameras_[side == Side::kLeft ? 0 : 1], deadline); };
    // Triggered, each camera takes exactly one frame per request: a later one would never
    // come, so a pair that disagrees is rejected at once. Free-running, the side behind
    // takes its next frame.
    const int advances = options_.trigger == "free" ? options_.max_advances : 0;
    return PairFrames(next, static_cast<std::int64_t>(options_.pairing_tolerance_ms * 1e6), advances, "genicam");
  }

  void ShareExposureAndGain() {
    GError* error = nullptr;
    ArvCamera* left = cameras_[0].camera;
    ArvCamera* right = cameras_[1].camera;
    if (options_.exposure_auto) {
      const double us = arv_camera_get_exposure_time(left, &error);
      Check(error, cameras_[0].name + ": cannot read the auto exposure");
      arv_camera_set_exposure_time(right, us, &error);
      Check(error, cameras_[1].name + ": cannot set the left camera's exposure");
    }
    if (options_.gain_auto) {
      const double gain = arv_camera_get_gain(left, &error);
      Check(error, cameras_[0].name + ": cannot read the auto gain");
      arv_camera_set_gain(right, gain, &error);
      Check(error, cameras_[1].name + ": cannot set the left camera's gain");
    }
  }

  Frame Pop(Camera& cam, Clock::time_point deadline) {
    std::string dropped;  // the last incomplete frame, free-running
    int drops = 0;
    for (;;) {
      const auto left_us = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
      ArvBuffer* buffer = arv_stream_timeout_pop_buffer(cam.stream, left_us > 0 ? static_cast<guint64>(left_us) : 0);
      if (buffer == nullptr) {
        // A camera that stopped answering, or a stream that stalled: both are reopened.
        reopen_ = true;
        if (cam.lost) throw CaptureError(cam.name + ": stopped answering (control lost); reopening at the next capture");
        throw CaptureError(cam.name + ": no frame within " + Ms(options_.timeout_ms) + " ms (trigger " +
                           options_.trigger + (drops > 0 ? ", " + std::to_string(drops) + " dropped, last " + dropped : "") +
                           "); reopening at the next capture");
      }
      const ArvBufferStatus status = arv_buffer_get_status(buffer);
      if (status == ARV_BUFFER_STATUS_SUCCESS) return Convert(cam, buffer);
      dropped = "frame " + std::to_string(arv_buffer_get_frame_id(buffer)) + " dropped: " + StatusName(status);
      arv_stream_push_buffer(cam.stream, buffer);
      // Triggered, the dropped frame was this request's: the capture fails. Free-running,
      // the next frame will do.
      if (options_.trigger != "free") throw CaptureError(cam.name + ": " + dropped);
      ++drops;
    }
  }

  // The image of a complete buffer, which goes back to the stream.
  Frame Convert(Camera& cam, ArvBuffer* buffer) {
    struct GiveBack {
      ArvStream* s;
      ArvBuffer* b;
      ~GiveBack() { arv_stream_push_buffer(s, b); }
    } give_back{cam.stream, buffer};
    if (arv_buffer_get_payload_type(buffer) != ARV_BUFFER_PAYLOAD_TYPE_IMAGE) {
      throw CaptureError(cam.name + ": frame " + std::to_string(arv_buffer_get_frame_id(buffer)) + " is not an image");
    }
    const int w = arv_buffer_get_image_width(buffer), h = arv_buffer_get_image_height(buffer);
    const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer);
    const int type = format == ARV_PIXEL_FORMAT_MONO_8 ? CV_8UC1 : format == ARV_PIXEL_FORMAT_MONO_16 ? CV_16UC1 : -1;
    if (type < 0) {
      char text[16];
      std::snprintf(text, sizeof(text), "0x%08x", static_cast<unsigned>(format));
      throw CaptureError(cam.name + ": frame in pixel format " + text + " (expected " + options_.pixel_format + ")");
    }
    std::size_t size = 0;
    const void* data = arv_buffer_get_data(buffer, &size);
    const std::size_t need = static_cast<std::size_t>(w) * h * (type == CV_8UC1 ? 1 : 2);
    if (w != cam.width || h != cam.height || data == nullptr || size < need) {
      throw CaptureError(cam.name + ": frame is " + std::to_string(w) + "x" + std::to_string(h) + ", " +
                         std::to_string(size) + " bytes (expected " + std::to_string(cam.width) + "x" +
                         std::to_string(cam.height) + ")");
    }
    Frame frame;
    // Mono16 is little-endian in GenICam, as on this computer.
    frame.image = cv::Mat(h, w, type, const_cast<void*>(data)).clone();
    frame.frame_id = arv_buffer_get_frame_id(buffer);
    frame.timestamp_ns = static_cast<std::int64_t>(options_.timestamps == "device" ? arv_buffer_get_timestamp(buffer)
                                                                                     : arv_buffer_get_system_timestamp(buffer));
    // The exposure on the system clock: the frame's timestamp, in whichever clock it is,
    // mapped through the lowest receipt delay seen (ClockMapping).
    frame.system_ns = cam.clock.ToSystem(frame.timestamp_ns, SystemNowNs());
    return frame;
  }

  static std::string Ms(double ms) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.0f", ms);
    return text;
  }

  GenicamOptions options_;
  std::mutex mutex_;
  Camera cameras_[2];
  bool open_ = false;
  bool reopen_ = false;  // set by a failure that the next capture should reopen the cameras for
  struct Closer {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done;
  };
  std::vector<Closer> closers_;  // releasing cameras given up (see Release)
};

}  // namespace

std::unique_ptr<StereoSource> MakeGenicamSource(const GenicamOptions& options) {
  return std::make_unique<GenicamStereo>(options);
}

}  // namespace rover::camera_hw
