// The executor against a fake world: a kinematic rover that moves as commanded (with a slip
// factor and a heading drift the test controls), an estimator that integrates the commanded
// motion and takes VO corrections, and VO, hazard and heartbeat sources that the test can
// silence or make fail. No bus.
#include "sequence/executor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <functional>
#include <numbers>
#include <set>

using namespace rover::sequence;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

class FakeWorld {
 public:
  // Knobs.
  double slip = 0.0;                 // fraction of commanded distance lost
  double drift_rad_per_m = 0.0;      // truth heading drift while driving
  double roll_rad = 0.0;             // terrain roll seen by IMU and estimator
  double pitch_rad = 0.0;            // terrain pitch (a slope along the heading)
  Eigen::Vector2d drift_per_m = Eigen::Vector2d::Zero();  // truth slides (site x, y) per metre
  int vo_fail_next = 0;              // the next n step pairs fail, then VO works again
  bool failed_pair_is_reference = true;  // VO keeps a failed pair as its reference (not if
                                         // the pair was unusable)
  double rover_radius_m = 0.5;       // footprint for keep-out checks
  enum class Vo { kOk, kFail, kSilent } vo = Vo::kOk;
  bool mobility_answers = true;
  bool mobility_faults = false;
  bool hazard_replies = true;
  bool hazard_unknown = false;
  bool hazard_monitor_knows_zones = true;  // status uses the zones it was sent
  bool nan_pose = false;                   // a broken estimator
  double position_sigma_m = 0.0;           // the estimate's horizontal 1-sigma (x and y)
  std::set<std::string> alive = {"rover_sim", "state_estimator", "hazard_monitor", "camera_capture",
                                 "visual_odometry"};

  // Truth and estimate (plane).
  PlanePose truth, estimate;
  int site_index = 0;
  int64_t last_vo_frame = -1;
  std::vector<KeepOutZone> zones;

  // Everything the executor said, in order.
  std::vector<ExecutorOutput> outputs;
  std::vector<MobilityCommand> motions;  // arcs and turns
  std::vector<MobilityCommand> stops;
  std::vector<CaptureRequest> captures;
  std::vector<HazardQuery> queries;
  std::vector<StepReport> steps;
  std::vector<SequenceStatus> statuses;
  std::vector<NewSiteRequest> sites;
  std::vector<KeepOutZoneSet> zone_sets;

  int64_t utime = 1'000'000;
  double wall = 100.0;

  // Called after each iteration; return false to stop early.
  std::function<void(SequenceExecutor&, int)> on_iteration;

  explicit FakeWorld(SequenceExecutor& ex) : ex_(ex) {}

  PoseEstimate Pose() const {
    PoseEstimate p;
    p.utime = utime;
    p.position = Eigen::Vector3d(estimate.x, estimate.y, 0);
    p.orientation = Eigen::Quaterniond(rover::geometry::RotationFromRpy(roll_rad, pitch_rad, estimate.yaw));
    p.site_index = site_index;
    p.last_vo_to_frame = last_vo_frame;
    p.covariance(0, 0) = p.covariance(1, 1) = position_sigma_m * position_sigma_m;
    if (nan_pose) p.position.x() = std::nan("");
    return p;
  }

  bool InZone(double x, double y, double margin_m = 0.0) const {
    for (const auto& z : zones) {
      if (z.shape == KeepOutZone::Shape::kCircle &&
          std::hypot(x - z.center.x(), y - z.center.y()) < z.radius_m + rover_radius_m + margin_m) {
        return true;
      }
    }
    return false;
  }

  HazardStatus Status() const {
    HazardStatus h;
    h.utime = utime;
    h.state = hazard_unknown ? HazardState::kUnknown : HazardState::kSafe;
    h.roll_rad = roll_rad;
    if (hazard_monitor_knows_zones && InZone(estimate.x, estimate.y)) {
      h.state = HazardState::kViolation;
      h.keepout_violated = true;
      h.zone_name = zones.front().name;
    }
    return h;
  }

  // Runs until the sequence is finished (or max_iterations of 0.1 s).
  void Run(int max_iterations = 20000) {
    for (int i = 0; i < max_iterations; ++i) {
      utime += 100'000;
      wall += 0.1;
      // Deliver what the world produced last iteration.
      std::deque<std::function<void()>> now;
      now.swap(pending_);
      for (auto& f : now) f();
      for (const auto& name : alive) ex_.OnHeartbeat(name, wall);
      if (alive.count("state_estimator")) ex_.OnPose(Pose());
      if (alive.count("hazard_monitor")) ex_.OnHazardStatus(Status());
      ex_.Tick(utime, wall);
      Handle(ex_.TakeOutputs());
      if (on_iteration) on_iteration(ex_, i);
      Handle(ex_.TakeOutputs());
      const SequenceState s = ex_.state();
      if (s == SequenceState::kCompleted || s == SequenceState::kAborted || s == SequenceState::kRejected) {
        return;
      }
    }
  }

  SequenceStatus Final() const { return statuses.back(); }

 private:
  void Handle(std::vector<ExecutorOutput> out) {
    for (auto& o : out) {
      outputs.push_back(o);
      std::visit([this](auto& v) { Handle(v); }, o);
    }
  }

  void Handle(const MobilityCommand& c) {
    if (c.type == MobilityCommand::Type::kStop) {
      stops.push_back(c);
      return;
    }
    motions.push_back(c);
    if (!alive.count("rover_sim") || !mobility_answers) return;
    if (mobility_faults) {
      pending_.push_back([this, c] {
        ex_.OnMobilityStatus({utime, c.command_id, MobilityState::kFault, 0, 0, "motor current"});
      });
      return;
    }
    PlannedStep commanded;
    double duration = 0;
    if (c.type == MobilityCommand::Type::kTurn) {
      commanded = {PlannedStep::Kind::kTurn, 0, 0, c.turn_rad};
      duration = std::abs(c.turn_rad) / c.turn_rate_rps;
    } else {
      commanded = {PlannedStep::Kind::kArc, c.distance_m, c.curvature_per_m, 0};
      duration = std::abs(c.distance_m) / c.speed_mps;
    }
    PlannedStep actual = commanded;
    actual.distance_m *= (1.0 - slip);
    truth = EndOfStep(truth, actual);
    truth.yaw += drift_rad_per_m * std::abs(actual.distance_m);
    truth.x += drift_per_m.x() * std::abs(c.distance_m);
    truth.y += drift_per_m.y() * std::abs(c.distance_m);
    estimate = EndOfStep(estimate, commanded);  // wheel odometry: sees no slip
    utime += static_cast<int64_t>(duration * 1e6);
    pending_.push_back([this, c] {
      ex_.OnMobilityStatus({utime, c.command_id, MobilityState::kDone, c.distance_m, c.turn_rad, ""});
    });
  }

