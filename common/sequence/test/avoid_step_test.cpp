// `goto ... avoid on` and the map verdicts in the executor, against a small fake world: a
// kinematic rover, a camera whose every pair yields the test's traversability grid (the
// hazard monitor's map), and a monitor that judges each query's swept footprint on that
// grid (common/avoidance). No bus.
#include "avoidance/grid.hpp"
#include "hazards/keepout.hpp"
#include "sequence/executor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <string>

using namespace rover::sequence;
using rover::avoidance::CellClass;
using rover::avoidance::Grid;

namespace {

class MapWorld {
 public:
  Grid grid = Grid::Filled(-4, -6, 0.2, 60, 60, CellClass::kSafe, 0.9f);
  bool map_known = true;          // false: every cell unknown until the first pair
  bool camera = true;
  bool answers_looks = true;  // false: a camera with no pan-tilt unit, refusing pointed pairs
  // Set: what each pair shows of `grid` (the request, a site point); the map is what the
  // pairs so far have shown. Unset: the whole grid once a pair was taken (map_known).
  std::function<bool(const CaptureRequest&, const PlanePose&, double, double)> sees;
  PlanePose pose;
  std::vector<MobilityCommand> motions;
  std::vector<PlanePose> trail;  // the pose after each motion
  std::vector<CaptureRequest> captures;
  std::vector<SequenceStatus> statuses;
  std::vector<StepReport> steps;
  std::vector<HazardQuery> queries;
  // What happened, in order: "frame N", "map N" (the map holding pair N), "motion".
  std::vector<std::string> events;
  // The monitor maps a pair this many ticks after it came (0: at once, with the frame).
  int map_delay_ticks = 0;
  bool refuse_ahead = false;  // the monitor refuses every step chosen on an earlier map
  int motion_ticks = 1;        // a motion ends this many ticks after it was commanded
  double caution_goodness = 0.0;  // the caution level each map gives (0: none)
  // Called as each motion is commanded (the pose already at its end): may change `grid`.
  std::function<void(MapWorld&, const MobilityCommand&)> on_motion;
  int64_t utime = 1'000'000;
  double wall = 100.0;

  explicit MapWorld(SequenceExecutor& ex) : ex_(ex) {}

  void Run(int max_iterations = 20000) {
    for (int i = 0; i < max_iterations; ++i) {
      utime += 100'000;
      wall += 0.1;
      std::deque<std::function<void()>> now;
      now.swap(pending_);
      for (auto& f : now) f();
      for (const char* name : {"rover_sim", "state_estimator", "hazard_monitor", "camera_capture", "visual_odometry"})
        ex_.OnHeartbeat(name, wall);
      PoseEstimate p;
      p.utime = utime;
      p.position = Eigen::Vector3d(pose.x, pose.y, 0);
      p.orientation = Eigen::Quaterniond(rover::geometry::RotationFromRpy(0, 0, pose.yaw));
      ex_.OnPose(p);
      HazardStatus h;
      h.utime = utime;
      h.state = HazardState::kSafe;
      ex_.OnHazardStatus(h);
      ex_.Tick(utime, wall);
      for (auto& o : ex_.TakeOutputs()) std::visit([this](auto& v) { Handle(v); }, o);
      const SequenceState s = ex_.state();
      if (s == SequenceState::kCompleted || s == SequenceState::kAborted || s == SequenceState::kRejected) return;
    }
  }

  SequenceStatus Final() const { return statuses.back(); }

 private:
  Grid Seen() const {
    if (sees) return revealed_;
    if (map_known) return grid;
    return Grid::Filled(grid.origin_x, grid.origin_y, grid.cell_m, grid.rows, grid.cols, CellClass::kUnknown, 0.0f);
  }

  void Handle(const MobilityCommand& c) {
    if (c.type == MobilityCommand::Type::kStop) return;
    motions.push_back(c);
    events.push_back("motion");
    PlannedStep s;
    if (c.type == MobilityCommand::Type::kTurn) {
      s.kind = PlannedStep::Kind::kTurn;
      s.turn_rad = c.turn_rad;
    } else {
      s.distance_m = c.distance_m;
      s.curvature_per_m = c.curvature_per_m;
    }
    pose = EndOfStep(pose, s);
    trail.push_back(pose);
    utime += 10'000'000;
    if (on_motion) on_motion(*this, c);
    Later(motion_ticks, [this, c] { ex_.OnMobilityStatus({utime, c.command_id, MobilityState::kDone, 0, 0, ""}); });
  }
  void Handle(const CaptureRequest& c) {
    captures.push_back(c);
    if (!camera || (c.purpose == "look" && !answers_looks)) return;
    map_known = true;  // the pair shows the ground
    if (sees) Reveal(c);
    pending_.push_back([this, c] {
      ex_.OnStereoFrame(c.frame_id);
      events.push_back("frame " + std::to_string(c.frame_id));
      Later(map_delay_ticks, [this, c] {
        TraversabilityMap m;
        m.utime = utime;
        m.last_frame_id = c.frame_id;
        m.grid = delivered_ = Seen();
        m.caution_goodness = caution_goodness;
        events.push_back("map " + std::to_string(c.frame_id));
        ex_.OnTraversabilityMap(m);
      });
    });
  }
  // f runs `ticks` ticks from now (0: now).
  void Later(int ticks, std::function<void()> f) {
    if (ticks <= 0) {
      f();
      return;
    }
    pending_.push_back([this, ticks, f] { Later(ticks - 1, f); });
  }
  void Handle(const HazardQuery& q) {
    std::vector<rover::avoidance::Pose2> path;
    for (const auto& s : q.samples) path.push_back({s.x, s.y, s.yaw});
    // A step chosen ahead is judged on the map the monitor holds (the last one sent).
    const auto sw = rover::avoidance::SweepFootprint(q.map_frame_id > 0 ? delivered_ : Seen(), {}, path, path.front(), 0.5);
    queries.push_back(q);
    HazardReply r;
    r.query_id = q.query_id;
    r.verdict = HazardVerdict::kSafe;
    if (refuse_ahead && q.map_frame_id > 0) {
      r.verdict = HazardVerdict::kUnknown;
      r.zone_name = "hazard_map";
      r.detail = "hazard_map: unknown on the map in hand";
    } else if (sw.unsafe > 0) {
      r.verdict = HazardVerdict::kUnsafe;
      r.zone_name = "hazard_map";
      r.detail = "hazard_map: step " + std::to_string(sw.worst_step_m).substr(0, 4) + " m";
    } else if (sw.UnknownFraction() > 0.2) {
      r.verdict = HazardVerdict::kUnknown;
      r.zone_name = "hazard_map";
      r.detail = "hazard_map: unknown";
    }
    pending_.push_back([this, r] { ex_.OnHazardReply(r); });
  }
  void Handle(const SequenceStatus& s) { statuses.push_back(s); }
  void Handle(const StepReport& r) { steps.push_back(r); }
  template <class T>
  void Handle(const T&) {}

