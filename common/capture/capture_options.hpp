// The `capture:` section of camera_capture's config (README, "Processes"), the part that
// is not a hardware source's own (`genicam:`, `gstreamer:` are camera_hw's).
#pragma once

#include "config/yaml_config.hpp"
#include "render/render_options.hpp"

#include <optional>
#include <string>

namespace rover::capture {

// The front HAZCAM pair (sim source only).
struct HazcamOptions {
  // The rig file; relative paths are resolved against the config file's folder.
  std::string rig_path;
  // The NAVCAM pair's render options overridden key by key by `capture.hazcam.render`
  // (image_scale 0.25 renders the 1024x1024 models at 256x256).
  render::RenderOptions render;
};

struct CaptureOptions {
  std::string source = "sim";  // sim | dataset | genicam | gstreamer
  std::string rig_path = "configs/cameras/navcam_pinhole.yaml";
  std::string encoding = "png";  // png | raw
  double rate_hz = 0.0;          // 0: only on CAPTURE_REQUEST
  render::RenderOptions render;  // the NAVCAM pair's (sim source)
  // Unset when `capture.hazcam` is absent or its rig empty.
  std::optional<HazcamOptions> hazcam;
  // One line for the process to print at start when a configured HAZCAM pair was left out
  // because `source_override` chose a source without HAZCAMs; empty otherwise.
  std::string notice;

  // Reads the section. `config_path` is the config file (relative rig paths are relative
  // to its folder, so that configs/ in the repository and /etc/rover on a rover computer
  // both work; "" leaves them as they are). `source_override` replaces `source` when set
  // (camera_capture's --dataset; a HAZCAM rig is then left out, with `notice`). Throws
  // config::ConfigError naming the key: unknown keys, bad values, and a HAZCAM rig with a
  // configured source other than sim.
  static CaptureOptions Load(const config::ConfigNode& section, const std::string& config_path,
                             const std::string& source_override = "");
};

}  // namespace rover::capture
