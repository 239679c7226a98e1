// rover_conformance NAME: checks a running driver against its contract (docs/HARDWARE.md,
// "Contracts"; ./rover conformance NAME --lcm-url URL). One line per failed rule, naming the
// rule, what was expected and what was seen; exit code 1 when any rule failed, 2 on a bad
// argument or a bus the kit cannot run on.
#include "bus/process.hpp"
#include "conformance/probe.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>

using namespace rover;

namespace {

using conformance::Num;

const char* kSummary =
    "Checks a running driver against its contract (docs/HARDWARE.md, \"Contracts\"). NAME is one of:\n"
    "  mobility        MOBILITY_COMMAND in, MOBILITY_STATUS out: status rate, units, timestamps, the\n"
    "                  answer to STOP, the dead-man, bad commands. MOVES THE ROVER a few centimetres:\n"
    "                  lift the wheels or clear the bench. No sequence_executor may run meanwhile.\n"
    "                  With --key (keys on): also that an unsigned command and one signed with\n"
    "                  another key are not obeyed.\n"
    "  imu             IMU: rate, units, frame (Z down), timestamps; the rover at rest (--drive: and\n"
    "                  in a turn, which moves the rover)\n"
    "  wheel_odometry  WHEEL_ODOMETRY: rate, fields, timestamps at rest; --drive: units and wheel signs\n"
    "  camera          CAPTURE_REQUEST in, STEREO_FRAME out: sizes, pairing, timestamps (each image's\n"
    "                  exposure within --pair-tolerance-ms of the other's), status on failure\n"
    "usage: rover_conformance NAME [options]. Prints one line per rule (ok or FAIL: expected; seen);\n"
    "exit code 0 when every rule held, 1 when one failed, 2 on a bad argument.";

double NumberOption(const bus::Process& proc, const std::string& flag, double fallback, double lo, double hi) {
  const auto text = proc.option(flag);
  if (!text) return fallback;
  const double v = bus::ParseNumberList(*text, 1, "rover_conformance: argument " + flag)[0];
  if (!(v >= lo && v <= hi)) {
    throw config::ConfigError("rover_conformance: argument " + flag + ": \"" + *text + "\": expected a number in [" +
                              Num(lo, 2) + ", " + Num(hi, 2) + "]");
  }
  return v;
}


// The capture process's own pairing tolerance, as its config gives it: that of the
// hardware source it uses (with that source's default), else 2 ms.
double PairingTolerance(const config::ConfigNode& capture) {
  std::string source = "sim";
  capture.Get("source", source);
  double ms = source == "gstreamer" ? 5.0 : 2.0;  // camera_hw's defaults (camera_options.hpp)
  if (source == "genicam" || source == "gstreamer") capture[source].Get("pairing_tolerance_ms", ms, 0.0, 10000.0);
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("rover_conformance", [&]() -> int {
    // NAME comes first; the options after it are the Process's.
    std::string name;
    std::vector<char*> args = {argv[0]};
    for (int i = 1; i < argc; ++i) {
      if (i == 1 && argv[i][0] != '-') {
        name = argv[i];
      } else {
        args.push_back(argv[i]);
      }
    }
    bus::Process proc("rover_conformance", kSummary, static_cast<int>(args.size()), args.data(),
                      {{"--deadman-s", "S", "mobility: the driver's dead-man limit (default mobility.deadman_s, else 1.5)"},
                       {"--answer-s", "S", "mobility: wall seconds a command's first status may take (default 1)"},
                       {"--time-source", "NAME", "whose ROVER_CLOCK is rover time (default bus.time_source, else rover_sim); without one on the bus, the system clock"},
                       {"--commander", "NAME", "mobility: the process whose heartbeat the dead-man watches (default sequence_executor)"},
                       {"--driver", "NAME", "the driver's heartbeat name (default rover_sim or mobility_driver)"},
                       {"--listen-s", "S", "imu, wheel_odometry: seconds to listen at rest (default 5)"},
                       {"--drive", "", "imu, wheel_odometry: then drive 0.10 m and turn 0.10 rad (as the commander) to check units and frames in motion"},
                       {"--min-rate-hz", "HZ", "imu, wheel_odometry: the minimum rate (default 10 and 8)"},
                       {"--gravity", "MPS2", "imu: gravity at the bench (default sensors.imu.gravity_mps2, else 9.80665)"},
                       {"--requests", "N", "camera: captures to ask for (default 3)"},
                       {"--timeout-s", "S", "camera: seconds a capture may take (default 20)"},
                       {"--size", "WxH", "camera: the image size expected (default: any)"},
                       {"--pair-tolerance-ms", "MS", "camera: how far apart a pair's two exposures may be (default the config's capture.genicam or capture.gstreamer pairing_tolerance_ms, else 2)"},
                       {"--capture-process", "NAME", "camera: the capture process's heartbeat name (default camera_capture)"},
                       {"--clock-tolerance-s", "S", "how far a utime may be from rover time (default 0.5)"}});
    const auto& contracts = conformance::ContractNames();
    if (name.empty()) {
      throw config::ConfigError("rover_conformance: missing NAME (expected mobility, imu, wheel_odometry or camera first)");
    }
    if (std::find(contracts.begin(), contracts.end(), name) == contracts.end()) {
      throw config::ConfigError("rover_conformance: NAME \"" + name +
                                "\": unknown (expected mobility, imu, wheel_odometry or camera)");
    }

    conformance::ProbeOptions options;
    const auto root = proc.config();
    root["bus"].Get("time_source", options.time_source);
    if (auto v = proc.option("--time-source")) options.time_source = *v;
    if (auto v = proc.option("--commander")) options.commander = *v;
    if (auto v = proc.option("--driver")) options.driver = *v;
    if (auto v = proc.option("--capture-process")) options.capture_process = *v;
    options.listen_s = NumberOption(proc, "--listen-s", 5.0, 1.0, 3600.0);
    options.drive = proc.has_switch("--drive");
    options.requests = static_cast<int>(NumberOption(proc, "--requests", 3, 1, 1000));
    const double tolerance = NumberOption(proc, "--clock-tolerance-s", 0.5, 0.001, 3600.0);

    conformance::Probe probe(proc.bus(), options);
    conformance::Report report;
    if (name == "mobility") {
      conformance::MobilityLimits limits;
      double deadman = 1.5;
      root["mobility"].Get("deadman_s", deadman, 0.2, 60.0);
      limits.deadman_s = NumberOption(proc, "--deadman-s", deadman, 0.2, 60.0);
      limits.answer_s = NumberOption(proc, "--answer-s", 1.0, 0.05, 60.0);
      limits.clock_tolerance_s = tolerance;
      probe.RunMobility(limits, report);
    } else if (name == "imu") {
      conformance::ImuLimits limits;
      root["sensors"]["imu"].Get("gravity_mps2", limits.gravity_mps2, 0.1, 100.0);
      limits.gravity_mps2 = NumberOption(proc, "--gravity", limits.gravity_mps2, 0.1, 100.0);
      limits.stream.min_rate_hz = NumberOption(proc, "--min-rate-hz", 10.0, 0.1, 10000.0);
      limits.stream.clock_tolerance_s = tolerance;
      probe.RunImu(limits, report);
    } else if (name == "wheel_odometry") {
      conformance::WheelOdometryLimits limits;
      limits.stream.min_rate_hz = NumberOption(proc, "--min-rate-hz", 8.0, 0.1, 10000.0);
      limits.stream.clock_tolerance_s = tolerance;
      probe.RunWheelOdometry(limits, report);
    } else {
      conformance::CameraLimits limits;
      limits.answer_s = NumberOption(proc, "--timeout-s", 20.0, 0.1, 3600.0);
      limits.clock_tolerance_s = tolerance;
      limits.pair_tolerance_ms = PairingTolerance(root["capture"]);
      limits.pair_tolerance_ms = NumberOption(proc, "--pair-tolerance-ms", limits.pair_tolerance_ms, 0.0, 10000.0);
      if (auto v = proc.option("--size")) {
        if (std::sscanf(v->c_str(), "%dx%d", &limits.width, &limits.height) != 2 || limits.width <= 0 ||
            limits.height <= 0) {
          throw config::ConfigError("rover_conformance: argument --size: \"" + *v + "\": expected WIDTHxHEIGHT, e.g. 512x512");
        }
      }
      probe.RunCamera(limits, report);
    }
    if (!probe.setup_problem().empty()) throw config::ConfigError("rover_conformance: " + probe.setup_problem());

    for (const auto& rule : conformance::RulesOf(name)) {
      if (report.Passed(rule.id)) std::cout << "ok   " << rule.id << "\n";
    }
    for (const auto& f : report.failures()) std::cout << conformance::FailureLine(f) << "\n";
    const auto unchecked = report.Unchecked(name);
    for (const auto& id : unchecked) {
      const std::string needs = conformance::NeededOption(name, id);
      const bool missing = (needs == "--drive" && !options.drive) || (needs == "--key" && !proc.bus().has_auth());
      std::cout << "--   " << id << (missing ? " (not checked: needs " + needs + ")" : " (not checked: an earlier step failed)")
                << "\n";
    }
    std::cout << "conformance " << name << ": " << (report.ok() ? "PASS" : "FAIL") << " ("
              << conformance::RulesOf(name).size() - unchecked.size() - report.failures().size() << " held, "
              << report.failures().size() << " failed, " << unchecked.size() << " not checked)\n";
    return report.ok() ? 0 : 1;
  });
}