  void Reveal(const CaptureRequest& c) {
    if (revealed_.state.size() != grid.state.size())
      revealed_ = Grid::Filled(grid.origin_x, grid.origin_y, grid.cell_m, grid.rows, grid.cols, CellClass::kUnknown,
                               0.0f);
    for (int i = 0; i < grid.rows; ++i)
      for (int j = 0; j < grid.cols; ++j) {
        if (!sees(c, pose, grid.CellCentreX(i), grid.CellCentreY(j))) continue;
        const std::size_t k = static_cast<std::size_t>(i) * grid.cols + j;
        revealed_.state[k] = grid.state[k];
        revealed_.goodness[k] = grid.goodness[k];
        revealed_.step_m[k] = grid.step_m[k];
      }
  }

  SequenceExecutor& ex_;
  std::deque<std::function<void()>> pending_;
  Grid revealed_;
  Grid delivered_;  // the last map sent
};

ExecutorOptions Fast() {
  ExecutorOptions o;
  o.hazard_reply_wait_s = 1.0;
  o.hazard_status_wait_s = 1.0;
  o.pose_wait_s = 1.0;
  o.start_wait_s = 1.0;
  o.heartbeat_timeout_s = 1.0;
  o.map_wait_s = 1.0;
  o.capture_wait_s = 1.0;
  return o;
}

// A rock 2.5 m ahead on the line to the goal.
void Rock(Grid* g) { g->Paint(2.5, 0.0, 0.45, CellClass::kUnsafe, 0.0f, 0.4f); }

TEST(AvoidStep, GotoWithAvoidanceGoesRoundTheRock) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  Rock(&w.grid);
  ex.SubmitText("goto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().abort_reason << ": " << w.Final().detail;
  EXPECT_LT(std::hypot(w.pose.x - 5.0, w.pose.y), 0.4);
  // A pair was taken before the first step (image, map, then drive), and some step turned.
  ASSERT_FALSE(w.captures.empty());
  ASSERT_FALSE(w.motions.empty());
  bool steered = false;
  for (const auto& m : w.motions) steered = steered || std::abs(m.curvature_per_m) > 1e-6 || std::abs(m.turn_rad) > 1e-6;
  EXPECT_TRUE(steered);
}

// Each step report says how its step was chosen: with the rock ahead by the arc vote, and
// once the goal is in reach with the way clear, straight at it; without avoidance, by the
// command (what ./rover plot colours from).
TEST(AvoidStep, StepReportsSayHowEachStepWasChosen) {
  {
    SequenceExecutor ex(Fast());
    MapWorld w(ex);
    Rock(&w.grid);
    ex.SubmitText("goto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
    w.Run();
    ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
    ASSERT_GE(w.steps.size(), 2u);
    EXPECT_EQ(w.steps.front().choice, StepChoice::kArcVote) << "the rock is ahead: the first step is voted";
    EXPECT_EQ(w.steps.back().choice, StepChoice::kSteerAtGoal) << "the goal in reach, the way clear";
    for (const auto& s : w.steps) EXPECT_NE(s.choice, StepChoice::kCommand) << "step " << s.step_index;
  }
  {
    SequenceExecutor ex(Fast());
    MapWorld w(ex);
    ex.SubmitText("goto 3 m 0 m within 0.4 m avoid off\ndrive 1 m\n", 1, "t.seq");
    w.Run();
    ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
    ASSERT_GE(w.steps.size(), 2u);
    for (const auto& s : w.steps) EXPECT_EQ(s.choice, StepChoice::kCommand) << "step " << s.step_index;
  }
}

// executor.avoid_good_enough 0 takes the cap from each map's caution level: a safe cobble
// (goodness 0.5) 2.6 m ahead on the line to the goal is driven over as the map's level 0.4
// makes it rank with open ground, and is steered round where every difference counts (1)
// or where the map gives no level.
TEST(AvoidStep, GoodEnoughZeroTakesTheMapsCautionLevel) {
  auto first_heading_change = [](double good_enough, double map_level) {
    ExecutorOptions o = Fast();
    o.avoid_good_enough = good_enough;
    SequenceExecutor ex(o);
    MapWorld w(ex);
    w.caution_goodness = map_level;
    w.grid.Paint(2.6, 0.0, 0.25, CellClass::kSafe, 0.5f, 0.05f);
    ex.SubmitText("goto 6 m 0 m within 0.4 m distance 14 m avoid on\n", 1, "t.seq");
    w.Run();
    EXPECT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().abort_reason << ": " << w.Final().detail;
    EXPECT_FALSE(w.motions.empty());
    if (w.motions.empty()) return 99.0;
    const MobilityCommand& m = w.motions.front();
    return m.type == MobilityCommand::Type::kTurn ? m.turn_rad : m.curvature_per_m * m.distance_m;
  };
  EXPECT_DOUBLE_EQ(first_heading_change(0.0, 0.4), 0.0) << "the map's level: safe ground ranks alike";
  EXPECT_DOUBLE_EQ(first_heading_change(0.4, 0.0), 0.0) << "the same level, set in the options";
  EXPECT_GT(std::abs(first_heading_change(1.0, 0.4)), 1e-3) << "every difference counts";
  EXPECT_GT(std::abs(first_heading_change(0.0, 0.0)), 1e-3) << "no level from the map: off";
}

TEST(AvoidStep, WithoutAvoidanceTheMapStopsTheRover) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  Rock(&w.grid);
  ex.SubmitText("goto 5 m 0 m within 0.4 m avoid off\n", 1, "t.seq");
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kAborted);
  EXPECT_EQ(w.Final().abort_reason, "hazard_map");
  EXPECT_NE(w.Final().detail.find("hazard_map: step 0.4"), std::string::npos) << w.Final().detail;
  EXPECT_LT(w.pose.x, 2.5 - 0.45 - 0.8);  // the body never reached the rock
}

