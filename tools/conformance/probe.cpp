#include "conformance/probe.hpp"

#include "bus/channels.hpp"
#include "bus/guard.hpp"
#include "bus/signing.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace rover::conformance {

namespace {

using rover_msgs::mobility_command_t;
using rover_msgs::mobility_status_t;

// LCM 1.3.1 subscribes member functions only: one object per subscription.
struct RawHandler {
  std::function<void(const lcm::ReceiveBuffer*, const std::string&)> on;
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { on(rbuf, channel); }
};

// A key that is not the deployment's (fixed: any other key is as wrong, and a fixed one
// keeps the kit's commands the same from run to run).
auth::Key NotTheDeploymentsKey() {
  std::vector<std::uint8_t> bytes(auth::kMinKeyBytes);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(0x5a ^ (i * 37));
  return auth::Key::FromBytes(std::move(bytes), "the conformance kit's wrong key");
}

// A heartbeat the kit sends as the commander says so in its detail, so that another
// commander on the bus (a running sequence_executor) can be told from the kit.
constexpr const char* kOwnHeartbeat = "rover_conformance";

}  // namespace

Probe::Probe(bus::Bus& bus, ProbeOptions options) : bus_(bus), options_(std::move(options)) {
  next_command_id_ = (std::chrono::system_clock::now().time_since_epoch().count() / 1000000000) % 1000000 * 100;
  Listen<rover_msgs::rover_clock_t>(channels::kClock, [this](const rover_msgs::rover_clock_t& m, const Stamp&) {
    if (static_cast<std::uint32_t>(static_cast<std::uint64_t>(m.pub_seq) >> 32) != bus::PublisherId(options_.time_source))
      return;
    if (m.mode == rover_msgs::rover_clock_t::MODE_VIRTUAL) {
      setup_problem_ = "the bus's clock (" + options_.time_source +
                       ") runs in virtual time; run the driver on a real clock (ROVER_TIME=real, or the "
                       "deployment's time: real)";
      return;
    }
    clock_ = m;
    clock_at_ = std::chrono::steady_clock::now();
  });
  Listen<mobility_status_t>(channels::kMobilityStatus, [this](const mobility_status_t& m, const Stamp& at) {
    if (recording_mobility_) mobility_.statuses.push_back({at, m});
  });
  Listen<rover_msgs::heartbeat_t>(channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& m, const Stamp& at) {
    if (m.process == options_.commander && m.detail != kOwnHeartbeat && other_commander_.empty()) {
      other_commander_ = m.process;
    }
    if (driver_name_.empty() &&
        (options_.driver.empty() ? (m.process == "rover_sim" || m.process == "mobility_driver")
                                 : m.process == options_.driver)) {
      driver_name_ = m.process;
    }
    if (recording_mobility_ && m.process == driver_name_) mobility_.driver_heartbeats.push_back({at, m});
    if (recording_camera_ && m.process == options_.capture_process) camera_.capture_heartbeats.push_back({at, m});
  });
  Listen<rover_msgs::imu_t>(channels::kImu, [this](const rover_msgs::imu_t& m, const Stamp& at) {
    if (recording_imu_) imu_.push_back({at, m});
  });
  Listen<rover_msgs::wheel_odometry_t>(channels::kWheelOdometry,
                                       [this](const rover_msgs::wheel_odometry_t& m, const Stamp& at) {
                                         if (recording_odometry_ || recording_mobility_) mobility_.odometry.push_back({at, m});
                                       });
  Listen<rover_msgs::stereo_frame_t>(channels::kStereoFrame, [this](const rover_msgs::stereo_frame_t& m, const Stamp& at) {
    if (recording_camera_) camera_.frames.push_back({at, m});
  });
}