  void Handle(const CaptureRequest& c) {
    captures.push_back(c);
    if (!alive.count("camera_capture")) return;
    pending_.push_back([this, c] { ex_.OnStereoFrame(c.frame_id); });
    if (c.purpose == "science" || vo == Vo::kSilent || !alive.count("visual_odometry")) return;
    VoUpdate u;
    u.utime = utime;
    u.to_frame_id = c.frame_id;
    u.from_frame_id = c.purpose == "vo_baseline" ? -1 : vo_reference_;
    if (c.purpose == "vo_baseline") {
      u.status = VoUpdate::kStatusBaseline;
    } else if (vo == Vo::kFail || vo_fail_next > 0) {
      if (vo_fail_next > 0) --vo_fail_next;
      u.status = 4;
      u.reason = "too few inliers";
    } else {
      u.status = VoUpdate::kStatusOk;
    }
    const bool ok = u.status == VoUpdate::kStatusOk;
    // Like the VO process, every pair becomes the reference for the next, except (here, when
    // the test says so) a failed one.
    if (ok || u.status == VoUpdate::kStatusBaseline || failed_pair_is_reference) vo_reference_ = c.frame_id;
    pending_.push_back([this, u, ok] {
      ex_.OnVoUpdate(u);
      if (ok) {
        // The estimator applies the update: VO measured the true motion.
        estimate = truth;
        last_vo_frame = u.to_frame_id;
      }
    });
  }

  void Handle(const HazardQuery& q) {
    queries.push_back(q);
    if (!alive.count("hazard_monitor") || !hazard_replies) return;
    HazardReply r;
    r.query_id = q.query_id;
    r.verdict = HazardVerdict::kSafe;
    for (const auto& s : q.samples) {
      if (InZone(s.x, s.y, q.margin_m)) {
        r.verdict = HazardVerdict::kUnsafe;
        r.zone_name = zones.front().name;
      }
    }
    pending_.push_back([this, r] { ex_.OnHazardReply(r); });
  }

  void Handle(const KeepOutZoneSet& z) {
    zone_sets.push_back(z);
    zones = z.zones;
  }
  void Handle(const NewSiteRequest& s) {
    sites.push_back(s);
    site_index = s.new_site_index;
    truth.x = truth.y = estimate.x = estimate.y = 0.0;
  }
  void Handle(const SequenceStatus& s) { statuses.push_back(s); }
  void Handle(const StepReport& r) { steps.push_back(r); }

  SequenceExecutor& ex_;
  std::deque<std::function<void()>> pending_;
  int64_t vo_reference_ = -1;
};

ExecutorOptions FastOptions() {
  ExecutorOptions o;
  o.vo_wait_s = 2.0;
  o.hazard_reply_wait_s = 1.0;
  o.hazard_status_wait_s = 1.0;
  o.pose_wait_s = 1.0;
  o.start_wait_s = 1.0;
  o.heartbeat_timeout_s = 1.0;
  return o;
}

void SubmitText(SequenceExecutor& ex, const std::string& text, int64_t id = 7) {
  ex.SubmitText(text, id, "test.seq");
}

int IndexOf(const std::vector<ExecutorOutput>& out, std::function<bool(const ExecutorOutput&)> pred) {
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (pred(out[i])) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

TEST(SequenceExecutor, MultiCommandSequenceCompletesWithTheExpectedSteps) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "vo on step 60 cm maxturn 18 deg failures 3 then abort\n"
                 "slip limit 40 % noprogress 10 % over 2 steps\n"
                 "limit time 3600 s distance 30 m\n"
                 "drive 2.34 m\n"
                 "turn -20.4 deg\n"
                 "turnto 90 deg\n"
                 "arc radius 3 m distance 1.5 m\n"
                 "goto 6 m 1.5 m within 0.3 m time 600 s distance 10 m\n"
                 "images\n");
  w.Run();
  const SequenceStatus last = w.Final();
  ASSERT_EQ(last.state, SequenceState::kCompleted) << last.abort_reason << ": " << last.detail;
  EXPECT_TRUE(w.stops.empty());

  // drive: 4 x 58.5 cm; turn: 2 x -10.2 deg; turnto 90 from -20.4: 7 x 15.77 deg;
  // arc: 3 x 0.5 m (28.6 deg total, under 18 deg per step).
  ASSERT_GE(w.motions.size(), 16u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(w.motions[i].type, MobilityCommand::Type::kArc);
    EXPECT_NEAR(w.motions[i].distance_m, 0.585, 1e-12);
    EXPECT_DOUBLE_EQ(w.motions[i].curvature_per_m, 0.0);
  }
  for (int i = 4; i < 6; ++i) {
    EXPECT_EQ(w.motions[i].type, MobilityCommand::Type::kTurn);
    EXPECT_NEAR(w.motions[i].turn_rad, -10.2 * kDeg, 1e-12);
  }
  for (int i = 6; i < 13; ++i) {
    EXPECT_EQ(w.motions[i].type, MobilityCommand::Type::kTurn);
    EXPECT_NEAR(w.motions[i].turn_rad, 110.4 / 7 * kDeg, 1e-9);
  }
  for (int i = 13; i < 16; ++i) {
    EXPECT_NEAR(w.motions[i].distance_m, 0.5, 1e-12);
    EXPECT_NEAR(w.motions[i].curvature_per_m, 1.0 / 3.0, 1e-12);
  }
  // Goto: ends inside the disc in truth.
  EXPECT_LT(std::hypot(w.truth.x - 6.0, w.truth.y - 1.5), 0.3);
  EXPECT_GT(w.motions.size(), 16u);

  // One step report per motion; one hazard query per motion; one baseline, then a VO pair
  // after every step, then the science pair.
  EXPECT_EQ(w.steps.size(), w.motions.size());
  EXPECT_EQ(w.queries.size(), w.motions.size());
  ASSERT_EQ(w.captures.size(), w.motions.size() + 2);
  EXPECT_EQ(w.captures.front().purpose, "vo_baseline");
  EXPECT_EQ(w.captures.back().purpose, "science");
  for (std::size_t i = 1; i + 1 < w.captures.size(); ++i) EXPECT_EQ(w.captures[i].purpose, "vo");
  for (const auto& s : w.steps) {
    EXPECT_EQ(s.vo_status, VoUpdate::kStatusOk);
    if (s.commanded_distance_m != 0.0) {
      EXPECT_NEAR(s.slip_pct, 0.0, 1e-6);
    }
  }
  // Order for the first step: baseline, query, arc, VO pair.
  const auto& out = w.outputs;
  const int baseline = IndexOf(out, [](const ExecutorOutput& o) {
    auto* c = std::get_if<CaptureRequest>(&o);
    return c && c->purpose == "vo_baseline";
  });
  const int query = IndexOf(out, [](const ExecutorOutput& o) { return std::holds_alternative<HazardQuery>(o); });
  const int arc = IndexOf(out, [](const ExecutorOutput& o) { return std::holds_alternative<MobilityCommand>(o); });
  const int vo = IndexOf(out, [](const ExecutorOutput& o) {
    auto* c = std::get_if<CaptureRequest>(&o);
    return c && c->purpose == "vo";
  });
  EXPECT_LT(baseline, query);
  EXPECT_LT(query, arc);
  EXPECT_LT(arc, vo);
  // Ids never repeat across commands, frames and queries.
  std::set<int64_t> ids;
  for (const auto& m : w.motions) EXPECT_TRUE(ids.insert(m.command_id).second);
  for (const auto& c : w.captures) EXPECT_TRUE(ids.insert(c.frame_id).second);
  for (const auto& q : w.queries) EXPECT_TRUE(ids.insert(q.query_id).second);
  EXPECT_EQ(last.num_commands, 9);
  EXPECT_GT(last.distance_m, 5.0);
  EXPECT_EQ(last.vo_failures, 0);
}