TEST(AvoidStep, UnknownMapTakesAPairFirstThenDrives) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  w.map_known = false;
  ex.SubmitText("drive 1.2 m\n", 1, "t.seq");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  ASSERT_FALSE(w.captures.empty());
  EXPECT_EQ(w.captures.front().purpose, "science");
  EXPECT_NEAR(w.pose.x, 1.2, 1e-6);
}

TEST(AvoidStep, UnknownMapWithoutACameraCannotDecide) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  w.map_known = false;
  w.camera = false;
  ex.SubmitText("drive 1.2 m\n", 1, "t.seq");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "hazard_unknown") << w.Final().detail;
  EXPECT_TRUE(w.motions.empty());
}

TEST(AvoidStep, BoxedInAbortsWithTheHazard) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  for (int i = 0; i < w.grid.rows; ++i)
    for (int j = 0; j < w.grid.cols; ++j) {
      const double x = w.grid.CellCentreX(i), y = w.grid.CellCentreY(j);
      if (std::abs(x) < 1.0 && std::abs(y) < 0.9) continue;
      const std::size_t k = static_cast<std::size_t>(i) * w.grid.cols + j;
      w.grid.state[k] = CellClass::kUnsafe;
      w.grid.goodness[k] = 0.0f;
      w.grid.step_m[k] = 0.5f;
    }
  ex.SubmitText("goto 5 m 0 m within 0.4 m avoid on\n", 1, "t.seq");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "hazard_map") << w.Final().detail;
  EXPECT_NE(w.Final().detail.find("no safe step"), std::string::npos) << w.Final().detail;
  EXPECT_TRUE(w.motions.empty());
}

// A keep-out zone on the line to the goal is an obstacle to the vote and the plan: the rover
// goes round it (the fake monitor here checks only the map, so nothing else would stop it).
TEST(AvoidStep, KeepOutZoneOnTheWayIsGoneRound) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  ex.SubmitText("keepout z circle 2.5 m 0 m radius 0.5 m\ngoto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().abort_reason << ": " << w.Final().detail;
  const auto zone = rover::hazards::KeepOutZone::Circle("z", 2.5, 0.0, 0.5);
  rover::hazards::Footprint body;
  body.width_m = 1.4;
  double closest = 1e9;
  for (const PlanePose& p : w.trail) closest = std::min(closest, rover::hazards::Clearance(zone, body, p.x, p.y, p.yaw));
  EXPECT_GT(closest, 0.0);
  ASSERT_FALSE(w.trail.empty());
}

// The goal inside a closed ring of rocks: the plan finds no way on 3 steps running and the
// goto aborts goal_unreachable, saying why, rather than wandering.
TEST(AvoidStep, GoalInsideARingOfRocksIsReportedUnreachable) {
  SequenceExecutor ex(Fast());
  MapWorld w(ex);
  for (int i = 0; i < w.grid.rows; ++i)
    for (int j = 0; j < w.grid.cols; ++j) {
      const double r = std::hypot(w.grid.CellCentreX(i) - 4.0, w.grid.CellCentreY(j));
      if (r < 1.2 || r > 1.8) continue;
      const std::size_t k = static_cast<std::size_t>(i) * w.grid.cols + j;
      w.grid.state[k] = CellClass::kUnsafe;
      w.grid.goodness[k] = 0.0f;
      w.grid.step_m[k] = 0.5f;
    }
  ex.SubmitText("goto 4 m 0 m within 0.3 m distance 12 m avoid on\n", 1, "t.seq");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "goal_unreachable") << w.Final().detail;
  EXPECT_NE(w.Final().detail.find("goal unreachable on 3 plans in a row: no way from"), std::string::npos)
      << w.Final().detail;
  EXPECT_LE(w.motions.size(), 2u);
}

// Squeezing through (avoid_squeeze_margin_m): the goal inside a ring of rocks whose one
// gap, 2.2 m between its rock cells' centres, passes the rover's body (1.4 m wide; the plan
// keeps its centre 0.8 m off rock cells, half a cell included) but not the body with the
// vote's margins (0.35 m here: 1.15 m). Without squeezing the goto aborts goal_unreachable;
// with it the plan and the vote narrow the margin while no way keeps it, and the rover
// drives through the gap, no rock cell ever under its body.
namespace {
// Rock cells (0.5 m steps) wherever `rock(x, y)` holds of a cell's centre.
void RocksWhere(Grid* g, const std::function<bool(double, double)>& rock) {
  for (int i = 0; i < g->rows; ++i)
    for (int j = 0; j < g->cols; ++j) {
      if (!rock(g->CellCentreX(i), g->CellCentreY(j))) continue;
      const std::size_t k = static_cast<std::size_t>(i) * g->cols + j;
      g->state[k] = CellClass::kUnsafe, g->goodness[k] = 0.0f, g->step_m[k] = 0.5f;
    }
}

// Rocks round the goal (4, 0), 2.0 to 2.6 m from it, but for a gap toward the start: no
// rock cell whose centre lies within `gap_half_width_m` of the x axis on the start's side.
void RingWithAGap(Grid* g, double gap_half_width_m) {
  RocksWhere(g, [gap_half_width_m](double x, double y) {
    const double r = std::hypot(x - 4.0, y);
    return r >= 2.0 && r <= 2.6 && !(x < 4.0 && std::abs(y) < gap_half_width_m);
  });
}

struct SqueezeRun {
  SequenceStatus final;
  std::vector<PlanePose> trail;
  bool said = false;
  Grid grid;
};

// One goto with the vote's margin at 0.35 m and the squeeze's at `squeeze_margin_m`.
SqueezeRun Squeeze(double squeeze_margin_m, bool planner, const std::function<void(Grid*)>& rocks,
                   const std::string& goto_line, int iterations) {
  ExecutorOptions o = Fast();
  o.planner_enabled = planner;
  o.avoid_margin_m = 0.35;
  o.avoid_squeeze_margin_m = squeeze_margin_m;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  rocks(&w.grid);
  ex.SubmitText(goto_line + "\n", 1, "t.seq");
  w.Run(iterations);
  SqueezeRun run{w.Final(), w.trail, false, w.grid};
  for (const SequenceStatus& st : w.statuses) run.said = run.said || st.detail.find("squeezing through") != std::string::npos;
  return run;
}

SqueezeRun DriveIntoTheRing(double squeeze_margin_m) {
  return Squeeze(squeeze_margin_m, true, [](Grid* g) { RingWithAGap(g, 1.0); },
                 "goto 4 m 0 m within 0.3 m distance 20 m avoid on", 60000);
}

// The rock cells whose centres lie under the body (1.6 m by 1.4 m, centred) at any pose.
int RockCellsUnderTheBody(const SqueezeRun& run) {
  int under = 0;
  for (const PlanePose& p : run.trail)
    for (int i = 0; i < run.grid.rows; ++i)
      for (int j = 0; j < run.grid.cols; ++j) {
        if (run.grid.state[static_cast<std::size_t>(i) * run.grid.cols + j] != CellClass::kUnsafe) continue;
        const double dx = run.grid.CellCentreX(i) - p.x, dy = run.grid.CellCentreY(j) - p.y;
        const double along = std::cos(p.yaw) * dx + std::sin(p.yaw) * dy;
        const double across = -std::sin(p.yaw) * dx + std::cos(p.yaw) * dy;
        if (std::abs(along) <= 0.8 && std::abs(across) <= 0.7) ++under;
      }
  return under;
}
}  // namespace