template <class Msg>
void Probe::Listen(const std::string& channel, std::function<void(const Msg&, const Stamp&)> on_message) {
  auto handler = std::make_unique<RawHandler>();
  handler->on = [this, on_message, channel](const lcm::ReceiveBuffer* rbuf, const std::string&) {
    Msg m;
    try {
      // As the Bus does (bus/guard.hpp): a lying length field cannot allocate gigabytes.
      bus::DecodeAllocationCap cap(16 * static_cast<std::size_t>(rbuf->data_size) + 65536);
      if (rbuf->data_size > bus::MaxPayloadBytes(channel) ||
          m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
        return;
      }
    } catch (const std::exception&) {
      return;
    }
    Stamp at;
    at.wall_s = Wall();
    at.clock_utime = RoverNow();
    if constexpr (requires { m.utime; }) at.utime = m.utime;
    on_message(m, at);
  };
  // Subscribed on LCM directly, which the Bus's kernel filter does not know of: off, so
  // that the kernel drops nothing this probe listens to (bus/kernel_filter.hpp).
  bus_.FilterInKernel(false);
  lcm::Subscription* sub = bus_.lcm().subscribe(channel, &RawHandler::OnMessage, handler.get());
  if (sub == nullptr) throw std::runtime_error("LCM subscribe failed on channel " + channel);
  sub->setQueueCapacity(1000);
  raw_.push_back(std::shared_ptr<void>(std::move(handler)));
}

std::int64_t Probe::RoverNow() const {
  if (clock_) {
    const double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_at_).count();
    return clock_->utime + static_cast<std::int64_t>(std::llround(since * clock_->rate * 1e6));
  }
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double Probe::Wall() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Probe::Spin(double seconds, const std::function<bool()>& done) {
  const double until = Wall() + seconds;
  while (Wall() < until && !(done && done())) {
    if (commander_alive_ && Wall() >= next_heartbeat_s_) {
      rover_msgs::heartbeat_t hb{};
      hb.utime = RoverNow();
      hb.process = options_.commander;
      hb.seq = heartbeat_seq_++;
      hb.detail = kOwnHeartbeat;
      bus_.Publish(channels::kHeartbeat, hb);
      last_heartbeat_s_ = Wall();
      next_heartbeat_s_ = last_heartbeat_s_ + 0.25;  // as sequence_executor: 4 a second
    }
    const int ms = static_cast<int>(std::max(1.0, std::min(20.0, (until - Wall()) * 1000.0)));
    bus_.lcm().handleTimeout(ms);
  }
}

std::int64_t Probe::Command(std::int8_t type, double distance_m, double curvature, double turn_rad, double speed,
                            double turn_rate, bus::Bus* via) {
  mobility_command_t c{};
  c.utime = RoverNow();
  c.command_id = ++next_command_id_;
  c.type = type;
  c.distance_m = distance_m;
  c.curvature_per_m = curvature;
  c.turn_rad = turn_rad;
  c.speed_mps = speed;
  c.turn_rate_rps = turn_rate;
  mobility_.commands.push_back({c.command_id, type, distance_m, curvature, turn_rad, speed, turn_rate, Wall()});
  (via ? *via : bus_).Publish(channels::kMobilityCommand, c);
  return c.command_id;
}

bool Probe::Ended(std::int64_t id) const {
  for (const auto& s : mobility_.statuses)
    if (s.msg.command_id == id && s.msg.state >= mobility_status_t::STATE_DONE) return true;
  return false;
}

bool Probe::Moving(std::int64_t id) const {
  for (const auto& s : mobility_.statuses)
    if (s.msg.command_id == id && s.msg.state == mobility_status_t::STATE_MOVING) return true;
  return false;
}

void Probe::WaitForClock() {
  // A simulator's clock comes 50 times a second: a bus with none for a second has none,
  // and rover time is the system clock.
  Spin(1.0, [&] { return clock_.has_value(); });
}

