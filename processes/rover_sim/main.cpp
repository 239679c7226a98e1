// rover_sim: the simulated rover on its terrain (common/terrain, common/mobility).
// Owns the rover clock in simulation and runs it faster than real time (--rate).
// Reads MOBILITY_COMMAND; writes ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS and
// SIM_TRUTH (truth: read only by tests and evaluation).
// The dead-man (common/mobility/deadman.hpp): a motion stops by itself when the
// sequence_executor's HEARTBEAT and MOBILITY_COMMAND have both been silent for
// mobility.deadman_s (of wall time on a real clock, of rover time in virtual time).
//
// Virtual time (README, "Simulated time"; common/simtime/barrier.hpp): the clock moves
// by sim.tick_s only when every process of --hold-for has finished the current instant
// and this process has every command sent to it, and at most `rate` times as fast as the wall
// clock (`--rate max`: as fast as the barrier allows). A process that holds the clock and
// says nothing for sim.barrier_timeout_s of wall time is declared lost: the rover stops
// and the clock runs on without it, so the executor finds it lost.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "bus/udpm_receiver.hpp"
#include "bus/virtual_time.hpp"
#include "mobility/deadman.hpp"
#include "mobility/rover_simulator.hpp"
#include "simtime/barrier.hpp"
#include "simtime/rate.hpp"
#include "terrain/world.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include <poll.h>

using namespace rover;

