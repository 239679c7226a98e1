// The gstreamer source: one gst-launch pipeline per camera, each ending in an appsink.
#include "camera_hw/sources.hpp"

#include <gst/app/gstappsink.h>
#include <gst/gst.h>

#include <mutex>

namespace rover::camera_hw {

bool GstreamerAvailable() { return true; }

namespace {

std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// The first error on a pipeline's bus, if any, as one line.
std::string BusError(GstElement* pipeline) {
  GstBus* bus = gst_element_get_bus(pipeline);
  std::string text;
  while (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
    if (text.empty()) {
      GError* error = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_error(m, &error, &debug);
      // The element that failed ("v4l2src0: Cannot identify device ..."), as gst-launch says.
      const char* element = GST_MESSAGE_SRC_NAME(m);
      text = OneLine(std::string(element ? element : "?") + ": " + (error ? error->message : "unknown error"));
      if (error) g_error_free(error);
      g_free(debug);
    }
    gst_message_unref(m);
  }
  gst_object_unref(bus);
  return text;
}

struct Pipeline {
  std::string name;  // "gstreamer: left pipeline"
  GstElement* pipeline = nullptr;
  GstAppSink* sink = nullptr;
  std::uint64_t samples = 0;

  ~Pipeline() {
    if (pipeline != nullptr) {
      gst_element_set_state(pipeline, GST_STATE_NULL);
      gst_object_unref(pipeline);
    }
    if (sink != nullptr) gst_object_unref(sink);
  }
};

class GstreamerStereo : public StereoSource {
 public:
  explicit GstreamerStereo(GstreamerOptions options) : options_(std::move(options)) {
    static std::once_flag once;
    static std::string init_error;
    std::call_once(once, [] {
      GError* error = nullptr;
      if (!gst_init_check(nullptr, nullptr, &error)) {
        init_error = OneLine(error ? error->message : "gst_init failed");
        if (error) g_error_free(error);
      }
    });
    if (!init_error.empty()) throw CaptureError("gstreamer: cannot start GStreamer: " + init_error);
    Build(pipelines_[0], "gstreamer: left pipeline", options_.left_pipeline);
    Build(pipelines_[1], "gstreamer: right pipeline", options_.right_pipeline);
    // A pipeline that parsed but cannot start yet (a camera not plugged in) is tried again
    // at each capture, as the genicam source opens its cameras: the process may start
    // before its cameras.
    try {
      Play();
    } catch (const CaptureError&) {
      restart_ = true;
    }
  }

  StereoFrames Capture() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (restart_) {
      // After an error, an end of stream or a stall: both pipelines start again together
      // (a camera unplugged and plugged back is opened anew by its source element).
      for (auto& p : pipelines_) gst_element_set_state(p.pipeline, GST_STATE_NULL);
      Play();
      restart_ = false;
    }
    const GstClockTime start = gst_util_get_timestamp();
    const GstClockTime budget = static_cast<GstClockTime>(options_.timeout_ms * 1e6);
    auto next = [&](Side side) {
      Pipeline& p = pipelines_[side == Side::kLeft ? 0 : 1];
      const GstClockTime spent = gst_util_get_timestamp() - start;
      return Pull(p, spent < budget ? budget - spent : 0);
    };
    return PairFrames(next, static_cast<std::int64_t>(options_.pairing_tolerance_ms * 1e6), options_.max_advances,
                      "gstreamer");
  }