TEST(AvoidStep, NoWayKeepsTheVotesMarginSoItSqueezesThroughWithTheBodyAlone) {
  const SqueezeRun off = DriveIntoTheRing(-1.0);
  EXPECT_EQ(off.final.abort_reason, "goal_unreachable") << off.final.detail;
  EXPECT_FALSE(off.said);
  const SqueezeRun on = DriveIntoTheRing(0.0);
  ASSERT_EQ(on.final.state, SequenceState::kCompleted) << on.final.abort_reason << ": " << on.final.detail;
  EXPECT_TRUE(on.said);
  ASSERT_FALSE(on.trail.empty());
  EXPECT_LT(std::hypot(on.trail.back().x - 4.0, on.trail.back().y), 0.3);
  EXPECT_EQ(RockCellsUnderTheBody(on), 0);
}

// Boxed in with the margin, free with the body alone: the rover starts in a corridor of
// rocks 0.9 m either side of its centre line, 6 m long (a rock cell under the body with the
// vote's 0.35 m margins, none without; the cells under it where it stands are excused). The
// plan is off, so the vote alone decides: every step with the margin is refused, and the
// goto aborts boxed in; squeezing, the vote takes steps with the body alone, and the rover
// drives out along the corridor to its goal, no rock cell ever under its body.
TEST(AvoidStep, BoxedInByTheVotesMarginItSqueezesOutWithTheBodyAlone) {
  const auto corridor = [](Grid* g) {
    RocksWhere(g, [](double x, double y) { return x >= -3.0 && x <= 3.0 && std::abs(std::abs(y) - 0.9) < 0.05; });
  };
  const std::string line = "goto 5 m 0 m within 0.4 m distance 12 m avoid on";
  const SqueezeRun off = Squeeze(-1.0, false, corridor, line, 20000);
  EXPECT_EQ(off.final.abort_reason, "hazard_map") << off.final.detail;
  EXPECT_FALSE(off.said);
  const SqueezeRun on = Squeeze(0.0, false, corridor, line, 20000);
  ASSERT_EQ(on.final.state, SequenceState::kCompleted) << on.final.abort_reason << ": " << on.final.detail;
  EXPECT_TRUE(on.said);
  EXPECT_EQ(RockCellsUnderTheBody(on), 0);
}

// A corridor narrower than the body (rock cells 0.7 m either side of its centre line) keeps
// the rover boxed in when squeezing: the abort says the narrower margin was tried too.
TEST(AvoidStep, BoxedInByTheBodyItselfTheAbortSaysTheSqueezeWasTried) {
  const SqueezeRun run = Squeeze(
      0.0, false,
      [](Grid* g) {
        RocksWhere(g, [](double x, double y) { return x >= -3.0 && x <= 3.0 && std::abs(std::abs(y) - 0.7) < 0.05; });
      },
      "goto 5 m 0 m within 0.4 m distance 12 m avoid on", 20000);
  EXPECT_EQ(run.final.abort_reason, "hazard_map") << run.final.detail;
  EXPECT_NE(run.final.detail.find("nor with the vote's margin narrowed to 0.00 m"), std::string::npos)
      << run.final.detail;
  EXPECT_FALSE(run.said);
}

// A gap narrower than the body itself stays shut when squeezing: the abort says the
// narrower margin was tried too.
TEST(AvoidStep, SqueezingNeverOpensAGapNarrowerThanTheBody) {
  const SqueezeRun run = Squeeze(0.0, true, [](Grid* g) { RingWithAGap(g, 0.6); },
                                 "goto 4 m 0 m within 0.3 m distance 20 m avoid on", 60000);
  EXPECT_EQ(run.final.abort_reason, "goal_unreachable") << run.final.detail;
  EXPECT_NE(run.final.detail.find("nor with the vote's margin narrowed to 0.00 m"), std::string::npos)
      << run.final.detail;
  EXPECT_EQ(RockCellsUnderTheBody(run), 0);
}

