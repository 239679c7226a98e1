// VO-9 and VO-10 limits against the executor's: a step commanded at the executor's
// limit, plus slip, must not be refused for its size. The project's configs must agree.
#include "config/yaml_config.hpp"
#include "sequence/executor.hpp"
#include "sequence/parser.hpp"
#include "vo/visual_odometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace rover::vo {
namespace {

// VO's limits sit at least this far beyond the executor's largest step.
constexpr double kMargin = 1.5;

void ExpectMargin(const VoOptions& vo, const sequence::ExecutorOptions& executor,
                  const std::string& what) {
  const sequence::LanguageLimits language;
  const double max_step_m = std::max(executor.default_step_m, language.max_step_m);
  const double max_turn_deg = executor.default_max_turn_deg;
  SCOPED_TRACE(what);
  // VO-10: motion too large for the overlap.
  if (vo.motion_max_rotation_deg > 0) {
    EXPECT_GE(vo.motion_max_rotation_deg, kMargin * max_turn_deg);
  }
  if (vo.motion_max_translation_m > 0) {
    EXPECT_GE(vo.motion_max_translation_m, kMargin * max_step_m);
  }
  // The executor plans 60 % overlap at its largest turn; VO refuses only below 60 / 1.5 %.
  EXPECT_LE(vo.motion_min_overlap, 0.6 / kMargin + 1e-12);
  // VO-9 sanity limits, where set.
  if (vo.sanity_max_translation_m > 0) {
    EXPECT_GE(vo.sanity_max_translation_m, kMargin * max_step_m);
  }
  if (vo.sanity_max_site_dx_m > 0) {
    EXPECT_GE(vo.sanity_max_site_dx_m, kMargin * max_step_m);
  }
  if (vo.sanity_max_site_dy_m > 0) {
    EXPECT_GE(vo.sanity_max_site_dy_m, kMargin * max_step_m);
  }
  if (vo.sanity_max_yaw_deg > 0) {
    EXPECT_GE(vo.sanity_max_yaw_deg, kMargin * max_turn_deg);
  }
}

TEST(VoLimits, VO9_VO10_DefaultsLeaveAMarginOverTheExecutorsSteps) {
  ExpectMargin(VoOptions{}, sequence::ExecutorOptions{}, "VoOptions and ExecutorOptions defaults");
}

TEST(VoLimits, VO9_VO10_ProjectConfigsLeaveAMarginOverTheExecutorsSteps) {
  const std::string root = ROVER_SOURCE_DIR;
  const VoOptions vo = LoadVoOptions(config::ConfigNode::LoadFile(root + "/configs/vo.yaml")["vo"]);
  const sequence::ExecutorOptions executor =
      sequence::LoadExecutorOptionsFile(root + "/configs/rover.yaml");
  ExpectMargin(vo, executor, "configs/vo.yaml against configs/rover.yaml executor:");
}

}  // namespace
}  // namespace rover::vo