TEST(SequenceExecutor, SlipOverTheLimitAbortsWithProgress) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.slip = 0.45;
  SubmitText(ex, "vo on step 60 cm\nslip limit 40 %\ndrive 3 m\n");
  w.Run();
  const SequenceStatus last = w.Final();
  ASSERT_EQ(last.state, SequenceState::kAborted);
  EXPECT_EQ(last.abort_reason, "progress");
  EXPECT_EQ(last.command_index, 2);
  EXPECT_EQ(last.command_line, 3);
  EXPECT_EQ(last.command_text, "drive 3 m");
  EXPECT_EQ(last.step_index, 1);
  EXPECT_NEAR(last.pose[0], 0.6 * 0.55, 1e-9);  // the VO-corrected pose
  ASSERT_EQ(w.motions.size(), 1u);
  ASSERT_EQ(w.stops.size(), 1u);
  ASSERT_EQ(w.steps.size(), 1u);
  EXPECT_NEAR(w.steps[0].slip_pct, 45.0, 1e-6);
  EXPECT_NE(last.detail.find("slip 45.0 % > limit 40.0 %"), std::string::npos) << last.detail;
}

TEST(SequenceExecutor, SlipUnderTheLimitCompletes) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.slip = 0.35;
  SubmitText(ex, "vo on step 60 cm\nslip limit 40 %\ndrive 3 m\n");
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  EXPECT_EQ(w.motions.size(), 5u);
  EXPECT_NEAR(w.truth.x, 3.0 * 0.65, 1e-9);
}

TEST(SequenceExecutor, NoProgressForNStepsAborts) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.slip = 0.95;  // under the 100 % limit, but almost no progress
  SubmitText(ex, "vo on\nslip limit 100 % noprogress 10 % over 3 steps\ndrive 5 m\n");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "progress");
  EXPECT_EQ(w.motions.size(), 3u);
}

TEST(SequenceExecutor, PredictiveKeepOutStopsBeforeTheStepIsCommanded) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "keepout rock circle 3 m 0 m radius 0.5 m\ndrive 6 m\n");
  w.Run();
  const SequenceStatus last = w.Final();
  ASSERT_EQ(last.state, SequenceState::kAborted);
  EXPECT_EQ(last.abort_reason, "keepout");
  EXPECT_EQ(last.step_index, 3);
  // Zone + footprint start at x = 2.0; steps of 0.6 m: the 4th would end at 2.4, so only
  // three are commanded and the rover stays clear.
  EXPECT_EQ(w.motions.size(), 3u);
  EXPECT_EQ(w.queries.size(), 4u);
  EXPECT_NEAR(w.truth.x, 1.8, 1e-9);
  EXPECT_FALSE(w.InZone(w.truth.x, w.truth.y));
  ASSERT_EQ(w.zone_sets.size(), 2u);
  EXPECT_TRUE(w.zone_sets[0].zones.empty());  // the start: no zones from an earlier sequence
  EXPECT_EQ(w.zone_sets[1].zones[0].name, "rock");
  EXPECT_EQ(w.stops.size(), 1u);
  EXPECT_NE(last.detail.find("rock"), std::string::npos);
  // The query samples the step's swept path from the current pose, ends included.
  const auto& q = w.queries[0].samples;
  ASSERT_GE(q.size(), 13u);
  EXPECT_NEAR(q.front().x, 0.0, 1e-12);
  EXPECT_NEAR(q.back().x, 0.6, 1e-12);
  for (std::size_t i = 1; i < q.size(); ++i) EXPECT_LE(std::hypot(q[i].x - q[i - 1].x, q[i].y - q[i - 1].y), 0.05 + 1e-9);
  EXPECT_NEAR(w.queries[3].samples.front().x, 1.8, 1e-9);
  EXPECT_NEAR(w.queries[3].samples.back().x, 2.4, 1e-9);
}

TEST(SequenceExecutor, HazardStatusViolationAfterAStepAbortsKeepout) {
  ExecutorOptions o = FastOptions();
  o.predictive_hazard_check = false;  // only the status check is left to catch it
  o.reactive_hazard_abort = false;
  SequenceExecutor ex(o);
  FakeWorld w(ex);
  SubmitText(ex, "keepout rock circle 3 m 0 m radius 0.5 m\ndrive 6 m\n");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "keepout");
  EXPECT_EQ(w.motions.size(), 4u);  // the step that entered the zone is the last
  EXPECT_TRUE(w.queries.empty());
}

TEST(SequenceExecutor, UnknownHazardStateOrSilentMonitorAborts) {
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    SubmitText(ex, "drive 2 m\n");
    w.on_iteration = [&](SequenceExecutor&, int i) { if (i == 5) w.hazard_unknown = true; };
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "hazard_unknown");
  }
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    w.hazard_replies = false;  // heartbeats go on, but no answer to the query
    SubmitText(ex, "drive 2 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "hazard_unknown");
    EXPECT_TRUE(w.motions.empty());
    EXPECT_NE(w.Final().detail.find("no hazard reply"), std::string::npos);
  }
}

TEST(SequenceExecutor, TiltOverTheSequenceLimitAborts) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.roll_rad = 22 * kDeg;
  SubmitText(ex, "tilt roll 20 deg pitch 25 deg\ndrive 2 m\n");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "tilt");
  EXPECT_EQ(w.motions.size(), 1u);  // reactive: the status during the step stops it
}

TEST(SequenceExecutor, SilentHeartbeatDuringADriveAbortsProcessLost) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "drive 5 m\n");
  w.on_iteration = [&](SequenceExecutor&, int) {
    if (w.motions.size() == 2) w.alive.erase("state_estimator");
  };
  w.Run();
  const SequenceStatus last = w.Final();
  EXPECT_EQ(last.abort_reason, "process_lost");
  EXPECT_NE(last.detail.find("state_estimator"), std::string::npos) << last.detail;
  EXPECT_EQ(w.motions.size(), 2u);
  EXPECT_EQ(w.stops.size(), 1u);
}