// A corridor of rocks whose far end the map never sees (unknown ground, as beside a rock no
// camera looks past), the goal beyond it. The plan leads through the unknown end (unknown
// ground is a way, at 1.25 per metre); the strict vote refuses to drive onto it. Without
// memory of the refusal the plan keeps leading the rover at the end, and it backs, turns
// and is led on again until something stops it (here the map: wedged by the corridor's
// wall, no safe step). With it (planner_refusal_cost), the plan's way through the end grows
// costly where the vote refused it (two backups and one return to where it stood), and
// the rover turns, drives out and goes round.
namespace {
void Corridor(Grid* g) {
  for (int i = 0; i < g->rows; ++i)
    for (int j = 0; j < g->cols; ++j) {
      const double x = g->CellCentreX(i), y = g->CellCentreY(j);
      const std::size_t k = static_cast<std::size_t>(i) * g->cols + j;
      if (x >= -1.0 && x <= 4.2 && std::abs(y) >= 1.5 && std::abs(y) <= 1.9) {
        g->state[k] = CellClass::kUnsafe, g->goodness[k] = 0.0f, g->step_m[k] = 0.5f;
      } else if (x >= 2.6 && x <= 4.2 && std::abs(y) < 1.5) {
        g->state[k] = CellClass::kUnknown, g->goodness[k] = 0.0f;
      }
    }
}

struct CorridorRun {
  SequenceStatus final;
  std::vector<PlanePose> trail;
  std::vector<std::string> details;
};

CorridorRun DriveTheCorridor(double refusal_cost) {
  ExecutorOptions o = Fast();
  o.avoid_unseen_ground_strict = true;
  o.planner_refusal_cost = refusal_cost;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  Corridor(&w.grid);
  ex.SubmitText("goto 6 m 0 m within 0.4 m distance 40 m avoid on\n", 1, "t.seq");
  w.Run(60000);
  CorridorRun r{w.Final(), w.trail, {}};
  for (const SequenceStatus& s : w.statuses) r.details.push_back(s.detail);
  return r;
}
}  // namespace

TEST(AvoidStep, AWayTheVoteRefusesCostsThePlannerAndTheRoverGoesRound) {
  const CorridorRun with = DriveTheCorridor(10.0);
  ASSERT_EQ(with.final.state, SequenceState::kCompleted) << with.final.abort_reason << ": " << with.final.detail;
  bool said = false;
  for (const std::string& d : with.details) said = said || d.find("costs the planner more") != std::string::npos;
  EXPECT_TRUE(said);
  // Round the corridor's wall, never through its unknown end.
  double widest = 0.0;
  for (const PlanePose& p : with.trail) {
    widest = std::max(widest, std::abs(p.y));
    EXPECT_FALSE(p.x > 2.6 && p.x < 4.2 && std::abs(p.y) < 1.5) << p.x << "," << p.y;
  }
  EXPECT_GT(widest, 1.9);
  const CorridorRun without = DriveTheCorridor(0.0);
  EXPECT_NE(without.final.state, SequenceState::kCompleted) << without.final.detail;
}


// The plan's clearance as the vote sees it (planner_vote_clearance): a wall of rocks across
// the way with a gap the rover's body (1.4 m, 1.5 m with the vote's margins here) cannot
// pass, its rock cells' centres 1.6 m apart (0.8 m either side of the rover's centre
// cell). The planner measures from cell centres; the vote counts a cell under the body
// when its centre lies within half a cell of it. Planning with half the body's width alone, the plan leads through the gap, and the vote refuses
// the way at its mouth: the rover backs out before the refusal, remembered, prices the gap
// out (in a field of rocks, a refusal's cost is often not enough: keepout_avoid's variants
// dithered at such a mouth for 37 steps). With the vote's clearance the plan goes round the
// wall's end at once.
namespace {
struct GapRun {
  SequenceStatus final;
  std::vector<PlanePose> trail;
  std::size_t backups = 0;
};

// The goto of the wall tests, 5 m ahead beyond the wall, on `w`'s grid.
GapRun GotoPastTheWall(SequenceExecutor& ex, MapWorld& w) {
  ex.SubmitText("goto 5 m 0 m within 0.4 m distance 40 m avoid on\n", 1, "t.seq");
  w.Run(60000);
  GapRun r{w.Final(), w.trail, 0};
  for (const auto& m : w.motions)
    if (m.type == MobilityCommand::Type::kArc && m.distance_m < 0.0) ++r.backups;
  return r;
}

GapRun DriveAtTheGap(bool vote_clearance) {
  ExecutorOptions o = Fast();
  o.planner_vote_clearance = vote_clearance;
  o.avoid_margin_m = 0.05;  // the planner's half-width 0.75 m, 0.85 m with the half cell
  SequenceExecutor ex(o);
  MapWorld w(ex);
  w.grid = Grid::Filled(-4, -8, 0.2, 60, 80, CellClass::kSafe, 0.9f);
  for (int i = 0; i < w.grid.rows; ++i)
    for (int j = 0; j < w.grid.cols; ++j) {
      const double x = w.grid.CellCentreX(i), y = w.grid.CellCentreY(j);
      if (x < 2.4 || x > 2.8 || std::abs(y - 0.1) < 0.75 || std::abs(y) > 4.5) continue;
      const std::size_t k = static_cast<std::size_t>(i) * w.grid.cols + j;
      w.grid.state[k] = CellClass::kUnsafe, w.grid.goodness[k] = 0.0f, w.grid.step_m[k] = 0.5f;
    }
  return GotoPastTheWall(ex, w);
}

// The trail's farthest reach to either side of the line to the goal (y = 0).
double Widest(const std::vector<PlanePose>& trail) {
  double widest = 0.0;
  for (const PlanePose& p : trail) widest = std::max(widest, std::abs(p.y));
  return widest;
}

// The trail's nearest approach to (x, y).
double NearestTo(const std::vector<PlanePose>& trail, double x, double y) {
  double d = 1e9;
  for (const PlanePose& p : trail) d = std::min(d, std::hypot(p.x - x, p.y - y));
  return d;
}
}  // namespace

TEST(AvoidStep, ThePlanLeavesTheVotesClearanceAndNeverLeadsIntoAGapTooNarrow) {
  const GapRun with = DriveAtTheGap(true);
  ASSERT_EQ(with.final.state, SequenceState::kCompleted) << with.final.abort_reason << ": " << with.final.detail;
  EXPECT_EQ(with.backups, 0u);
  EXPECT_GT(Widest(with.trail), 4.5);  // round the wall's end
  // Without it the plan leads the rover to the gap's mouth, where it can only back up.
  const GapRun without = DriveAtTheGap(false);
  EXPECT_GT(without.backups, 0u) << without.final.detail;
  EXPECT_LT(NearestTo(without.trail, 2.4, 0.1), NearestTo(with.trail, 2.4, 0.1) - 0.2);
}