namespace {

// sim.rate and --rate: rover seconds per wall second.
using simtime::kMaxRate;
using simtime::kMinRate;

struct SimOptions {
  double rate = 50.0;        // rover seconds per wall second; 0: as fast as the barrier allows
  double step_s = 0.01;      // rover time per simulation step
  double truth_hz = 20.0;    // SIM_TRUTH
  double clock_hz = 50.0;    // ROVER_CLOCK (real time)
  double status_hz = 4.0;    // periodic MOBILITY_STATUS (changes are sent at once)
  std::int64_t start_utime = 1000000;
  double tick_s = 0.1;             // virtual time: one instant of the barrier
  // Virtual time: the longest step the clock takes while the rover stands still and every
  // member is quiet (bus::Process::set_quiet_until): hours parked in minutes. Sensors then
  // report once a step. 0 (the default): every step is tick_s.
  double idle_step_s = 0.0;
  double barrier_timeout_s = 10.0;  // virtual time: wall seconds before a silent process is lost
};

SimOptions LoadSimOptions(const config::ConfigNode& section) {
  SimOptions o;
  section.CheckKeys({"rate", "step_s", "truth_hz", "clock_hz", "status_hz", "start_utime", "tick_s",
                     "barrier_timeout_s", "idle_step_s"});
  section.Get("tick_s", o.tick_s, 0.01, 1.0);
  // At most the members' bus.max_clock_step_s (5 s by default), or they wait for a second
  // clock message to confirm each step.
  section.Get("idle_step_s", o.idle_step_s, 0.0, 5.0);
  section.Get("barrier_timeout_s", o.barrier_timeout_s, 0.1, 600.0);
  if (section.Has("rate") && section["rate"].AsString() == "max") {
    o.rate = 0;
  } else {
    section.Get("rate", o.rate, kMinRate, kMaxRate);  // or max (above)
  }
  section.Get("step_s", o.step_s, 0.001, 0.1);
  section.Get("truth_hz", o.truth_hz, 1.0, 1000.0);
  section.Get("clock_hz", o.clock_hz, 1.0, 1000.0);
  section.Get("status_hz", o.status_hz, 0.5, 100.0);
  section.Get("start_utime", o.start_utime);
  return o;
}

rover_msgs::mobility_status_t ToMsg(const mobility::MobilityStatus& s) {
  rover_msgs::mobility_status_t m{};
  m.utime = s.utime;
  m.command_id = s.command_id;
  m.state = static_cast<std::int8_t>(s.state);
  m.wheel_distance_m = s.wheel_distance_m;
  m.wheel_turn_rad = s.wheel_turn_rad;
  m.detail = s.detail;
  return m;
}

// Waits up to `ms` for a message on the bus or a sync report and handles what has arrived:
// every sync report already there (Drain has a bound, so that a flood cannot hold the
// loop), so that the barrier is judged once per burst of reports rather than once per
// report. What poll found is handled without asking again (handle(), not
// handleTimeout(0), which would select on the descriptor once more: a system call a
// message).
template <class OnReport>
void HandleEither(bus::Bus& bus, bus::UdpmReceiver& sync, const OnReport& on_report, int ms) {
  pollfd fds[2] = {{bus.fileno(), POLLIN, 0}, {sync.fd(), POLLIN, 0}};
  if (::poll(fds, 2, ms) <= 0) return;
  if (fds[0].revents & POLLIN) bus.HandleReady();
  if (fds[1].revents & POLLIN) sync.Drain(on_report);
}

// The sync reports of the set, into the barrier (on the sync bus: bus/virtual_time.hpp).
struct SyncListener {
  simtime::Barrier* barrier;
  const bus::Process* proc;
  void operator()(const std::string& channel, const std::uint8_t* data, std::size_t size, std::int64_t) const {
    if (channel != bus::kSimSyncChannel) return;
    rover_msgs::sim_sync_t m;
    try {
      bus::DecodeAllocationCap cap(16 * size + 65536);
      if (m.decode(data, 0, static_cast<int>(size)) < 0) return;
    } catch (const std::exception&) {
      return;  // a hostile packet on the sync port: not a member's report
    }
    barrier->Report(bus::FromMsg(m), proc->wall_seconds());
  }
};

// --rate R|max: the same range as sim.rate; max is 0.
double ParseRate(const std::string& r) {
  double rate = 0;
  if (!simtime::ParseRate(r, &rate)) {
    throw config::ConfigError("rover_sim: argument --rate: \"" + r + "\": expected " + simtime::kRateExpected);
  }
  return rate;
}

// The simulated rover at --start X,Y,YAW_DEG, or at the world's start.
std::unique_ptr<mobility::RoverSimulator> MakeSimulator(const bus::Process& proc, const terrain::World& world,
                                                        const mobility::MobilityOptions& mobility_options,
                                                        const SimOptions& options) {
  const auto s = proc.option("--start");
  if (!s) return std::make_unique<mobility::RoverSimulator>(world, mobility_options, options.start_utime);
  const auto v = bus::ParseNumberList(*s, 3, "rover_sim: argument --start");
  try {
    return std::make_unique<mobility::RoverSimulator>(world, mobility_options, v[0], v[1], v[2] * M_PI / 180.0,
                                                      options.start_utime);
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError("rover_sim: argument --start: " + std::string(e.what()));
  }
}

// --hold-for's names, less rover_sim itself.
std::vector<std::string> HoldForMembers(const bus::Process& proc) {
  std::vector<std::string> members;
  if (auto names = proc.option("--hold-for")) {
    std::stringstream ss(*names);
    for (std::string n; std::getline(ss, n, ',');)
      if (!n.empty() && n != "rover_sim") members.push_back(n);
  }
  return members;
}

// A MOBILITY_COMMAND as the simulator's command; nothing for a type it does not know.
std::optional<mobility::MotionCommand> ToMotionCommand(const rover_msgs::mobility_command_t& m) {
  mobility::MotionCommand c;
  c.id = m.command_id;
  c.distance_m = m.distance_m;
  c.curvature_per_m = m.curvature_per_m;
  c.turn_rad = m.turn_rad;
  c.speed_mps = m.speed_mps;
  c.turn_rate_rps = m.turn_rate_rps;
  switch (m.type) {
    case rover_msgs::mobility_command_t::TYPE_ARC: c.type = mobility::MotionCommand::Type::kArc; return c;
    case rover_msgs::mobility_command_t::TYPE_TURN: c.type = mobility::MotionCommand::Type::kTurn; return c;
    case rover_msgs::mobility_command_t::TYPE_STOP: c.type = mobility::MotionCommand::Type::kStop; return c;
    default: return std::nullopt;
  }
}

// The rover simulator on the bus: commands in; IMU, odometry, status, truth and the clock
// out; the dead-man between.
class SimOnBus {
 public:
  SimOnBus(bus::Process& proc, const SimOptions& options, mobility::RoverSimulator& sim,
           mobility::Deadman& deadman)
      : proc_(proc), options_(options), sim_(sim), deadman_(deadman),
        next_truth_(sim.utime()), next_status_(sim.utime()) {}