TEST(SequenceExecutor, NoSequenceStartsWhileAProcessIsSilent) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.alive.erase("hazard_monitor");
  SubmitText(ex, "drive 5 m\n");
  w.Run();
  const SequenceStatus last = w.Final();
  EXPECT_EQ(last.state, SequenceState::kRejected);
  EXPECT_EQ(last.abort_reason, "process_lost");
  EXPECT_NE(last.detail.find("hazard_monitor"), std::string::npos);
  EXPECT_TRUE(w.motions.empty());
  // VO processes are needed only by a sequence that turns VO on.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.alive.erase("visual_odometry");
  SubmitText(ex2, "drive 1 m\n");
  w2.Run();
  EXPECT_EQ(w2.Final().state, SequenceState::kCompleted);
  SequenceExecutor ex3(FastOptions());
  FakeWorld w3(ex3);
  w3.alive.erase("visual_odometry");
  SubmitText(ex3, "vo on\ndrive 1 m\n");
  w3.Run();
  EXPECT_EQ(w3.Final().abort_reason, "process_lost");
  EXPECT_NE(w3.Final().detail.find("visual_odometry"), std::string::npos);
}

TEST(SequenceExecutor, MobilityDriverAlternativesSatisfyTheRequirement) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.alive.erase("rover_sim");
  w.alive.insert("mobility_driver");
  SubmitText(ex, "site\n");
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
}

TEST(SequenceExecutor, VoFailuresPastTheLimitAbort) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.vo = FakeWorld::Vo::kFail;
  SubmitText(ex, "vo on step 50 cm failures 2 then abort\ndrive 3 m\n");
  w.Run();
  const SequenceStatus last = w.Final();
  EXPECT_EQ(last.abort_reason, "vo_failures");
  EXPECT_EQ(last.vo_failures, 3);
  EXPECT_EQ(w.motions.size(), 3u);
  EXPECT_EQ(w.steps.back().vo_status, 4);
}

TEST(SequenceExecutor, VoFailuresPastTheLimitCanContinueOnWheelOdometry) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.vo = FakeWorld::Vo::kFail;
  SubmitText(ex, "vo on step 50 cm failures 1 then continue\ndrive 3 m\n");
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted);
  EXPECT_EQ(w.motions.size(), 6u);
  // Baseline + a pair after steps 1 and 2; then VO is off and no more pairs are taken.
  EXPECT_EQ(w.captures.size(), 3u);
  EXPECT_EQ(w.Final().vo_failures, 2);
}

TEST(SequenceExecutor, VoSwitchedOffByFailuresIsTriedAgainAfterVoRetryAfterM) {
  ExecutorOptions o = FastOptions();
  o.vo_retry_after_m = 1.0;
  SequenceExecutor ex(o);
  FakeWorld w(ex);
  w.vo_fail_next = 2;  // the pairs after steps 1 and 2 fail; VO measures again from then on
  SubmitText(ex, "vo on step 50 cm failures 1 then continue\ndrive 4 m\n");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  ASSERT_EQ(w.steps.size(), 8u);
  // Off after step 2 (1 m); steps 3 and 4 blind (1 m more); back on before step 5 with a
  // baseline pair, and every step after it measured.
  for (std::size_t i = 2; i < 4; ++i) EXPECT_EQ(w.steps[i].vo_status, -1) << i;
  for (std::size_t i = 4; i < 8; ++i) EXPECT_EQ(w.steps[i].vo_status, VoUpdate::kStatusOk) << i;
  int baselines = 0;
  for (const auto& c : w.captures) baselines += c.purpose == "vo_baseline";
  EXPECT_EQ(baselines, 2);
  // Without the option (Mars's meaning), VO stays off to the end.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.vo_fail_next = 2;
  SubmitText(ex2, "vo on step 50 cm failures 1 then continue\ndrive 4 m\n");
  w2.Run();
  ASSERT_EQ(w2.steps.size(), 8u);
  EXPECT_EQ(w2.steps.back().vo_status, -1);
  EXPECT_EQ(w2.captures.size(), 3u);
}

TEST(SequenceExecutor, SilentVoCountsFailuresAfterTheWait) {
  ExecutorOptions o = FastOptions();
  o.vo_processes_required = false;
  SequenceExecutor ex(o);
  FakeWorld w(ex);
  w.vo = FakeWorld::Vo::kSilent;  // heartbeats, but never an answer
  SubmitText(ex, "vo on step 50 cm failures 5 then abort wait 1 s\ndrive 1 m\n");
  const double wall0 = w.wall;
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted);
  EXPECT_EQ(w.Final().vo_failures, 3);  // the baseline and two steps
  EXPECT_GT(w.wall - wall0, 3.0);        // each waited its 1 s
  // With no VO process at all, nothing is waited for.
  SequenceExecutor ex2(o);
  FakeWorld w2(ex2);
  w2.alive.erase("visual_odometry");
  SubmitText(ex2, "vo on step 50 cm failures 1 then abort\ndrive 2 m\n");
  w2.Run();
  EXPECT_EQ(w2.Final().abort_reason, "vo_failures");
}

TEST(SequenceExecutor, GotoReachesItsDiscDespiteHeadingDrift) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.drift_rad_per_m = 4 * kDeg;  // the rover pulls right; VO sees it and goto re-steers
  SubmitText(ex, "vo on\ngoto 5 m -4 m within 0.2 m\n");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  EXPECT_LT(std::hypot(w.truth.x - 5.0, w.truth.y + 4.0), 0.2);
  EXPECT_LT(w.Final().distance_m, 1.5 * std::hypot(5.0, 4.0));
  // Without VO the estimate drifts away from truth, yet the goto ends inside the disc in
  // the estimate.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.drift_rad_per_m = 4 * kDeg;
  SubmitText(ex2, "goto 5 m -4 m within 0.2 m\n");
  w2.Run();
  ASSERT_EQ(w2.Final().state, SequenceState::kCompleted);
  EXPECT_LT(std::hypot(w2.estimate.x - 5.0, w2.estimate.y + 4.0), 0.2);
  EXPECT_GT(std::hypot(w2.truth.x - 5.0, w2.truth.y + 4.0), 0.2);
}