void Probe::RunMobility(const MobilityLimits& limits, Report& report) {
  WaitForClock();
  recording_mobility_ = true;
  commander_alive_ = true;
  Spin(2.0);  // at rest: the status stream and the driver's heartbeat
  if (!other_commander_.empty()) {
    report.Fail("mobility.deadman.alive", "no other " + options_.commander + " on the bus (stop it for the kit)",
                "heartbeats from another " + other_commander_);
  }
  // Each motion is short and slow, so that a bench rover moves at most a few centimetres.
  const std::int64_t idle_stop = Command(mobility_command_t::TYPE_STOP, 0, 0, 0, 0, 0);
  Spin(1.5);
  const std::int64_t arc = Command(mobility_command_t::TYPE_ARC, 0.10, 0, 0, 0.05, 0);
  Spin(2.0 * 0.10 / 0.05 + 2.0, [&] { return Ended(arc); });
  Spin(0.3);
  const std::int64_t turn = Command(mobility_command_t::TYPE_TURN, 0, 0, 0.10, 0, 0.1);
  Spin(2.0 * 0.10 / 0.1 + 2.0, [&] { return Ended(turn); });
  Spin(0.3);

  // STOP during a motion.
  const std::int64_t long_arc = Command(mobility_command_t::TYPE_ARC, 2.0, 0, 0, 0.05, 0);
  Spin(limits.answer_s, [&] { return Moving(long_arc); });
  Spin(1.0);
  const std::int64_t stop = Command(mobility_command_t::TYPE_STOP, 0, 0, 0, 0, 0);
  Spin(2.0);

  // The dead-man: alive past the limit, then silent.
  const std::int64_t watched = Command(mobility_command_t::TYPE_ARC, 2.0, 0, 0, 0.05, 0);
  Spin(limits.deadman_s + 1.0);
  commander_alive_ = false;
  // Silent since the last heartbeat sent, not since now: on a busy machine this loop may
  // have come round late, and the driver's dead-man counts from what it last heard (a
  // driver seen stopping 1.25 s after "now" was 1.5 s after the last heartbeat).
  mobility_.silent_from_s = last_heartbeat_s_ > 0 ? last_heartbeat_s_ : Wall();
  Spin(limits.deadman_s + limits.deadman_margin_s + 1.0, [&] { return Ended(watched); });
  Spin(0.3);
  mobility_.silent_until_s = Wall();
  commander_alive_ = true;
  next_heartbeat_s_ = 0;
  const std::int64_t cleanup = Command(mobility_command_t::TYPE_STOP, 0, 0, 0, 0, 0);
  Spin(1.5);

  // Bad commands, each at rest.
  const std::int64_t curved = Command(mobility_command_t::TYPE_ARC, 0.10, 1000.0, 0, 0.05, 0);
  Spin(1.5);
  const std::int64_t negative = Command(mobility_command_t::TYPE_ARC, 0.10, 0, 0, -0.05, 0);
  Spin(1.5);
  const std::int64_t nan = Command(mobility_command_t::TYPE_ARC, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0.05, 0);
  Spin(1.5);
  const std::int64_t unknown = Command(7, 0.10, 0, 0, 0.05, 0);
  Spin(1.5);

  // With the deployment's key: commands anyone on the network could send, which a driver
  // must not obey. An ARC of 0.10 m unsigned (from a bus with no key), then one signed
  // with a key that is not the deployment's.
  std::int64_t unsigned_arc = 0, forged_arc = 0;
  if (bus_.has_auth()) {
    bus::Bus plain(bus_.url());
    plain.set_publisher("rover_conformance_unsigned");
    unsigned_arc = Command(mobility_command_t::TYPE_ARC, 0.10, 0, 0, 0.05, 0, &plain);
    Spin(1.5);
    bus::Bus forged(bus_.url());
    forged.set_publisher("rover_conformance_forged");
    forged.set_auth(bus::MakeBusAuth(NotTheDeploymentsKey(), "rover_conformance"));
    forged_arc = Command(mobility_command_t::TYPE_ARC, 0.10, 0, 0, 0.05, 0, &forged);
    Spin(1.5);
  }
  Command(mobility_command_t::TYPE_STOP, 0, 0, 0, 0, 0);
  Spin(0.5);
  mobility_.end_wall_s = Wall();
  recording_mobility_ = false;
  (void)cleanup;

  CheckStatusStream(mobility_, limits, report);
  CheckIdleStop(mobility_, idle_stop, limits, report);
  CheckMotion(mobility_, arc, limits, report);
  CheckMotion(mobility_, turn, limits, report);
  CheckStop(mobility_, long_arc, stop, limits, report);
  CheckDeadman(mobility_, watched, limits, report);
  CheckRefusal(mobility_, curved, "mobility.bad.curvature", false, limits, report);
  CheckRefusal(mobility_, negative, "mobility.bad.speed", false, limits, report);
  CheckRefusal(mobility_, nan, "mobility.bad.not_finite", true, limits, report);
  CheckRefusal(mobility_, unknown, "mobility.bad.type", true, limits, report);
  if (unsigned_arc != 0) {
    CheckNotObeyed(mobility_, unsigned_arc, "mobility.auth.unsigned", "unsigned", report);
    CheckNotObeyed(mobility_, forged_arc, "mobility.auth.wrong_key", "signed with another key", report);
  }
}