  void OnCommand(const rover_msgs::mobility_command_t& m) {
    deadman_.OnCommanderMessage(proc_.guard_seconds());
    const auto c = ToMotionCommand(m);
    if (!c) {
      PublishFault(m.command_id, "command " + std::to_string(m.command_id) + ": unknown type " +
                                     std::to_string(m.type) + " (expected 0 arc, 1 turn, 2 stop)");
      return;
    }
    try {
      sim_.Command(*c);
    } catch (const std::invalid_argument& e) {
      PublishFault(m.command_id, "command " + std::to_string(m.command_id) + " refused: " + e.what());
    }
  }

  void OnHeartbeat(const rover_msgs::heartbeat_t& hb) { deadman_.OnHeartbeat(hb.process, proc_.guard_seconds()); }

  // One simulation step, the dead-man judged first, and what it produced on the bus. With
  // `hold` (an idle stride) only the newest sample of each kind is kept, for FlushHeld.
  void Step(bool hold = false) {
    if (const auto why = deadman_.Check(sim_.moving(), proc_.guard_seconds())) {
      std::cerr << "rover_sim: command " << sim_.status().command_id << ": " << *why << "\n";
      sim_.Halt(*why);
    }
    const mobility::StepOutput out = sim_.Step(options_.step_s);
    for (const auto& s : out.imu) hold ? void(held_imu_ = s) : PublishImu(s);
    for (const auto& s : out.odometry) hold ? void(held_odometry_ = s) : PublishOdometry(s);
    for (const auto& s : out.status) proc_.bus().Publish(channels::kMobilityStatus, ToMsg(s));
    const std::int64_t now = sim_.utime();
    if (now >= next_status_) {
      auto st = sim_.status();
      st.utime = now;
      if (hold) {
        held_status_ = st;
      } else {
        proc_.bus().Publish(channels::kMobilityStatus, ToMsg(st));
      }
      next_status_ += Period(options_.status_hz);
    }
    if (now >= next_truth_) {
      if (hold) {
        truth_held_ = true;
      } else {
        PublishTruth();
      }
      next_truth_ += Period(options_.truth_hz);
    }
  }

  // The end of an idle stride: the newest of each sensor's samples, as a driver that
  // sleeps with the rover reports on waking.
  void FlushHeld() {
    if (held_imu_) PublishImu(*held_imu_);
    if (held_odometry_) PublishOdometry(*held_odometry_);
    if (held_status_) proc_.bus().Publish(channels::kMobilityStatus, ToMsg(*held_status_));
    if (truth_held_) PublishTruth();
    held_imu_.reset();
    held_odometry_.reset();
    held_status_.reset();
    truth_held_ = false;
  }

  void PublishClock(std::int64_t now, const simtime::Cut* cut = nullptr) {
    rover_msgs::rover_clock_t m{};
    if (cut) bus::SetCut(*cut, &m);
    m.utime = now;
    // Virtual time has no fixed ratio to the wall clock (the pacing is only a ceiling): 0,
    // so that a run at 50x and one as fast as possible publish the same bytes.
    m.rate = proc_.virtual_time() ? 0.0 : options_.rate;
    m.mode = proc_.virtual_time() ? rover_msgs::rover_clock_t::MODE_VIRTUAL : rover_msgs::rover_clock_t::MODE_REAL;
    proc_.bus().Publish(channels::kClock, m);
  }

  static std::int64_t Period(double hz) { return static_cast<std::int64_t>(1e6 / hz); }

  bus::Process& proc() { return proc_; }
  const SimOptions& options() const { return options_; }
  mobility::RoverSimulator& sim() { return sim_; }

