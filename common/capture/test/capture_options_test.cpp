// The `capture:` section: defaults, rig paths relative to the config file, the HAZCAM's
// render options over the NAVCAM's, and a HAZCAM refused with any source but sim.
#include "capture/capture_options.hpp"

#include <gtest/gtest.h>

#include <string>

namespace rover::capture {
namespace {

config::ConfigNode Section(const std::string& yaml) {
  return config::ConfigNode::FromString(yaml, "/etc/rover/rover.yaml")["capture"];
}

TEST(CaptureOptions, DefaultsAndNoHazcamWithoutTheSection) {
  const auto o = CaptureOptions::Load(Section("capture:\n  source: sim\n"), "/etc/rover/rover.yaml");
  EXPECT_EQ(o.source, "sim");
  EXPECT_EQ(o.rig_path, "/etc/rover/configs/cameras/navcam_pinhole.yaml");
  EXPECT_EQ(o.encoding, "png");
  EXPECT_EQ(o.rate_hz, 0.0);
  EXPECT_FALSE(o.hazcam.has_value());
  // An empty rig is no HAZCAM either.
  EXPECT_FALSE(CaptureOptions::Load(Section("capture:\n  hazcam: {rig: \"\"}\n"), "").hazcam.has_value());
}

TEST(CaptureOptions, HazcamRigIsRelativeToTheConfigAndItsRenderOverridesTheNavcams) {
  const auto o = CaptureOptions::Load(Section("capture:\n  rig: cameras/navcam.yaml\n"
                                              "  render: {image_scale: 0.5, threads: 2, noise_sigma_dn: 2.5}\n"
                                              "  hazcam:\n    rig: cameras/hazcam_front.yaml\n"
                                              "    render: {image_scale: 0.25}\n"),
                                      "/etc/rover/rover.yaml");
  EXPECT_EQ(o.rig_path, "/etc/rover/cameras/navcam.yaml");
  EXPECT_EQ(o.render.image_scale, 0.5);
  ASSERT_TRUE(o.hazcam.has_value());
  EXPECT_EQ(o.hazcam->rig_path, "/etc/rover/cameras/hazcam_front.yaml");
  EXPECT_EQ(o.hazcam->render.image_scale, 0.25);     // its own
  EXPECT_EQ(o.hazcam->render.threads, 2);            // the NAVCAM's
  EXPECT_EQ(o.hazcam->render.noise_sigma_dn, 2.5);   // the NAVCAM's
  // An absolute rig stays as it is; with no config file, relative paths too.
  const auto a = CaptureOptions::Load(Section("capture:\n  hazcam: {rig: /opt/hazcam.yaml}\n"), "/etc/rover/rover.yaml");
  EXPECT_EQ(a.hazcam->rig_path, "/opt/hazcam.yaml");
  EXPECT_EQ(a.hazcam->render.image_scale, 1.0);
  EXPECT_EQ(CaptureOptions::Load(Section("capture:\n  hazcam: {rig: h.yaml}\n"), "").hazcam->rig_path, "h.yaml");
}

std::string LoadError(const std::string& yaml, const std::string& source_override = "") {
  try {
    CaptureOptions::Load(Section(yaml), "/etc/rover/rover.yaml", source_override);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(CaptureOptions, AHazcamWithASourceOtherThanSimIsRefusedInOneLine) {
  for (const char* source : {"dataset", "genicam", "gstreamer"}) {
    EXPECT_EQ(LoadError(std::string("capture:\n  source: ") + source + "\n  hazcam: {rig: h.yaml}\n"),
              std::string("/etc/rover/rover.yaml: capture.hazcam: expected no HAZCAM rig with source ") + source +
                  " (only the sim source takes a HAZCAM pair; remove capture.hazcam)");
  }
  // --dataset on the simulator's config (the systemd unit's way to play a recording): the
  // HAZCAM pair is left out, and the notice names the key.
  EXPECT_EQ(LoadError("capture:\n  source: sim\n  hazcam: {rig: h.yaml}\n", "dataset"), "");
  EXPECT_EQ(LoadError("capture:\n  source: genicam\n  hazcam: {rig: \"\"}\n"), "");
}

TEST(CaptureOptions, DatasetOverTheSimulatorsConfigLeavesTheHazcamOutAndSaysSo) {
  const auto o = CaptureOptions::Load(Section("capture:\n  source: sim\n  hazcam: {rig: h.yaml}\n"),
                                      "/etc/rover/rover.yaml", "dataset");
  EXPECT_EQ(o.source, "dataset");
  EXPECT_FALSE(o.hazcam.has_value());
  EXPECT_NE(o.notice.find("capture.hazcam ignored: the dataset source has no HAZCAM images"), std::string::npos)
      << o.notice;
  // Without the override the simulator's config keeps its HAZCAMs and says nothing.
  const auto sim = CaptureOptions::Load(Section("capture:\n  source: sim\n  hazcam: {rig: h.yaml}\n"),
                                        "/etc/rover/rover.yaml");
  EXPECT_TRUE(sim.hazcam.has_value());
  EXPECT_EQ(sim.notice, "");
}

TEST(CaptureOptions, UnknownKeysAndBadValuesNameTheKey) {
  EXPECT_NE(LoadError("capture:\n  hazcam: {rigg: h.yaml}\n").find("rigg"), std::string::npos);
  EXPECT_NE(LoadError("capture:\n  hazcam: {rig: h.yaml, render: {image_scal: 0.25}}\n").find("image_scal"),
            std::string::npos);
  EXPECT_NE(LoadError("capture:\n  hazcam: {rig: h.yaml, render: {image_scale: -1}}\n").find("capture.hazcam.render.image_scale"),
            std::string::npos);
  EXPECT_NE(LoadError("capture:\n  encoding: jpeg\n").find("capture.encoding"), std::string::npos);
}

}  // namespace
}  // namespace rover::capture
