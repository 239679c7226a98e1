// A checked operator sequence (LANGUAGE.md). All values are SI: metres, radians, seconds,
// and fractions (40 % is stored as 0.40). Signs follow mobility_command_t: + distance is
// forward, + turn is clockwise seen from above (north toward east), + arc radius curves
// right. Headings and coordinates are in the current site frame (X north, Y east).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace rover::sequence {

struct KeepOutZone {
  enum class Shape { kCircle, kPolygon };
  std::string name;
  Shape shape = Shape::kCircle;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // circle, site x y (m)
  double radius_m = 0.0;                              // circle
  std::vector<Eigen::Vector2d> vertices;              // polygon, site x y (m)
};

// ---- motion commands ----
struct Drive {
  double distance_m = 0.0;  // signed: + forward
};
struct Arc {
  double radius_m = 0.0;    // signed: + curves right (clockwise), - curves left
  double distance_m = 0.0;  // signed arc length: + forward
};
struct Turn {
  double angle_rad = 0.0;   // signed: + clockwise (right)
};
struct TurnTo {
  double heading_rad = 0.0;  // site heading: 0 north, +pi/2 east
};
struct Goto {
  Eigen::Vector2d target = Eigen::Vector2d::Zero();  // site x (north), y (east)
  double tolerance_m = 0.0;                          // radius of the goal disc
  std::optional<double> time_limit_s;                // rover time from the goto's start
  std::optional<double> distance_limit_m;            // distance driven by this goto
  // `avoid on`: each step is chosen by arc voting on the hazard monitor's traversability
  // map (common/avoidance) instead of steering straight at the target. Either way every
  // step passes the monitor's predictive check, map included.
  bool avoid = false;
};

// ---- settings (apply from their line to the rest of the sequence) ----
enum class VoFailureAction { kAbort, kContinue };
struct VoSetting {
  bool enabled = false;
  std::optional<double> step_m;            // absent: keep the step in force
  std::optional<double> max_turn_rad;      // absent: keep the max turn in force
  std::optional<int> max_failures;         // absent: keep; acceptable failures
  std::optional<VoFailureAction> past_max; // what happens past max_failures
  std::optional<double> wait_s;            // wall-clock wait for a VO answer
};
// `vo lost`: what the executor does when VO could not measure a step on ground where slip
// is likely (a slope steeper than `slope`, or VO measured more than `slip` % of slip or
// sideways drift in one of the recent steps). There, wheel odometry is no evidence of
// progress: Sol 206's rover reported metres uphill while it slid downhill.
enum class VoLostAction { kAbort, kRetry, kShorten };
struct VoLostSetting {
  VoLostAction action = VoLostAction::kAbort;
  int retries = 0;                    // kRetry: pairs taken again where the rover stands
  std::optional<double> slope_rad;    // absent: keep the slope in force (executor option)
  std::optional<double> slip_pct;     // absent: keep the slip in force (executor option)
};
struct SlipSetting {
  bool enabled = false;
  double limit_pct = 100.0;              // abort when one step's slip exceeds this
  double no_progress_fraction = 0.0;     // a step with progress below this counts
  int over_steps = 1;                    // ... and this many in a row abort
};
struct TiltSetting {
  bool enabled = false;                  // `tilt off` disables the sequence's limits
  std::optional<double> roll_rad;
  std::optional<double> pitch_rad;
};
struct LimitSetting {
  std::optional<double> time_s;          // total rover time since the sequence started
  std::optional<double> distance_m;      // total distance driven in the sequence
};
struct KeepOutAdd {
  KeepOutZone zone;
};
struct KeepOutRemove {
  std::string name;
};
struct KeepOutClear {};
struct NewSite {};
enum class ImagePurpose { kScience, kVoBaseline };
struct Images {
  ImagePurpose purpose = ImagePurpose::kScience;
};

using Action = std::variant<Drive, Arc, Turn, TurnTo, Goto, VoSetting, VoLostSetting, SlipSetting,
                            TiltSetting, LimitSetting, KeepOutAdd, KeepOutRemove, KeepOutClear,
                            NewSite, Images>;

struct Command {
  int line = 0;         // 1-based line in the file
  std::string text;     // the line without its comment, trimmed
  Action action;
};

bool IsMotion(const Command& command);  // drive, arc, turn, turnto, goto

struct Sequence {
  std::string name;     // file name, for messages
  std::vector<Command> commands;
};

}  // namespace rover::sequence