 private:
  void PublishFault(std::int64_t command_id, const std::string& detail) {
    rover_msgs::mobility_status_t st{};
    st.utime = sim_.utime();
    st.command_id = command_id;
    st.state = rover_msgs::mobility_status_t::STATE_FAULT;
    st.detail = detail;
    proc_.bus().Publish(channels::kMobilityStatus, st);
  }
  void PublishImu(const mobility::ImuSample& s) {
    rover_msgs::imu_t m{};
    m.utime = s.utime;
    bus::QuaternionToArray(s.q_site_rover, m.orientation);
    for (int i = 0; i < 3; ++i) {
      m.angular_rate[i] = s.angular_rate_rps[i];
      m.accel[i] = s.accel_mps2[i];
    }
    proc_.bus().Publish(channels::kImu, m);
  }
  void PublishOdometry(const mobility::WheelOdometrySample& s) {
    rover_msgs::wheel_odometry_t m{};
    m.utime = s.utime;
    m.num_wheels = static_cast<std::int32_t>(s.wheel_distance_m.size());
    m.wheel_distance_m.assign(s.wheel_distance_m.begin(), s.wheel_distance_m.end());
    m.distance_m = s.distance_m;
    m.curvature_per_m = s.curvature_per_m;
    m.turning_in_place = s.turning_in_place;
    proc_.bus().Publish(channels::kWheelOdometry, m);
  }
  void PublishTruth() {
    const auto t = sim_.Truth();
    rover_msgs::sim_truth_t m{};
    m.utime = t.utime;
    for (int i = 0; i < 3; ++i) {
      m.position[i] = t.position[i];
      m.rpy[i] = t.rpy[i];
    }
    bus::QuaternionToArray(t.q_site_rover, m.orientation);
    m.odometer_m = t.odometer_m;
    m.slip = t.slip;
    m.soil = terrain::SoilName(t.soil);
    m.command_id = t.command_id;
    proc_.bus().Publish(channels::kSimTruth, m);
  }

  bus::Process& proc_;
  const SimOptions options_;
  mobility::RoverSimulator& sim_;
  mobility::Deadman& deadman_;
  std::int64_t next_truth_, next_status_;
  std::optional<mobility::ImuSample> held_imu_;
  std::optional<mobility::WheelOdometrySample> held_odometry_;
  std::optional<mobility::MobilityStatus> held_status_;
  bool truth_held_ = false;
};

// ---- Virtual time: one instant at a time, when the whole set has finished it. ----
class VirtualClock {
 public:
  // rover_sim is a member too: the clock must also wait for the commands sent to it.
  VirtualClock(SimOnBus& rover, std::vector<std::string> members)
      : rover_(rover), proc_(rover.proc()), options_(rover.options()),
        barrier_(WithSelf(std::move(members)), options_.barrier_timeout_s, "rover_sim"),
        sync_bus_(bus::SyncUrl(proc_.bus().url()), "sync bus"), listener_{&barrier_, &proc_},
        tick_us_(static_cast<std::int64_t>(std::llround(options_.tick_s * 1e6))) {
  }

  int Run() {
    HoldUntilAllHeard();
    t_ = rover_.sim().utime();
    rover_start_ = t_;
    wall_start_ = proc_.wall_seconds();
    next_heartbeat_ = t_;
    BeginInstant();
    tick_wall_ = proc_.wall_seconds();
    last_note_ = tick_wall_;
    last_announce_ = tick_wall_;
    while (!proc_.stopping()) {
      if (!WaitUntilInstantFinished()) break;  // stopped while waiting: the instant is not finished
      if (!PaceToRate()) break;
      NextInstant();
    }
    return 0;
  }

 private:
  static std::vector<std::string> WithSelf(std::vector<std::string> members) {
    members.push_back("rover_sim");
    return members;
  }

  void HoldUntilAllHeard() {
    const double hold_start = proc_.wall_seconds();
    barrier_.Report(proc_.bus().SyncState("rover_sim", -1, false), proc_.wall_seconds());
    while (!barrier_.AllHeard() && !proc_.stopping()) {
      HandleEither(proc_.bus(), sync_bus_, listener_, 50);
      if (proc_.wall_seconds() - hold_start > 30) {
        throw std::runtime_error("--hold-for: no sync report within 30 s from: " + barrier_.Holding(-1));
      }
    }
  }