DriveRecord Probe::Drive() {
  // As the mobility check does: the kit is the commander while it drives.
  recording_mobility_ = true;
  commander_alive_ = true;
  next_heartbeat_s_ = 0;
  Spin(0.5);
  DriveRecord d;
  d.arc_m = 0.10;
  d.arc_from_s = Wall();
  const std::int64_t arc = Command(rover_msgs::mobility_command_t::TYPE_ARC, d.arc_m, 0, 0, 0.05, 0);
  Spin(2.0 * d.arc_m / 0.05 + 2.0, [&] { return Ended(arc); });
  Spin(0.3);
  d.arc_to_s = Wall();
  d.turn_rad = 0.10;
  d.turn_from_s = Wall();
  const std::int64_t turn = Command(rover_msgs::mobility_command_t::TYPE_TURN, 0, 0, d.turn_rad, 0, 0.1);
  Spin(2.0 * d.turn_rad / 0.1 + 2.0, [&] { return Ended(turn); });
  Spin(0.3);
  d.turn_to_s = Wall();
  Spin(0.3);  // samples after the turn, to judge it by
  commander_alive_ = false;
  recording_mobility_ = false;
  return d;
}

void Probe::RunImu(const ImuLimits& limits, Report& report) {
  WaitForClock();
  recording_imu_ = true;
  Spin(options_.listen_s);
  const auto at_rest = imu_;
  if (options_.drive) {
    const DriveRecord d = Drive();
    CheckImuDrive(imu_, d, report);
  }
  recording_imu_ = false;
  CheckImu(at_rest, limits, report);
}

void Probe::RunWheelOdometry(const WheelOdometryLimits& limits, Report& report) {
  WaitForClock();
  recording_odometry_ = true;
  Spin(options_.listen_s);
  const auto at_rest = mobility_.odometry;
  if (options_.drive) {
    const DriveRecord d = Drive();
    CheckWheelOdometryDrive(mobility_.odometry, d, report);
  }
  recording_odometry_ = false;
  CheckWheelOdometry(at_rest, limits, report);
}

void Probe::RunCamera(const CameraLimits& limits, Report& report) {
  WaitForClock();
  recording_camera_ = true;
  Spin(1.0);  // the capture process's heartbeat
  for (int i = 0; i < options_.requests; ++i) {
    rover_msgs::capture_request_t r{};
    r.utime = RoverNow();
    r.frame_id = ++next_command_id_;
    r.purpose = "vo";
    camera_.requests.push_back({r.frame_id, r.purpose, r.utime, Wall()});
    const double sent = Wall();
    bus_.Publish(channels::kCaptureRequest, r);
    Spin(limits.answer_s, [&] {
      for (const auto& f : camera_.frames)
        if (f.msg.frame_id == r.frame_id) return true;
      for (const auto& h : camera_.capture_heartbeats)
        if (h.at.wall_s > sent + 0.3 && h.msg.state != rover_msgs::heartbeat_t::STATE_OK) return true;
      return false;
    });
    Spin(0.3);
  }
  camera_.end_wall_s = Wall();
  recording_camera_ = false;
  CheckCamera(camera_, limits, report);
}

}  // namespace rover::conformance