// The top rule in the plan (avoid_top_rise_in_plan): the same wall, its gap 2.6 m wide, and
// in the gap's middle a rock the map reads low (caution, steps 0.20 m) while its tops stand
// 0.32 m over the ground. The vote's top rule (avoid_top_rise_m 0.25) makes it unsafe, and
// the body cannot pass beside it. Counted in the site map as well, the plan goes round the
// wall's end at once; counted by the vote alone, the plan leads into the gap, where the
// vote refuses it.
namespace {
GapRun DriveAtTheLowReadRock(bool in_plan) {
  ExecutorOptions o = Fast();
  o.avoid_top_rise_m = 0.25;
  o.avoid_top_rise_in_plan = in_plan;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  w.grid = Grid::Filled(-4, -8, 0.2, 60, 80, CellClass::kSafe, 0.9f);
  w.grid.SetHeights(0.0f, 0.01f);
  for (int i = 0; i < w.grid.rows; ++i)
    for (int j = 0; j < w.grid.cols; ++j) {
      const double x = w.grid.CellCentreX(i), y = w.grid.CellCentreY(j);
      const std::size_t k = static_cast<std::size_t>(i) * w.grid.cols + j;
      if (std::hypot(x - 2.6, y - 0.1) < 0.35) {
        w.grid.state[k] = CellClass::kCaution, w.grid.goodness[k] = 0.2f, w.grid.step_m[k] = 0.2f;
        w.grid.elevation_m[k] = 0.32f;
      } else if (x >= 2.4 && x <= 2.8 && std::abs(y - 0.1) >= 1.3 && std::abs(y) <= 4.5) {
        w.grid.state[k] = CellClass::kUnsafe, w.grid.goodness[k] = 0.0f, w.grid.step_m[k] = 0.5f;
        w.grid.elevation_m[k] = 0.5f;
      }
    }
  return GotoPastTheWall(ex, w);
}
}  // namespace

TEST(AvoidStep, WithTheTopRuleInThePlanItGoesRoundARockTheMapReadsLow) {
  const GapRun with = DriveAtTheLowReadRock(true);
  ASSERT_EQ(with.final.state, SequenceState::kCompleted) << with.final.abort_reason << ": " << with.final.detail;
  EXPECT_EQ(with.backups, 0u);
  EXPECT_GT(Widest(with.trail), 4.5);  // round the wall's end
  const GapRun without = DriveAtTheLowReadRock(false);
  EXPECT_LT(NearestTo(without.trail, 2.4, 0.1), NearestTo(with.trail, 2.4, 0.1) - 0.2) << without.final.detail;
}

// Looking aside (avoidance/look_aside.hpp): a wall across the way ahead, the goal to the
// right, and the ground beside the rover never framed, since the mast looks ahead (the way
// it came, behind, is known). Every ground that could hide a rock is refused (strict), so
// the first vote has nothing on but backing up. With looks the mast is pointed at the side
// first, the map gains it, and the rover turns right in place and drives to the goal;
// without them it backs and fills, uncovering the sides by moving, refusals and all.
struct LookRun {
  SequenceStatus final;
  std::vector<CaptureRequest> captures;
  std::size_t motions = 0, backups = 0;
};

// A goto with looks (pan look_pan_deg; 0: none) on the rocks `rocks` paints, every ground
// that could hide a rock refused (strict). What each pair shows, in the rover frame at the
// capture: 45 deg either side of the mast's pointing, from 0.5 m to 6 m (the body itself is
// known to the vote as the ground it stands on), and with `behind_known` the ground behind,
// the way the rover came.
LookRun RunWithLooks(double look_pan_deg, bool answers_looks, bool behind_known,
                     const std::function<void(Grid*)>& rocks, const std::string& goto_line) {
  ExecutorOptions o = Fast();
  o.avoid_unseen_ground_strict = true;
  o.avoid_start_ring_known = false;
  o.avoid_look_pan_deg = look_pan_deg;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  w.answers_looks = answers_looks;
  rocks(&w.grid);
  w.sees = [behind_known](const CaptureRequest& c, const PlanePose& at, double x, double y) {
    const double dx = x - at.x, dy = y - at.y, r = std::hypot(dx, dy);
    const double bearing = std::remainder(std::atan2(dy, dx) - at.yaw, 2 * M_PI);  // + right
    const bool behind = behind_known && std::abs(bearing) > 2.0;
    return r > 0.5 && r < 6.0 && (std::abs(std::remainder(bearing - c.pan_rad, 2 * M_PI)) < M_PI / 4 || behind);
  };
  ex.SubmitText(goto_line + "\n", 1, "t.seq");
  w.Run();
  LookRun run{w.Final(), w.captures, w.motions.size(), 0};
  for (const auto& m : w.motions)
    if (m.type == MobilityCommand::Type::kArc && m.distance_m < 0.0) ++run.backups;
  return run;
}

LookRun DriveBesideAWall(double look_pan_deg, bool answers_looks = true) {
  const auto wall = [](Grid* g) {
    for (double y = -3.0; y <= 1.2; y += 0.1) g->Paint(1.6, y, 0.2, CellClass::kUnsafe, 0.0f, 0.5f);
  };
  return RunWithLooks(look_pan_deg, answers_looks, /*behind_known=*/true, wall, "goto 0 m 3 m within 0.5 m avoid on");
}