  // The clock carries the cut (simtime/cut.hpp): what the members had published when they
  // finished the last instant, and what this process has sent for the new one.
  simtime::Cut CutNow() {
    simtime::Cut cut = barrier_.Published();
    const auto own = bus::PublisherId("rover_sim");
    for (const auto& [channel, count] : proc_.bus().SyncState("rover_sim", t_, false).published) {
      cut.Set(channel, own, count);
    }
    cut.Set(channels::kClock, own, 0);  // the clock is acted on at once, never batched
    return cut;
  }

  void BeginInstant() {
    proc_.ObserveTime(t_);
    const simtime::Cut cut = CutNow();
    rover_.PublishClock(t_, &cut);
    if (t_ >= next_heartbeat_) {
      proc_.PublishHeartbeat();
      next_heartbeat_ = t_ + static_cast<std::int64_t>(0.25e6);
    }
  }

  // 1. Everyone has finished instant t, and what was sent to rover_sim has come. False:
  // stopped meanwhile.
  bool WaitUntilInstantFinished() {
    double last_pass = proc_.wall_seconds();
    while (!proc_.stopping()) {
      // A pass long after the last (this process was stopped or starved): the others'
      // silence meanwhile is not theirs to answer for.
      if (proc_.wall_seconds() - last_pass > 1.0) tick_wall_ = proc_.wall_seconds();
      last_pass = proc_.wall_seconds();
      auto own = proc_.bus().SyncState("rover_sim", t_, false);
      own.quiet_until = rover_.sim().moving() ? 0 : bus::Process::kQuietForGood;
      barrier_.Report(own, proc_.wall_seconds());
      if (barrier_.Finished(t_)) return true;
      DeclareLost();
      AnnounceAgainForTheFarBehind();
      if (proc_.wall_seconds() - std::max(last_note_, tick_wall_) > 10.0) {
        std::cerr << "rover_sim: the clock waits at " << t_ << ": " << barrier_.Holding(t_) << "\n";
        last_note_ = proc_.wall_seconds();
      }
      // Woken by any report or message; the timeout serves only the wall-time rules
      // above (0.5 s and more), so it need not spin.
      HandleEither(proc_.bus(), sync_bus_, listener_, 20);
    }
    return false;
  }

  // The one wall-time rule: a member silent for sim.barrier_timeout_s is lost, and the
  // rover stops.
  void DeclareLost() {
    std::vector<std::string> forgiven;
    const auto lost = barrier_.DeclareLost(t_, proc_.wall_seconds(), tick_wall_, &forgiven);
    for (const auto& line : forgiven) {
      std::cerr << "rover_sim: messages lost on the way (" << line << ") after " << options_.barrier_timeout_s
                << " s of wall time: forgiven, the clock runs on\n";
    }
    for (const auto& name : lost) {
      const std::string why = "process " + name + " lost: it held the clock for " +
                              std::to_string(options_.barrier_timeout_s) +
                              " s of wall time without a word (sim.barrier_timeout_s)";
      std::cerr << "rover_sim: " << why << "; the rover stops and the clock runs on without it\n";
      rover_.sim().Halt(why);
    }
  }

  // A member back from a freeze may have lost the clock messages in between, and takes a
  // jump of more than bus.max_clock_step_s only when the next clock message confirms it:
  // while such a member holds the clock, the instant is announced again (twice a second).
  // Never in a run without a fault, whose log it would change.
  void AnnounceAgainForTheFarBehind() {
    if (proc_.wall_seconds() - std::max(last_announce_, tick_wall_) > 0.5 &&
        barrier_.FarBehind(t_, static_cast<std::int64_t>(1e6))) {
      const simtime::Cut cut = CutNow();
      rover_.PublishClock(t_, &cut);
      last_announce_ = proc_.wall_seconds();
    }
  }

  // 2. No faster than `rate` times the wall clock. False: stopped meanwhile.
  bool PaceToRate() {
    if (options_.rate <= 0) return true;
    const double due = wall_start_ + (t_ + NextStep() - rover_start_) * 1e-6 / options_.rate;
    while (!proc_.stopping() && proc_.wall_seconds() < due) {
      HandleEither(proc_.bus(), sync_bus_, listener_, std::max(1, static_cast<int>((due - proc_.wall_seconds()) * 1000)));
    }
    return !proc_.stopping();
  }