// Goal reached by truth, not hope: with a 5 cm position sigma the goto ends inside the
// disc less 3 sigma (0.3 - 0.15 m), and says so; with 0.2 m the margin does not fit in the
// 0.3 m disc, and it ends within a quarter of the radius and says the truth may lie outside.
TEST(SequenceExecutor, GotoEndsInsideTheDiscLessThreeSigma) {
  for (const double sigma : {0.0, 0.05, 0.2}) {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    w.position_sigma_m = sigma;
    SubmitText(ex, "goto 2.3 m 0.1 m within 0.3 m\n");
    w.Run();
    ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
    const double off = std::hypot(w.estimate.x - 2.3, w.estimate.y - 0.1);
    const std::string& d = w.Final().detail;
    if (sigma == 0.0) {
      EXPECT_LE(off, 0.3);
      EXPECT_NE(d.find("inside the 0.30 m disc less 3 sigma (0.00 m)"), std::string::npos) << d;
    } else if (sigma == 0.05) {
      EXPECT_LE(off, 0.15 + 1e-9);
      EXPECT_NE(d.find("inside the 0.30 m disc less 3 sigma (0.15 m)"), std::string::npos) << d;
    } else {
      EXPECT_LE(off, 0.075 + 1e-9);
      EXPECT_NE(d.find("the estimate's 3 sigma (0.60 m) does not fit in the 0.30 m disc"), std::string::npos) << d;
      EXPECT_NE(d.find("the truth may lie outside the disc"), std::string::npos) << d;
    }
  }
}

TEST(SequenceExecutor, GotoLimitsAbort) {
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    SubmitText(ex, "goto 5 m 0 m within 0.2 m distance 2 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "goto_distance_limit");
    EXPECT_NEAR(w.truth.x, 2.4, 1e-9);  // the step that passed 2 m
  }
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    SubmitText(ex, "goto 5 m 0 m within 0.2 m time 40 s\n");  // 15 s per 0.6 m step
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "goto_time_limit");
    EXPECT_EQ(w.motions.size(), 3u);
  }
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    w.slip = 1.2;  // slides back and never gets there; the default limit (1.5 d + 2 m) stops it
    SubmitText(ex, "vo on\ngoto 2 m 0 m within 0.2 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "goto_distance_limit");
    EXPECT_NE(w.Final().detail.find("limit 5.00 m"), std::string::npos) << w.Final().detail;
  }
}

TEST(SequenceExecutor, TotalLimitsAbort) {
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    SubmitText(ex, "limit distance 1 m\ndrive 3 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "distance_limit");
    EXPECT_EQ(w.motions.size(), 2u);
  }
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    SubmitText(ex, "limit time 20 s\ndrive 3 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "time_limit");
    EXPECT_EQ(w.motions.size(), 2u);
  }
}

TEST(SequenceExecutor, OperatorAbortStopsAndSkipsTheRest) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "drive 3 m\nturn 90 deg\n");
  w.on_iteration = [&](SequenceExecutor& e, int) {
    if (w.motions.size() == 2 && e.Active()) e.Abort("rock ahead");
  };
  w.Run();
  const SequenceStatus last = w.Final();
  EXPECT_EQ(last.state, SequenceState::kAborted);
  EXPECT_EQ(last.abort_reason, "operator");
  EXPECT_NE(last.detail.find("rock ahead"), std::string::npos);
  EXPECT_EQ(w.motions.size(), 2u);
  EXPECT_EQ(w.stops.size(), 1u);
  // The stop comes after the last motion.
  EXPECT_GT(w.stops[0].command_id, w.motions.back().command_id);
}

TEST(SequenceExecutor, PauseHoldsBetweenStepsAndResumeFinishes) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "drive 3 m\n");
  std::size_t motions_at_pause = 0;
  int paused_iterations = 0;
  w.on_iteration = [&](SequenceExecutor& e, int) {
    if (w.motions.size() == 2 && motions_at_pause == 0) {
      e.Pause();
      motions_at_pause = 2;
    }
    if (e.state() == SequenceState::kPaused && ++paused_iterations == 30) e.Resume();
  };
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted);
  EXPECT_EQ(paused_iterations, 30);
  EXPECT_EQ(w.motions.size(), 5u);
  bool saw_paused = false;
  for (const auto& s : w.statuses) saw_paused |= s.state == SequenceState::kPaused && s.step_index == 2;
  EXPECT_TRUE(saw_paused);
}

// A pause counts against no time limit: an hour paused in a goto with a 600 s limit, inside
// a sequence limited to 1200 s, and the goto still completes; the resume line says what is left.
TEST(SequenceExecutor, AnHourPausedCountsAgainstNoTimeLimit) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "limit time 1200 s\ngoto 3 m 0 m within 0.3 m time 600 s\n");
  bool paused_once = false;
  int paused_iterations = 0;
  w.on_iteration = [&](SequenceExecutor& e, int) {
    if (w.motions.size() == 2 && !paused_once) {
      e.Pause();
      paused_once = true;
    }
    if (e.state() != SequenceState::kPaused) return;
    ++paused_iterations;
    if (paused_iterations == 3) {
      w.utime += 3600'000'000;  // an hour of rover time while paused
      w.wall += 3600.0;
    }
    if (paused_iterations == 6) e.Resume();
  };
  w.Run();
  const SequenceStatus last = w.Final();
  EXPECT_EQ(last.state, SequenceState::kCompleted) << last.abort_reason << ": " << last.detail;
  EXPECT_LT(last.elapsed_s, 1200.0);  // the hour paused is not in it
  bool said_paused = false, said_resumed = false;
  for (const auto& st : w.statuses) {
    said_paused |= st.state == SequenceState::kPaused &&
                   st.detail.find("the time limits stand still while paused") != std::string::npos &&
                   st.detail.find("goto ") != std::string::npos;
    said_resumed |= st.detail.find("resumed after 3600.") != std::string::npos &&
                    st.detail.find("not counted against the time limits") != std::string::npos;
  }
  EXPECT_TRUE(said_paused);
  EXPECT_TRUE(said_resumed);

  // The same hour passing while the goto runs (no pause) is over its limit.
  SequenceExecutor running(FastOptions());
  FakeWorld r(running);
  SubmitText(running, "goto 3 m 0 m within 0.3 m time 600 s\n");
  bool jumped = false;
  r.on_iteration = [&](SequenceExecutor&, int) {
    if (r.motions.size() == 2 && !jumped) {
      r.utime += 3600'000'000;
      jumped = true;
    }
  };
  r.Run();
  EXPECT_EQ(r.Final().abort_reason, "goto_time_limit") << r.Final().detail;
}