TEST(AvoidStep, LooksAsideAtUnframedGroundATurnWouldSweepInsteadOfBackingUp) {
  const LookRun without = DriveBesideAWall(0.0);
  EXPECT_EQ(without.final.state, SequenceState::kCompleted) << without.final.detail;
  EXPECT_GE(without.backups, 1u) << "the world does not test looking: nothing but backing up was on";
  for (const auto& c : without.captures) EXPECT_NE(c.purpose, "look");

  const LookRun with = DriveBesideAWall(70.0);
  EXPECT_EQ(with.final.state, SequenceState::kCompleted) << with.final.detail;
  EXPECT_EQ(with.backups, 0u) << "backed up though it looked";
  EXPECT_NE(with.final.detail.find("looks aside"), std::string::npos) << with.final.detail;
  EXPECT_LT(with.motions, without.motions);
  int left = 0, right = 0;
  for (const auto& c : with.captures) {
    if (c.purpose != "look") continue;
    EXPECT_NEAR(std::abs(c.pan_rad), 70.0 * M_PI / 180.0, 1e-9);
    EXPECT_NEAR(c.tilt_rad, 15.0 * M_PI / 180.0, 1e-9);
    ++(c.pan_rad > 0 ? right : left);
  }
  EXPECT_EQ(right, 1) << "one look toward the goal's side";
  EXPECT_LE(left, 1) << "a side is looked at once per pose";
  for (const auto& c : with.captures)
    if (c.purpose == "look") {
      EXPECT_GT(c.pan_rad, 0.0) << "the side with more unknown ground, the goal's, first";
      break;
    }
}

// Looking behind: the rover stands in a pocket of rocks (ahead and both sides), so no arc or
// turn is on, and the ground behind it was never framed, so a back-up is refused too. With
// looks it looks at each side (rocks), then behind (pan 180: clear), backs out and goes to a
// goal behind it; without them it is boxed in at once.
LookRun BackOutOfAPocket(double look_pan_deg) {
  const auto pocket = [](Grid* g) {
    for (double y = -1.3; y <= 1.3; y += 0.1) g->Paint(1.6, y, 0.2, CellClass::kUnsafe, 0.0f, 0.5f);
    for (double x = -0.6; x <= 1.6; x += 0.1) {
      g->Paint(x, -1.3, 0.2, CellClass::kUnsafe, 0.0f, 0.5f);
      g->Paint(x, 1.3, 0.2, CellClass::kUnsafe, 0.0f, 0.5f);
    }
  };
  return RunWithLooks(look_pan_deg, /*answers_looks=*/true, /*behind_known=*/false, pocket,
                      "goto -3 m 0 m within 0.5 m avoid on");
}

TEST(AvoidStep, LooksBehindWhenEvenBackingUpIsRefusedAndBacksOut) {
  const LookRun without = BackOutOfAPocket(0.0);
  EXPECT_EQ(without.final.abort_reason, "hazard_map") << without.final.detail;
  EXPECT_EQ(without.motions, 0u);

  const LookRun with = BackOutOfAPocket(70.0);
  EXPECT_EQ(with.final.state, SequenceState::kCompleted) << with.final.detail;
  EXPECT_GE(with.backups, 1u);
  bool behind = false;
  for (const auto& c : with.captures)
    if (c.purpose == "look" && std::abs(std::abs(c.pan_rad) - M_PI) < 1e-9) behind = true;
  EXPECT_TRUE(behind) << "no look behind";
}

// A camera that cannot point never answers a look: the executor waits capture_wait_s once,
// asks no more in this sequence, and drives on the map it has, as without looks.
TEST(AvoidStep, ACameraThatCannotPointIsAskedOnce) {
  const LookRun without = DriveBesideAWall(0.0);
  const LookRun refused = DriveBesideAWall(70.0, /*answers_looks=*/false);
  EXPECT_EQ(refused.final.state, SequenceState::kCompleted) << refused.final.detail;
  int looks = 0;
  for (const auto& c : refused.captures) looks += c.purpose == "look";
  EXPECT_EQ(looks, 1);
  EXPECT_EQ(refused.motions, without.motions);
}

// Thinking while driving (think_ahead.cpp): the monitor maps each pair for a while after it
// came. Where the map in hand (the pair before's) already knows the next step's ground
// safe, the step is chosen on it and driven while the new pair is mapped; the query says
// which map it was chosen on.
struct AheadRun {
  SequenceStatus final;
  std::vector<MobilityCommand> motions;
  std::vector<StepReport> steps;
  std::vector<HazardQuery> queries;
  std::vector<std::string> events;
  PlanePose pose;
};