  // How far the clock moves next: one tick, or an idle stride when the rover stands still
  // and every member has nothing of its own to do before then (Barrier::QuietUntil), on
  // the tick grid and at most sim.idle_step_s.
  std::int64_t NextStep() const {
    const std::int64_t idle_us = static_cast<std::int64_t>(std::llround(options_.idle_step_s * 1e6));
    if (idle_us <= tick_us_ || rover_.sim().moving()) return tick_us_;
    const std::int64_t quiet = barrier_.QuietUntil();
    if (quiet <= t_ + tick_us_) return tick_us_;
    const std::int64_t step = std::min(idle_us, quiet - t_);
    return std::max(tick_us_, step / tick_us_ * tick_us_);
  }

  // 3. The next instant: what came during this one acts first (commands, heartbeats).
  void NextInstant() {
    const std::int64_t step = NextStep();
    proc_.bus().SealBatch(t_ + step);
    proc_.bus().DispatchBatch();
    const std::int64_t until = t_ + step;
    // A command from outside the set (it said nothing of being quiet) may start a motion in
    // a stride: that stride's samples go out one by one as in any instant.
    const bool stride = step > tick_us_ && !rover_.sim().moving();
    while (rover_.sim().utime() < until) rover_.Step(stride);
    if (stride) rover_.FlushHeld();
    t_ = rover_.sim().utime();
    BeginInstant();
    tick_wall_ = proc_.wall_seconds();
  }