TEST(SequenceExecutor, MobilityFaultAndSilenceAbort) {
  {
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    w.mobility_faults = true;
    SubmitText(ex, "drive 1 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "mobility_fault");
    EXPECT_NE(w.Final().detail.find("motor current"), std::string::npos);
  }
  {
    ExecutorOptions o = FastOptions();
    o.mobility_wait_s = 5.0;
    SequenceExecutor ex(o);
    FakeWorld w(ex);
    w.mobility_answers = false;  // heartbeats but no DONE
    SubmitText(ex, "drive 1 m\n");
    w.Run();
    EXPECT_EQ(w.Final().abort_reason, "timeout");
  }
}

// The zones of one sequence end with it: the next one starts by sending the hazard monitor
// an empty set, so a sequence that declares none is not aborted on an old zone it drives into.
TEST(SequenceExecutor, ZonesOfAnEarlierSequenceAreClearedForTheMonitor) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "keepout mazatzal circle 3 m 0 m radius 0.5 m\nturn 90 deg\n", 1);
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  ASSERT_EQ(w.zones.size(), 1u);  // the monitor holds it after the sequence ended
  SubmitText(ex, "turnto 0 deg\ndrive 4 m\n", 2);
  w.Run();
  EXPECT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  EXPECT_TRUE(w.zones.empty());
  EXPECT_GT(w.truth.x, 3.5);  // it drove through where the old zone was
  ASSERT_FALSE(w.zone_sets.empty());
  EXPECT_TRUE(w.zone_sets.back().zones.empty());
}

TEST(SequenceExecutor, SiteAndZonesAndRejections) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "keepout a circle 10 m 10 m radius 1 m\ndrive 1 m\nsite\ndrive 1 m\n");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  ASSERT_EQ(w.sites.size(), 1u);
  EXPECT_EQ(w.sites[0].new_site_index, 1);
  ASSERT_EQ(w.zone_sets.size(), 3u);          // the start's empty set, the zone, the new site's
  EXPECT_TRUE(w.zone_sets[2].zones.empty());  // zones of the old site are cleared
  EXPECT_NEAR(w.estimate.x, 1.0, 1e-9);        // 1 m from the new site's origin

  // A check failure is rejected with the file:line:col line; nothing is commanded.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  SubmitText(ex2, "drive 1 m\ndrive 3 deg\n", 42);
  const SequenceStatus rej = std::get<SequenceStatus>(ex2.TakeOutputs().back());
  EXPECT_EQ(rej.state, SequenceState::kRejected);
  EXPECT_EQ(rej.submission_id, 42);
  EXPECT_EQ(rej.abort_reason, "invalid_sequence");
  EXPECT_EQ(rej.detail.rfind("test.seq:2:9: wrong unit 'deg'", 0), 0u) << rej.detail;

  // A submission while one runs is rejected; the running one carries on.
  SequenceExecutor ex3(FastOptions());
  FakeWorld w3(ex3);
  SubmitText(ex3, "drive 2 m\n", 1);
  bool submitted = false;
  w3.on_iteration = [&](SequenceExecutor& e, int) {
    if (!submitted && w3.motions.size() == 1) {
      submitted = true;
      e.SubmitText("drive 1 m\n", 2, "other.seq");
    }
  };
  w3.Run();
  EXPECT_EQ(w3.Final().state, SequenceState::kCompleted);
  EXPECT_EQ(w3.Final().submission_id, 1);
  bool busy = false;
  for (const auto& s : w3.statuses) busy |= s.submission_id == 2 && s.abort_reason == "busy";
  EXPECT_TRUE(busy);
}

TEST(ExecutorOptions, LoadsTheExampleAndRejectsBadValues) {
  const std::string path = std::string(ROVER_SOURCE_DIR) + "/common/sequence/executor_example.yaml";
  const ExecutorOptions o = LoadExecutorOptionsFile(path);
  EXPECT_DOUBLE_EQ(o.heartbeat_timeout_s, 3.0);
  ASSERT_EQ(o.required_processes.size(), 3u);
  EXPECT_EQ(o.required_processes[0], "rover_sim|mobility_driver");
  EXPECT_DOUBLE_EQ(o.blind_slope_deg, 15.0);
  EXPECT_EQ(o.recent_steps, 3);
  EXPECT_DOUBLE_EQ(o.step_sigma_growth_pct, 2.0);
  using rover::config::ConfigError;
  using rover::config::ConfigNode;
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  vo_wiat_s: 3\n", "x.yaml")), ConfigError);
  try {
    LoadExecutorOptions(ConfigNode::FromString("executor:\n  vo_wait_s: -1\n", "x.yaml"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("executor.vo_wait_s"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  recent_steps: 0\n", "x.yaml")), ConfigError);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  blind_slope_deg: 60\n", "x.yaml")), ConfigError);
  EXPECT_DOUBLE_EQ(o.avoid_hidden_flank_step_m, 0.0);  // off in the example
  EXPECT_DOUBLE_EQ(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_hidden_flank_step_m: 0.125\n", "x.yaml"))
                       .avoid_hidden_flank_step_m,
                   0.125);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_hidden_flank_step_m: -0.1\n", "x.yaml")),
               ConfigError);
  EXPECT_DOUBLE_EQ(o.avoid_top_rise_m, 0.0);  // off in the example
  EXPECT_DOUBLE_EQ(o.avoid_top_ground_radius_m, 1.0);
  EXPECT_DOUBLE_EQ(
      LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_top_rise_m: 0.25\n", "x.yaml")).avoid_top_rise_m,
      0.25);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_top_rise_m: -0.1\n", "x.yaml")),
               ConfigError);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_top_ground_radius_m: 0.1\n", "x.yaml")),
               ConfigError);
  EXPECT_FALSE(o.avoid_top_rise_in_plan);
  EXPECT_TRUE(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_top_rise_in_plan: true\n", "x.yaml"))
                  .avoid_top_rise_in_plan);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_top_rise_in_plan: 2\n", "x.yaml")),
               ConfigError);
  EXPECT_FALSE(o.avoid_keep_unsafe);
  EXPECT_TRUE(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_keep_unsafe: true\n", "x.yaml")).avoid_keep_unsafe);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_keep_unsafe: 3\n", "x.yaml")), ConfigError);
  EXPECT_DOUBLE_EQ(o.avoid_good_enough, 1.0);  // off in the example
  EXPECT_DOUBLE_EQ(
      LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_good_enough: 0\n", "x.yaml")).avoid_good_enough, 0.0);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_good_enough: -0.1\n", "x.yaml")), ConfigError);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  avoid_good_enough: 1.5\n", "x.yaml")), ConfigError);
  EXPECT_DOUBLE_EQ(o.planner_near_cost, 3.0);
  EXPECT_DOUBLE_EQ(
      LoadExecutorOptions(ConfigNode::FromString("executor:\n  planner_near_cost: 1.5\n", "x.yaml")).planner_near_cost, 1.5);
  EXPECT_THROW(LoadExecutorOptions(ConfigNode::FromString("executor:\n  planner_near_cost: 0.5\n", "x.yaml")), ConfigError);
  const ExecutorOptions d = LoadExecutorOptions(ConfigNode::FromString("other: 1\n", "x.yaml"));
  EXPECT_DOUBLE_EQ(d.vo_wait_s, ExecutorOptions{}.vo_wait_s);
  ExecutorOptions bad;
  bad.speed_mps = 0.0;
  EXPECT_THROW(SequenceExecutor{bad}, std::invalid_argument);
}

