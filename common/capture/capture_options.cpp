#include "capture/capture_options.hpp"

#include <filesystem>

namespace rover::capture {
namespace {

std::string RelativeToConfig(const std::string& path, const std::string& config_path) {
  if (path.empty() || path[0] == '/' || config_path.empty()) return path;
  return (std::filesystem::path(config_path).parent_path() / path).string();
}

}  // namespace

CaptureOptions CaptureOptions::Load(const config::ConfigNode& section, const std::string& config_path,
                                    const std::string& source_override) {
  CaptureOptions o;
  section.CheckKeys({"source", "rig", "encoding", "rate_hz", "render", "hazcam", "genicam", "gstreamer"});
  section.GetEnum("source", o.source, {"sim", "dataset", "genicam", "gstreamer"});
  section.Get("rig", o.rig_path);
  section.GetEnum("encoding", o.encoding, {"png", "raw"});
  section.Get("rate_hz", o.rate_hz, 0.0, 100.0);
  const std::string configured_source = o.source;
  if (!source_override.empty()) o.source = source_override;
  o.rig_path = RelativeToConfig(o.rig_path, config_path);
  o.render = render::LoadRenderOptions(section["render"]);

  const config::ConfigNode hazcam = section["hazcam"];
  if (hazcam.IsNull()) return o;
  hazcam.CheckKeys({"rig", "render"});
  std::string rig;
  hazcam.Get("rig", rig);
  if (rig.empty()) return o;
  // --dataset on the simulator's config (the systemd unit's way to play a recording): a
  // dataset has no HAZCAM images, so the pair is left out and the process says so.
  if (configured_source == "sim" && o.source != "sim") {
    o.notice = hazcam.source() + ": " + hazcam.path() + " ignored: the " + o.source +
               " source has no HAZCAM images (only the sim source takes a HAZCAM pair)";
    return o;
  }
  // Refused rather than ignored: a map configured to see the near field must not go blind
  // there without a word. camera_hw takes one synchronised pair, and a dataset has no
  // HAZCAM images.
  if (o.source != "sim") {
    hazcam.Fail("expected no HAZCAM rig with source " + o.source +
                " (only the sim source takes a HAZCAM pair; remove capture.hazcam)");
  }
  o.hazcam = HazcamOptions{RelativeToConfig(rig, config_path), render::LoadRenderOptions(hazcam["render"], o.render)};
  return o;
}

}  // namespace rover::capture