AheadRun ThinkAheadRun(bool think, bool rock, bool refuse_ahead = false) {
  ExecutorOptions o = Fast();
  o.think_while_driving = think;
  o.map_wait_s = 5.0;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  if (rock) Rock(&w.grid);
  w.map_delay_ticks = 15;  // 1.5 s
  w.refuse_ahead = refuse_ahead;
  ex.SubmitText("goto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
  w.Run();
  return {w.Final(), w.motions, w.steps, w.queries, w.events, w.pose};
}

// The index in `events` of the motion commanded after `frame`'s pair came, before its map:
// -1 when every motion after that pair waited for its map.
int MotionBeforeMap(const std::vector<std::string>& events, int64_t frame) {
  const auto at = std::find(events.begin(), events.end(), "frame " + std::to_string(frame));
  for (auto it = at; it != events.end(); ++it) {
    if (*it == "map " + std::to_string(frame)) return -1;
    if (*it == "motion") return static_cast<int>(it - events.begin());
  }
  return -1;
}

TEST(AvoidStep, OnOpenGroundTheNextStepIsChosenAndDrivenWhileThePairIsMapped) {
  const AheadRun with = ThinkAheadRun(true, false);
  ASSERT_EQ(with.final.state, SequenceState::kCompleted) << with.final.detail;
  EXPECT_LT(std::hypot(with.pose.x - 5.0, with.pose.y), 0.4);
  ASSERT_GE(with.steps.size(), 4u);
  // The first step waits for the first map (there is no earlier one); the later ones, on
  // open ground, are chosen ahead, each on the map of the pair taken one step before.
  EXPECT_FALSE(with.steps.front().thought_ahead);
  int ahead = 0;
  for (const auto& s : with.steps) ahead += s.thought_ahead;
  EXPECT_GE(ahead, static_cast<int>(with.steps.size()) - 2) << with.final.detail;
  EXPECT_NE(with.final.detail.find(std::to_string(ahead) + " steps chosen while driving"), std::string::npos)
      << with.final.detail;
  int ahead_queries = 0;
  for (const auto& q : with.queries) {
    if (q.map_frame_id <= 0) continue;
    ++ahead_queries;
    // Chosen on a map the monitor had sent, and a motion followed before the newer map.
    EXPECT_NE(std::find(with.events.begin(), with.events.end(), "map " + std::to_string(q.map_frame_id)),
              with.events.end());
  }
  EXPECT_EQ(ahead_queries, ahead);
  int driven_while_mapping = 0;
  for (const auto& e : with.events)
    if (e.rfind("frame ", 0) == 0 && MotionBeforeMap(with.events, std::stoll(e.substr(6))) >= 0) ++driven_while_mapping;
  EXPECT_EQ(driven_while_mapping, ahead);

  // Off: every step waits for the map of the pair taken where it begins.
  const AheadRun without = ThinkAheadRun(false, false);
  ASSERT_EQ(without.final.state, SequenceState::kCompleted) << without.final.detail;
  for (const auto& s : without.steps) EXPECT_FALSE(s.thought_ahead);
  for (const auto& q : without.queries) EXPECT_LE(q.map_frame_id, 0);
  for (const auto& e : without.events) {
    if (e.rfind("frame ", 0) != 0) continue;
    EXPECT_EQ(MotionBeforeMap(without.events, std::stoll(e.substr(6))), -1) << e;
  }
}

// Near the rock the map in hand does not settle the step (a turn, a tight arc, ground not
// yet known safe): those steps wait for the new map. Only gentle forward arcs are ahead.
TEST(AvoidStep, NearAnObstacleTheRoverStopsToThink) {
  const AheadRun with = ThinkAheadRun(true, true);
  ASSERT_EQ(with.final.state, SequenceState::kCompleted) << with.final.detail;
  EXPECT_LT(std::hypot(with.pose.x - 5.0, with.pose.y), 0.4);
  int ahead = 0, waited = 0;
  for (std::size_t k = 0; k < with.steps.size(); ++k) {
    const StepReport& s = with.steps[k];
    if (!s.thought_ahead) {
      waited += k > 0;
      continue;
    }
    ++ahead;
    const auto m = std::find_if(with.motions.begin(), with.motions.end(),
                                [&](const MobilityCommand& c) { return c.command_id == s.mobility_command_id; });
    ASSERT_NE(m, with.motions.end()) << "step " << k;
    EXPECT_EQ(m->type, MobilityCommand::Type::kArc) << "step " << k;
    EXPECT_GT(m->distance_m, 0.0) << "step " << k;
    EXPECT_LT(std::abs(m->curvature_per_m), ExecutorOptions{}.avoid_look_curvature_per_m) << "step " << k;
  }
  EXPECT_GE(ahead, 1);
  EXPECT_GE(waited, 1) << "the rock made no step wait for its map";
}

// The monitor may refuse a step chosen on the map in hand: nothing aborts, and the step is
// chosen again on the new map exactly as without thinking ahead (the vote's history, the
// planner's refusals and blocks put back), so the drive is the same step for step.
TEST(AvoidStep, AStepChosenAheadThatTheMonitorRefusesIsChosenAgainOnTheNewMap) {
  const AheadRun refused = ThinkAheadRun(true, true, /*refuse_ahead=*/true);
  const AheadRun without = ThinkAheadRun(false, true);
  ASSERT_EQ(refused.final.state, SequenceState::kCompleted) << refused.final.detail;
  int asked_ahead = 0;
  for (const auto& q : refused.queries) asked_ahead += q.map_frame_id > 0;
  EXPECT_GE(asked_ahead, 1);
  for (const auto& s : refused.steps) EXPECT_FALSE(s.thought_ahead);
  ASSERT_EQ(refused.motions.size(), without.motions.size());
  for (std::size_t k = 0; k < refused.motions.size(); ++k) {
    EXPECT_EQ(refused.motions[k].type, without.motions[k].type) << k;
    EXPECT_DOUBLE_EQ(refused.motions[k].distance_m, without.motions[k].distance_m) << k;
    EXPECT_DOUBLE_EQ(refused.motions[k].curvature_per_m, without.motions[k].curvature_per_m) << k;
    EXPECT_DOUBLE_EQ(refused.motions[k].turn_rad, without.motions[k].turn_rad) << k;
  }
}

// A step chosen ahead is committed; but when the map of the pair taken where it began comes
// while it is driven and rates ground on its way unsafe (here a rock that pair shows and
// the map before did not), the rover stops, naming both maps.
TEST(AvoidStep, AStepChosenAheadStopsWhenTheNewerMapRatesItsWayUnsafe) {
  ExecutorOptions o = Fast();
  o.map_wait_s = 5.0;
  SequenceExecutor ex(o);
  MapWorld w(ex);
  w.map_delay_ticks = 15;
  w.motion_ticks = 30;  // the map comes while the step is driven
  int rocks = 0;
  w.on_motion = [&](MapWorld& world, const MobilityCommand& c) {
    // The first step chosen ahead: the query before it named the map it was chosen on.
    if (rocks > 0 || c.type != MobilityCommand::Type::kArc || world.queries.empty() ||
        world.queries.back().map_frame_id <= 0)
      return;
    // Under the front of the body at the step's end, beyond where it stood.
    const PlanePose end = world.pose;
    world.grid.Paint(end.x + 0.6 * std::cos(end.yaw), end.y + 0.6 * std::sin(end.yaw), 0.2, CellClass::kUnsafe, 0.0f,
                     0.4f);
    ++rocks;
  };
  ex.SubmitText("goto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
  w.Run();
  ASSERT_EQ(rocks, 1);
  EXPECT_EQ(w.Final().state, SequenceState::kAborted);
  EXPECT_EQ(w.Final().abort_reason, "hazard_map");
  EXPECT_NE(w.Final().detail.find("was driven, rates its way unsafe"), std::string::npos) << w.Final().detail;

  // Without the rock the same drive completes.
  SequenceExecutor ex2(o);
  MapWorld clear(ex2);
  clear.map_delay_ticks = 15;
  clear.motion_ticks = 30;
  ex2.SubmitText("goto 5 m 0 m within 0.4 m distance 12 m avoid on\n", 1, "t.seq");
  clear.Run();
  EXPECT_EQ(clear.Final().state, SequenceState::kCompleted) << clear.Final().detail;
}

}  // namespace