TEST(SequenceExecutor, BrokenPoseEstimateStopsWithoutThrowing) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  SubmitText(ex, "drive 2 m\ngoto 3 m 3 m within 0.5 m\n");
  w.on_iteration = [&](SequenceExecutor&, int) { if (w.motions.size() == 2) w.nan_pose = true; };
  ASSERT_NO_THROW(w.Run());
  EXPECT_EQ(w.Final().state, SequenceState::kAborted);
  EXPECT_EQ(w.Final().abort_reason, "hazard_unknown");
  EXPECT_EQ(w.stops.size(), 1u);
}

TEST(SequenceExecutor, EverySampleSequenceRunsToAnEndInTheFakeWorld) {
  const std::filesystem::path dir = std::filesystem::path(ROVER_SOURCE_DIR) / "configs" / "sequences";
  int files = 0;
  for (const char* name : {"approach_outcrop.seq", "demo_drive.seq", "keepout_rock.seq",
                           "rock_course_vo.seq", "slope_climb.seq"}) {
    const std::filesystem::directory_entry entry(dir / name);
    ++files;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    SequenceExecutor ex(FastOptions());
    FakeWorld w(ex);
    ex.SubmitText(text.str(), files, entry.path().filename().string());
    w.Run();
    const SequenceStatus last = w.Final();
    // Flat, slip-free, everything answering: only a keep-out zone may stop a sample.
    EXPECT_TRUE(last.state == SequenceState::kCompleted ||
                (last.state == SequenceState::kAborted && last.abort_reason == "keepout"))
        << entry.path() << ": " << ToString(last.state) << " " << last.abort_reason << ": " << last.detail;
    EXPECT_FALSE(w.steps.empty()) << entry.path();
  }
  EXPECT_EQ(files, 5);
}

// ---- VO lost: no blind slide ----

namespace {
int CountPurpose(const FakeWorld& w, const std::string& purpose) {
  int n = 0;
  for (const auto& c : w.captures) n += c.purpose == purpose;
  return n;
}
}  // namespace

TEST(SequenceExecutor, VoLostOnASlopeAbortsByDefaultInsteadOfDrivingOnWheelOdometry) {
  // Sol 206: VO fails on every step up a 20 deg slope while the rover slides back. With
  // `then continue` VO used to switch off and wheel odometry reported metres of progress.
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.pitch_rad = -20 * kDeg;  // nose up
  w.slip = 1.3;
  w.vo = FakeWorld::Vo::kFail;
  SubmitText(ex, "vo on step 60 cm failures 5 then continue\nslip limit 40 % noprogress 10 % over 2 steps\n"
                 "drive 10 m\n");
  w.Run();
  const SequenceStatus last = w.Final();
  ASSERT_EQ(last.state, SequenceState::kAborted);
  EXPECT_EQ(last.abort_reason, "vo_lost");
  EXPECT_NE(last.detail.find("tilt 20.0 deg > 15.0 deg"), std::string::npos) << last.detail;
  EXPECT_EQ(w.motions.size(), 1u);  // one step, then it stops
  EXPECT_EQ(w.stops.size(), 1u);
  // The same on flat ground keeps the Mars meaning: VO off after 5 failures, drive on.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.vo = FakeWorld::Vo::kFail;
  SubmitText(ex2, "vo on step 60 cm failures 5 then continue\ndrive 6 m\n");
  w2.Run();
  EXPECT_EQ(w2.Final().state, SequenceState::kCompleted) << w2.Final().detail;
  EXPECT_EQ(w2.motions.size(), 10u);
}

TEST(SequenceExecutor, SlipMeasuredInTheRecentStepsMakesAVoFailureVoLost) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.slip = 0.3;  // flat, but VO measures 30 % slip (> 20 %)
  SubmitText(ex, "vo on step 50 cm\ndrive 4 m\n");
  w.on_iteration = [&](SequenceExecutor&, int) { if (w.steps.size() == 2) w.vo = FakeWorld::Vo::kFail; };
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "vo_lost");
  EXPECT_NE(w.Final().detail.find("VO measured 30.0 % slip"), std::string::npos) << w.Final().detail;
  EXPECT_EQ(w.motions.size(), 3u);
  // Sideways drift counts as well, and `vo lost ... slip` moves the threshold.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.drift_per_m = {0.0, 0.25};  // 25 % of the step sideways
  SubmitText(ex2, "vo on step 50 cm\nvo lost abort slip 30 %\ndrive 4 m\n");
  w2.on_iteration = [&](SequenceExecutor&, int) { if (w2.steps.size() == 2) w2.vo = FakeWorld::Vo::kFail; };
  w2.Run();
  EXPECT_EQ(w2.Final().state, SequenceState::kCompleted) << w2.Final().detail;
  SequenceExecutor ex3(FastOptions());
  FakeWorld w3(ex3);
  w3.drift_per_m = {0.0, 0.25};
  SubmitText(ex3, "vo on step 50 cm\ndrive 4 m\n");
  w3.on_iteration = [&](SequenceExecutor&, int) { if (w3.steps.size() == 2) w3.vo = FakeWorld::Vo::kFail; };
  w3.Run();
  EXPECT_EQ(w3.Final().abort_reason, "vo_lost");
}

TEST(SequenceExecutor, VoSwitchedOffByFailuresDoesNotDriveBlindOntoASlope) {
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.vo = FakeWorld::Vo::kFail;
  SubmitText(ex, "vo on step 50 cm failures 1 then continue\ndrive 5 m\n");
  // Flat for three steps (VO off after the second), then the ground tilts.
  w.on_iteration = [&](SequenceExecutor&, int) { if (w.motions.size() == 4) w.pitch_rad = 18 * kDeg; };
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "vo_lost");
  EXPECT_NE(w.Final().detail.find("step 3:"), std::string::npos) << w.Final().detail;
  EXPECT_EQ(w.motions.size(), 4u);
  EXPECT_EQ(w.captures.size(), 3u);  // baseline and two pairs; none once VO was off
}