  SimOnBus& rover_;
  bus::Process& proc_;
  const SimOptions& options_;
  simtime::Barrier barrier_;
  bus::UdpmReceiver sync_bus_;
  SyncListener listener_;
  const std::int64_t tick_us_;
  std::int64_t t_ = 0, rover_start_ = 0, next_heartbeat_ = 0;
  double wall_start_ = 0, tick_wall_ = 0, last_note_ = 0, last_announce_ = 0;
};

// ---- Real time: the clock runs at `rate` times the wall clock, as on a rover. ----
int RunRealTime(SimOnBus& rover, const std::set<std::string>& waiting) {
  bus::Process& proc = rover.proc();
  const SimOptions& options = rover.options();
  const auto hold_start = std::chrono::steady_clock::now();
  double next_hold_heartbeat_wall = 0;
  while (!waiting.empty() && !proc.stopping()) {
    // Once a wall second, as everywhere: every heartbeat on the bus (this one included)
    // wakes Handle(), so sending one per wake-up floods the bus.
    if (proc.wall_seconds() >= next_hold_heartbeat_wall) {
      proc.PublishHeartbeat();
      next_hold_heartbeat_wall = proc.wall_seconds() + 1.0;
    }
    proc.bus().Handle(200);
    if (std::chrono::steady_clock::now() - hold_start > std::chrono::seconds(30)) {
      std::string list;
      for (const auto& n : waiting) list += " " + n;
      throw std::runtime_error("--hold-for: no heartbeat within 30 s from:" + list);
    }
  }
  // As the rover's hardware (rover time is the system clock: bus.time system) rover_sim
  // publishes what real drivers do and no clock; its time is the system clock's, paced at
  // rate 1.
  const bool hardware = proc.time_mode() == bus::Process::TimeMode::kSystemClock;
  std::int64_t next_clock = rover.sim().utime();
  const auto wall_start = std::chrono::steady_clock::now();
  const std::int64_t rover_start = rover.sim().utime();
  double next_heartbeat_wall = 0;
  while (!proc.stopping()) {
    while (proc.bus().Handle(0)) {
    }
    rover.Step();
    const std::int64_t now = rover.sim().utime();
    proc.ObserveTime(now);
    if (!hardware && now >= next_clock) {
      rover.PublishClock(now);
      next_clock += SimOnBus::Period(options.clock_hz);
    }
    if (proc.wall_seconds() >= next_heartbeat_wall) {
      proc.PublishHeartbeat();
      next_heartbeat_wall = proc.wall_seconds() + 0.25;
    }
    // Pace rover time at `rate` times the wall clock.
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const double ahead_s = (now - rover_start) * 1e-6 / options.rate - wall;
    if (ahead_s > 0) {
      proc.bus().Handle(static_cast<int>(ahead_s * 1000.0));
      const double wall2 = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      const double still = (now - rover_start) * 1e-6 / options.rate - wall2;
      if (still > 0) std::this_thread::sleep_for(std::chrono::duration<double>(still));
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("rover_sim", [&]() -> int {
    bus::Process proc("rover_sim",
                      "The simulated rover: arcs and turns on a height field with slip, IMU and\n"
                      "wheel encoders. Owns the rover clock. Reads MOBILITY_COMMAND; writes\n"
                      "ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS, SIM_TRUTH.\n"
                      "Config: `mobility:`, `sensors:` and `sim:` sections (configs/rover.yaml).\n"
                      "In virtual time ($ROVER_TIME=virtual or bus.time) the clock waits for every\n"
                      "process of --hold-for to finish each instant (README, \"Simulated time\").",
                      argc, argv,
                      {{"--world", "FILE", "world YAML (configs/worlds/)"},
                       {"--start", "X,Y,YAW_DEG", "start pose (default: the world's start)"},
                       {"--rate", "R|max", "rover seconds per wall second (overrides sim.rate); max: as fast as the barrier allows (virtual time)"},
                       {"--hold-for", "NAMES", "comma-separated processes the clock waits for: before it starts, and in virtual time at every instant"}});
    SimOptions options = LoadSimOptions(proc.config()["sim"]);
    if (auto r = proc.option("--rate")) options.rate = ParseRate(*r);
    if (proc.time_mode() == bus::Process::TimeMode::kSystemClock) {
      // The rover's hardware on the system clock: the simulated rover's time is the
      // system clock's, at its pace (sim.rate is a simulation's pace, not taken here).
      if (proc.option("--rate") && options.rate != 1.0) {
        throw config::ConfigError("rover_sim: argument --rate " + *proc.option("--rate") +
                                  " with rover time on the system clock (bus.time: system): as the rover's hardware "
                                  "rover_sim runs at the wall clock's pace (expected --rate 1)");
      }
      options.rate = 1.0;
      options.start_utime = bus::RoverClock::SystemUtime();
    }
    if (options.rate <= 0 && !proc.virtual_time()) {
      throw config::ConfigError("rover_sim: rate max (0) needs virtual time (expected $ROVER_TIME=virtual or bus.time: virtual, or a rate > 0)");
    }
    const auto world_path = proc.option("--world");
    if (!world_path) throw config::ConfigError("rover_sim: missing argument --world FILE (expected a world YAML)");
    const terrain::World world(terrain::WorldOptions::LoadFile(*world_path));
    const auto mobility_options = mobility::MobilityOptions::Load(proc.config());
    mobility::Deadman deadman(mobility::LoadDeadmanOptions(proc.config()));
    const auto sim = MakeSimulator(proc, world, mobility_options, options);
    proc.ObserveTime(sim->utime());
    proc.AnnounceTime();

    SimOnBus rover(proc, options, *sim, deadman);
    proc.bus().Subscribe<rover_msgs::mobility_command_t>(
        channels::kMobilityCommand, [&](const rover_msgs::mobility_command_t& m) { rover.OnCommand(m); });
    const std::vector<std::string> members = HoldForMembers(proc);
    std::set<std::string> waiting(members.begin(), members.end());  // real time: heartbeats before start
    proc.bus().Subscribe<rover_msgs::heartbeat_t>(
        channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
          waiting.erase(hb.process);
          rover.OnHeartbeat(hb);
        }, 1000);

    proc.DeclarePublications({{channels::kClock}, {channels::kImu}, {channels::kWheelOdometry},
                              {channels::kMobilityStatus}, {channels::kSimTruth}});
    if (proc.virtual_time()) return VirtualClock(rover, members).Run();
    return RunRealTime(rover, waiting);
  });
}