 private:
  // Both pipelines to PLAYING on one clock with one base time, so that their buffer times
  // (base time + running time) are instants on one clock and can be compared, live or not.
  void Play() {
    GstClock* clock = gst_system_clock_obtain();
    const GstClockTime base = gst_clock_get_time(clock);
    for (auto& p : pipelines_) {
      gst_pipeline_use_clock(GST_PIPELINE(p.pipeline), clock);
      gst_element_set_start_time(p.pipeline, GST_CLOCK_TIME_NONE);  // keep the base time set here
      gst_element_set_base_time(p.pipeline, base);
    }
    gst_object_unref(clock);
    for (auto& p : pipelines_) {
      if (gst_element_set_state(p.pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
        const std::string why = BusError(p.pipeline);
        restart_ = true;
        throw CaptureError(p.name + ": cannot start" + (why.empty() ? "" : ": " + why));
      }
    }
  }

  static void Build(Pipeline& p, const std::string& name, const std::string& text) {
    p.name = name;
    GError* error = nullptr;
    p.pipeline = gst_parse_launch(text.c_str(), &error);
    if (error != nullptr) {
      const std::string why = OneLine(error->message);
      g_error_free(error);
      throw CaptureError(name + ": " + why + " (in \"" + text + "\")");
    }
    if (p.pipeline == nullptr || !GST_IS_PIPELINE(p.pipeline)) {
      throw CaptureError(name + ": expected a pipeline of several elements ending in appsink (in \"" + text + "\")");
    }
    // The options loader checked that the text ends in appsink; find that element.
    GstIterator* it = gst_bin_iterate_sinks(GST_BIN(p.pipeline));
    GValue item = G_VALUE_INIT;
    while (gst_iterator_next(it, &item) == GST_ITERATOR_OK) {
      GstElement* element = GST_ELEMENT(g_value_get_object(&item));
      if (GST_IS_APP_SINK(element) && p.sink == nullptr) p.sink = GST_APP_SINK(gst_object_ref(element));
      g_value_reset(&item);
    }
    g_value_unset(&item);
    gst_iterator_free(it);
    if (p.sink == nullptr) throw CaptureError(name + ": no appsink (in \"" + text + "\")");
  }

  Frame Pull(Pipeline& p, GstClockTime timeout) {
    GstSample* sample = gst_app_sink_try_pull_sample(p.sink, timeout);
    if (sample == nullptr) {
      restart_ = true;
      const std::string why = BusError(p.pipeline);
      if (!why.empty()) throw CaptureError(p.name + ": " + why);
      if (gst_app_sink_is_eos(p.sink)) throw CaptureError(p.name + ": ended (end of stream)");
      throw CaptureError(p.name + ": no frame within " + std::to_string(static_cast<long>(options_.timeout_ms)) + " ms");
    }
    struct Unref {
      GstSample* s;
      ~Unref() { gst_sample_unref(s); }
    } unref{sample};
    GstBuffer* buffer = gst_sample_get_buffer(sample);
    GstCaps* caps = gst_sample_get_caps(sample);
    const GstStructure* s = caps ? gst_caps_get_structure(caps, 0) : nullptr;
    int w = 0, h = 0;
    const char* format = s ? gst_structure_get_string(s, "format") : nullptr;
    if (s == nullptr || buffer == nullptr || !gst_structure_get_int(s, "width", &w) ||
        !gst_structure_get_int(s, "height", &h) || format == nullptr) {
      throw CaptureError(p.name + ": a sample without video caps (expected video/x-raw,format=GRAY8 or GRAY16_LE)");
    }
    const std::string f = format;
    const int type = f == "GRAY8" ? CV_8UC1 : f == "GRAY16_LE" ? CV_16UC1 : -1;
    if (type < 0) {
      throw CaptureError(p.name + ": frames in format " + f + " (expected GRAY8 or GRAY16_LE: end the pipeline with " +
                         "videoconvert ! video/x-raw,format=GRAY8 ! appsink)");
    }
    GstMapInfo map;
    if (!gst_buffer_map(buffer, &map, GST_MAP_READ)) throw CaptureError(p.name + ": cannot read a frame");
    // GStreamer pads each row of a raw video frame to a multiple of 4 bytes.
    const std::size_t row = static_cast<std::size_t>(w) * (type == CV_8UC1 ? 1 : 2);
    const std::size_t stride = (row + 3) / 4 * 4;
    Frame frame;
    if (map.size < stride * (h - 1) + row) {
      gst_buffer_unmap(buffer, &map);
      throw CaptureError(p.name + ": frame of " + std::to_string(map.size) + " bytes for " + std::to_string(w) + "x" +
                         std::to_string(h) + " " + f);
    }
    frame.image = cv::Mat(h, w, type, map.data, stride).clone();
    gst_buffer_unmap(buffer, &map);
    // An instant on the shared clock: base time + running time of the buffer.
    const GstClockTime pts = GST_BUFFER_PTS(buffer);
    if (!GST_CLOCK_TIME_IS_VALID(pts)) throw CaptureError(p.name + ": a frame without a timestamp");
    GstSegment* segment = gst_sample_get_segment(sample);
    const GstClockTime running = segment ? gst_segment_to_running_time(segment, GST_FORMAT_TIME, pts) : pts;
    frame.timestamp_ns = static_cast<std::int64_t>(gst_element_get_base_time(p.pipeline) + running);
    // The same instant on the system clock: the pipeline's clock (Play) read now against
    // the system clock now.
    GstClock* clock = gst_system_clock_obtain();
    const auto clock_now = static_cast<std::int64_t>(gst_clock_get_time(clock));
    gst_object_unref(clock);
    frame.system_ns = SystemNowNs() - (clock_now - frame.timestamp_ns);
    frame.frame_id = p.samples++;
    return frame;
  }

  GstreamerOptions options_;
  std::mutex mutex_;
  Pipeline pipelines_[2];
  bool restart_ = false;  // a pipeline failed: both start again at the next capture
};

}  // namespace

std::unique_ptr<StereoSource> MakeGstreamerSource(const GstreamerOptions& options) {
  return std::make_unique<GstreamerStereo>(options);
}

}  // namespace rover::camera_hw