TEST(SequenceExecutor, VoLostShortenHalvesTheStepsThenAbortsAtTheShortest) {
  SequenceExecutor ex(FastOptions());  // lost_min_step_m 0.15
  FakeWorld w(ex);
  w.pitch_rad = -20 * kDeg;
  w.vo = FakeWorld::Vo::kFail;
  SubmitText(ex, "vo on step 60 cm\nvo lost shorten\ndrive 3 m\n");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "vo_lost");
  EXPECT_NE(w.Final().detail.find("at the shortest step (0.15 m)"), std::string::npos) << w.Final().detail;
  ASSERT_EQ(w.motions.size(), 3u);
  EXPECT_NEAR(w.motions[0].distance_m, 0.6, 1e-12);
  EXPECT_NEAR(w.motions[1].distance_m, 0.3, 1e-12);   // 2.4 m left in 8 steps
  EXPECT_NEAR(w.motions[2].distance_m, 0.15, 1e-12);  // 2.1 m left in 14 steps
  // When VO measures again, each measured step doubles the step back to the setting.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.pitch_rad = -20 * kDeg;
  w2.vo_fail_next = 2;
  SubmitText(ex2, "vo on step 60 cm\nvo lost shorten\ndrive 3 m\n");
  w2.Run();
  ASSERT_EQ(w2.Final().state, SequenceState::kCompleted) << w2.Final().detail;
  ASSERT_EQ(w2.motions.size(), 7u);
  // Lost at 60 and 30 cm; measured at 15 cm, so the 1.95 m left go in 30 cm steps (7 of
  // 27.9 cm); measured again, so the rest goes in 60 cm steps (3 of 55.7 cm).
  const double rest = 1.95 - 1.95 / 7;
  const double expected[] = {0.6, 0.3, 0.15, 1.95 / 7, rest / 3, rest / 3, rest / 3};
  for (std::size_t i = 0; i < 7; ++i) EXPECT_NEAR(w2.motions[i].distance_m, expected[i], 1e-12) << i;
  EXPECT_NEAR(w2.truth.x, 3.0, 1e-9);
}

TEST(SequenceExecutor, VoLostRetryCountsOnlyAPairMeasuredAcrossTheStep) {
  // An unusable pair (VO keeps the pair before the step as its reference): the pair taken
  // again measures the whole step, and the drive goes on.
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.pitch_rad = -20 * kDeg;
  w.vo_fail_next = 1;
  w.failed_pair_is_reference = false;
  SubmitText(ex, "vo on step 50 cm\nvo lost retry 2\ndrive 1 m\n");
  w.Run();
  ASSERT_EQ(w.Final().state, SequenceState::kCompleted) << w.Final().detail;
  EXPECT_EQ(w.motions.size(), 2u);
  EXPECT_EQ(CountPurpose(w, "vo"), 3);  // two steps and one retry
  EXPECT_EQ(w.steps.front().vo_status, VoUpdate::kStatusOk);
  // A failed pair that VO took as its reference: the retries measure from it, not across
  // the step, so they do not count; after two the sequence aborts.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.pitch_rad = -20 * kDeg;
  w2.vo_fail_next = 1;
  SubmitText(ex2, "vo on step 50 cm\nvo lost retry 2\ndrive 1 m\n");
  w2.Run();
  EXPECT_EQ(w2.Final().abort_reason, "vo_lost");
  EXPECT_NE(w2.Final().detail.find("also after 2 more pairs"), std::string::npos) << w2.Final().detail;
  EXPECT_EQ(w2.motions.size(), 1u);
  EXPECT_EQ(CountPurpose(w2, "vo"), 3);
  EXPECT_EQ(w2.steps.size(), 1u);  // one report for the step, after its retries
}

TEST(SequenceExecutor, WheelOdometryIsNoEvidenceOfProgressOnASlope) {
  // VO off by the operator: on flat ground the check trusts wheel odometry; on a slope it
  // cannot decide, so the steps count as no progress and the drive stops.
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.pitch_rad = -20 * kDeg;
  w.slip = 1.2;  // sliding back; the wheels say 0 %
  SubmitText(ex, "slip limit 40 % noprogress 10 % over 2 steps\ndrive 5 m\n");
  w.Run();
  EXPECT_EQ(w.Final().abort_reason, "progress");
  EXPECT_NE(w.Final().detail.find("progress unknown"), std::string::npos) << w.Final().detail;
  EXPECT_EQ(w.motions.size(), 2u);
  // Without a progress check the operator drives blind, as asked.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.pitch_rad = -20 * kDeg;
  SubmitText(ex2, "drive 2 m\n");
  w2.Run();
  EXPECT_EQ(w2.Final().state, SequenceState::kCompleted);
}

// ---- predictive keep-out with drift ----

TEST(SequenceExecutor, PredictiveKeepOutAllowsForTheDriftVoMeasured) {
  // Wopmay: the rover slides 5 cm east per 25 cm step north, toward a rock east of its path.
  // Each step's commanded path clears the zone; the drift VO measured does not.
  const char* text = "keepout rock circle 2.5 m 1.3 m radius 0.3 m\ndrive 5 m\n";
  SequenceExecutor ex(FastOptions());
  FakeWorld w(ex);
  w.drift_per_m = {0.0, 0.2};
  SubmitText(ex, std::string("vo on step 25 cm\n") + text);
  w.Run();
  const SequenceStatus last = w.Final();
  ASSERT_EQ(last.abort_reason, "keepout") << last.detail;
  EXPECT_EQ(w.motions.size(), 9u);
  EXPECT_FALSE(w.InZone(w.truth.x, w.truth.y));  // truth clearance > 0
  // The refused query: its commanded half alone clears the zone; with the drift it does not.
  const HazardQuery& q = w.queries.back();
  const std::size_t half = w.queries.front().samples.size();  // no drift measured before step 0
  ASSERT_EQ(q.samples.size(), 2 * half);
  bool commanded_hits = false, drifted_hits = false;
  for (std::size_t i = 0; i < q.samples.size(); ++i) {
    (i < half ? commanded_hits : drifted_hits) |= w.InZone(q.samples[i].x, q.samples[i].y, q.margin_m);
  }
  EXPECT_FALSE(commanded_hits);
  EXPECT_TRUE(drifted_hits);
  EXPECT_NEAR(q.samples[half].x, q.samples[half - 1].x, 1e-9);         // the drifted end ...
  EXPECT_NEAR(q.samples[half].y - q.samples[half - 1].y, 0.05, 1e-9);  // ... 5 cm east
  EXPECT_NEAR(q.samples.back().y, q.samples.front().y, 1e-9);          // back at the start
  // Margin: no spread (steady drift) plus 3 x 2 % of the 25 cm step (the pose sigma is 0).
  EXPECT_NEAR(q.margin_m, 3 * 0.02 * 0.25, 1e-9);

  // The same drive blind: wheel odometry sees no drift, every query passes, and the rover
  // enters the zone.
  SequenceExecutor ex2(FastOptions());
  FakeWorld w2(ex2);
  w2.drift_per_m = {0.0, 0.2};
  SubmitText(ex2, std::string("vo off step 25 cm\n") + text);
  bool entered = false;
  w2.on_iteration = [&](SequenceExecutor&, int) { entered |= w2.InZone(w2.truth.x, w2.truth.y); };
  w2.Run();
  EXPECT_EQ(w2.Final().state, SequenceState::kCompleted);
  EXPECT_TRUE(entered);
  for (const auto& bq : w2.queries) {
    for (const auto& sample : bq.samples) EXPECT_NEAR(sample.y, 0.0, 1e-12);  // no drift seen
  }
}
