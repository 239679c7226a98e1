// Every process and tool meets bad arguments and bad configs with one clear line and a
// non-zero exit; the launcher reports a process that dies and exits non-zero.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>

#include <algorithm>
#include <chrono>

#include <gtest/gtest.h>

#include <fstream>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <sstream>

namespace rover::test {
namespace {

int CountLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

const char* kProcesses[] = {"rover_sim", "state_estimator", "hazard_monitor", "sequence_executor",
                            "camera_capture", "visual_odometry"};

TEST(ProcessCli, HelpPrintsUsageAndExitsZero) {
  for (const char* p : kProcesses) {
    const auto r = RunCommand(Bin(p) + " --help");
    EXPECT_EQ(r.exit_code, 0) << p;
    EXPECT_NE(r.output.find("usage: "), std::string::npos) << p << ": " << r.output;
    EXPECT_NE(r.output.find("--lcm-url"), std::string::npos) << p;
  }
}

TEST(ProcessCli, UnknownArgumentIsOneLineAndExitTwo) {
  for (const char* p : kProcesses) {
    const auto r = RunCommand(Bin(p) + " --bogus");
    EXPECT_EQ(r.exit_code, 2) << p;
    EXPECT_EQ(r.output, std::string(p) + ": argument --bogus: unknown option (expected one of "
                                         "the options in --help)\n");
  }
}

TEST(ProcessCli, BadConfigNamesFileKeyAndExpectation) {
  const std::string dir = OutDir("process_cli");
  const std::string bad = dir + "/bad.yaml";
  std::ofstream(bad) << "estimator:\n  publish_hz: fast\n";
  auto r = RunCommand(Bin("state_estimator") + " --config " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, bad + ": estimator.publish_hz: expected a finite number in [8, 1000], got \"fast\"\n");

  std::ofstream(bad) << "hazards:\n  roll_limit_deg: 30\n  pich_limit_deg: 30\n";
  r = RunCommand(Bin("hazard_monitor") + " --config " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.output), 1) << r.output;
  EXPECT_EQ(r.output.rfind(bad + ": hazards.pich_limit_deg: unknown key", 0), 0u) << r.output;

  std::ofstream(bad) << "nonsense: [1, 2\n";
  r = RunCommand(Bin("sequence_executor") + " --config " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.output), 1) << r.output;
  EXPECT_EQ(r.output.rfind(bad + ":", 0), 0u) << r.output;

  r = RunCommand(Bin("rover_sim") + " --config configs/rover.yaml --world /nonexistent.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "/nonexistent.yaml: cannot open file (expected a readable YAML file)\n");

  r = RunCommand(Bin("rover_sim") + " --config configs/rover.yaml --world configs/worlds/flat_rock_course.yaml --start 1,x,0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "rover_sim: argument --start: \"1,x,0\": expected 3 finite numbers separated by commas\n");
}

// The command line takes the YAML's ranges, and files that are not regular files (a
// directory, a character device that never ends, a FIFO that never opens) or are too large
// are refused with one line at once, never read.
TEST(ProcessCli, CommandLineRangesAreTheConfigRanges) {
  const auto r = RunCommand(Bin("rover_sim") + " --rate 1e12 --world configs/worlds/flat_rock_course.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "rover_sim: argument --rate: \"1e12\": expected max or a number in [0.1, 10000]\n");
  const std::string dir = OutDir("process_cli_rate");
  std::ofstream(dir + "/rate.yaml") << "sim:\n  rate: 1e12\n";
  const auto y = RunCommand(Bin("rover_sim") + " --config " + dir + "/rate.yaml --world configs/worlds/flat_rock_course.yaml");
  EXPECT_EQ(y.exit_code, 2);
  EXPECT_EQ(y.output, dir + "/rate.yaml: sim.rate: expected a number in [0.1, 10000], got \"1e12\"\n");
  for (const char* ok : {"0.1", "10000"}) {
    const auto b = RunCommand(Bin("rover_sim") + " --rate " + ok + " --world /nonexistent.yaml");
    EXPECT_EQ(b.output, "/nonexistent.yaml: cannot open file (expected a readable YAML file)\n") << ok;
  }
}

TEST(ProcessCli, ConfigThatIsNotARegularFileIsOneLineAtOnce) {
  const std::string dir = OutDir("process_cli_files");
  const std::string fifo = dir + "/fifo.yaml";
  ASSERT_EQ(RunCommand("mkfifo '" + fifo + "'").exit_code, 0);
  for (const char* p : kProcesses) {
    for (const std::string& file : {std::string("/dev/zero"), std::string("/tmp"), fifo}) {
      const auto start = std::chrono::steady_clock::now();
      const auto r = RunCommand("timeout 10 " + Bin(p) + " --config " + file);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      EXPECT_EQ(r.exit_code, 2) << p << " " << file;
      EXPECT_EQ(r.output, file + ": not a regular file (expected a YAML file)\n") << p;
      EXPECT_LT(s, 5.0) << p << " " << file;
    }
  }
  const std::string big = dir + "/big.yaml";
  std::ofstream(big) << std::string(2 << 20, '#');
  const auto r = RunCommand(Bin("state_estimator") + " --config " + big);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, big + ": too large: 2097152 bytes (expected a YAML file of at most 1048576 bytes)\n");
  const auto w = RunCommand(Bin("rover_sim") + " --world /dev/zero");
  EXPECT_EQ(w.exit_code, 2);
  EXPECT_EQ(w.output, "/dev/zero: not a regular file (expected a YAML file)\n");
}

// Three bad inputs an operator met, each answered with one line of ours that names where
// and what was expected.
TEST(ProcessCli, HugeWorldBadLcmUrlAndADirectoryStateFileAreOneLine) {
  const std::string dir = OutDir("process_cli_bad_inputs");
  // A world whose map would be 2e17 cells: the file and map.size_m, not just the world's name.
  const std::string world = dir + "/huge.yaml";
  std::ofstream(world) << "name: huge\nmap: {center: [0, 0], size_m: [1e7, 1e7], resolution_m: 0.05}\n";
  auto r = RunCommand(Bin("rover_sim") + " --config configs/rover.yaml --world " + world);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(CountLines(r.output), 1) << r.output;
  EXPECT_EQ(r.output.rfind(world + ": map.size_m: ", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("expected at most 16000000: a smaller size_m or a coarser resolution_m"), std::string::npos) << r.output;

  // An impossible group and port: ours, with no "Error:" line of LCM's before it.
  r = RunCommand(Bin("state_estimator") + " --config configs/rover.yaml --lcm-url 'udpm://999.1.1.1:99999'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, "state_estimator: argument --lcm-url: udpm://999.1.1.1:99999: group '999.1.1.1' is not an "
                      "IPv4 address (expected udpm://GROUP:PORT?ttl=N, GROUP in 224.0.0.0/4, PORT 1-65535, ttl 0-255)\n");
  r = RunCommand("ROVER_LCM_URL='udpm://239.255.76.67:99999?ttl=0' " + Bin("hazard_monitor") + " --config configs/rover.yaml");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(CountLines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("hazard_monitor: $ROVER_LCM_URL: udpm://239.255.76.67:99999?ttl=0: port '99999' is not in "
                          "1-65535"), std::string::npos) << r.output;
  for (const std::string& tool : {std::string("rover_console --once"), std::string("rover_seq status"), "rover_recorder " + dir + "/x.lcm"}) {
    r = RunCommand(Bin(tool) + " --lcm-url 'udpm://999.1.1.1:99999'");
    EXPECT_NE(r.exit_code, 0) << tool;
    EXPECT_EQ(CountLines(r.output), 1) << tool << ": " << r.output;
    EXPECT_EQ(r.output.find("Error:"), std::string::npos) << tool << ": " << r.output;
    EXPECT_NE(r.output.find("999.1.1.1"), std::string::npos) << tool << ": " << r.output;
  }

  // A directory where the executor keeps its running sequence.
  r = RunCommand("timeout 10 " + Bin("sequence_executor") + " --config configs/rover.yaml --state-file " + dir);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, "sequence_executor: argument --state-file: " + dir +
                          ": is a directory (expected the path of a file the executor keeps its running sequence in)\n");
}

// A bus port already bound by a socket that does not share it (CI once met another
// program's outgoing socket there): every process says so in a line and exits 1, where
// LCM 1.3.1 alone leaves a subscription with no socket under it, and all six crashed.
TEST(ProcessCli, ABusPortHeldByAnotherSocketIsOneLineNotACrash) {
  const std::string url = PrivateUrl(57);
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  const int holder = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(holder, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_ANY);
  ASSERT_EQ(bind(holder, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0) << "port " << port;
  for (const char* p : kProcesses) {
    const auto r = RunCommand("ROVER_LCM_URL='" + url + "' timeout 20 " + Bin(p) + " --config configs/rover.yaml");
    EXPECT_EQ(r.exit_code, 1) << p << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(p) + ": error: cannot receive on the LCM bus at " + url +
                            ": its UDP port is held by a socket that does not share it"),
              std::string::npos) << p << ": " << r.output;
  }
  const auto r = RunCommand("timeout 20 " + Bin("rover_recorder") + " " + OutDir("held_port") + "/x.lcm --lcm-url '" + url + "'");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cannot receive on the LCM bus at " + url), std::string::npos) << r.output;
  close(holder);
}

TEST(SeqCheck, FifoDeviceDirectoryAndHugeFileAreErrorsAtOnce) {
  const std::string dir = OutDir("seq_check_files");
  const std::string fifo = dir + "/fifo.seq";
  ASSERT_EQ(RunCommand("mkfifo '" + fifo + "'").exit_code, 0);
  const std::string big = dir + "/big.seq";
  std::ofstream(big) << std::string((1 << 20) + 1, '#');
  const auto start = std::chrono::steady_clock::now();
  const auto r = RunCommand("timeout 10 " + Bin("seq_check") + " " + fifo + " /dev/zero " + dir + " " + big);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, fifo + ":1:1: not a regular file (expected a sequence file)\n"
                      "/dev/zero:1:1: not a regular file (expected a sequence file)\n" +
                      dir + ":1:1: not a regular file (expected a sequence file)\n" +
                      big + ":1:1: too large: 1048577 bytes (expected a sequence file of at most 1048576 bytes)\n");
}

TEST(ProcessCli, OperatorSubmitChecksTheFileFirst) {
  const auto r = RunCommand(Bin("rover_seq") + " submit configs/sequences/bad_units.seq");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output,
            "configs/sequences/bad_units.seq:5:9: wrong unit 'deg' for drive distance (expected m or cm)\n");
}

// The operator's command line against a launched process set: submit and follow to the
// end, then submit, abort, and see the abort reported.
TEST(OperatorCommandLine, SubmitFollowsToTheEndAndAbortStopsTheDrive) {
  const std::string dir = OutDir("operator");
  std::ofstream(dir + "/short.seq") << "vo off step 50 cm\ndrive 1 m\n";
  std::ofstream(dir + "/long.seq") << "vo off step 50 cm\nturn 180 deg\ndrive 5 m\n";
  const std::string url = PrivateUrl(5);
  const auto r = RunCommand(
      "export ROVER_LCM_URL='" + url + "'; " + Bin("launcher") + " configs/deploy/sim.yaml > " + dir +
      "/launch.log 2>&1 & L=$!; sleep 2; " +
      "timeout 60 " + Bin("rover_seq") + " submit " + dir + "/short.seq; echo \"submit rc=$?\"; " +
      "timeout 10 " + Bin("rover_seq") + " submit " + dir + "/long.seq --no-follow; sleep 1; " +
      Bin("rover_seq") + " abort 'stop for the test'; " +
      "timeout 10 " + Bin("rover_seq") + " status; echo \"status rc=$?\"; kill -TERM $L; wait $L");
  EXPECT_NE(r.output.find("[completed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("submit rc=0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("abort_reason=operator"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stop for the test"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("status rc=1"), std::string::npos) << r.output;  // aborted
}

// Pause and resume from the operator's command line: the drive holds between steps,
// status says paused, and resume takes it to the end.
TEST(OperatorCommandLine, PauseHoldsTheDriveAndResumeFinishesIt) {
  const std::string dir = OutDir("operator_pause");
  // Ten short steps, short of the rock Adirondack (4.2 m north): blind, they go by at
  // several a second, so the pause follows the submit closely.
  std::ofstream(dir + "/long.seq") << "vo off step 25 cm\ndrive 2.5 m\n";
  const std::string url = PrivateUrl(61);
  const std::string seq = Bin("rover_seq");
  const auto r = RunCommand(
      "export ROVER_LCM_URL='" + url + "'; " + Bin("launcher") + " configs/deploy/sim.yaml > " + dir +
      "/launch.log 2>&1 & L=$!; sleep 2; " +
      "timeout 10 " + seq + " submit " + dir + "/long.seq --no-follow; sleep 0.5; " +
      seq + " pause 'hold for the test'; echo \"pause rc=$?\"; sleep 4; " +
      "echo once:; timeout 10 " + seq + " status --once; " +
      seq + " resume; echo \"resume rc=$?\"; " +
      "timeout 60 " + seq + " status; echo \"status rc=$?\"; kill -TERM $L; wait $L");
  EXPECT_NE(r.output.find("pause sent: hold for the test"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pause rc=0"), std::string::npos) << r.output;
  const auto once = r.output.find("once:\n");
  ASSERT_NE(once, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("[paused", once), once + 6) << r.output;  // still paused 4 s later
  EXPECT_NE(r.output.find("resume rc=0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("[completed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("status rc=0"), std::string::npos) << r.output;
}

// Every rover_seq subcommand answers --help with its own usage; misuse is one line.
TEST(ProcessCli, RoverSeqSubcommandsAnswerHelp) {
  for (const std::string sub : {"submit", "status", "abort", "pause", "resume", "keygen"}) {
    const auto r = RunCommand(Bin("rover_seq") + " " + sub + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub << ": " << r.output;
    EXPECT_EQ(r.output.rfind("usage: rover_seq " + sub, 0), 0u) << sub << ": " << r.output;
  }
  const auto all = RunCommand(Bin("rover_seq") + " --help");
  EXPECT_EQ(all.exit_code, 0);
  EXPECT_NE(all.output.find("pause [REASON]"), std::string::npos) << all.output;
  for (const std::string bad : {"", "pause two words", "bogus"}) {
    const auto r = RunCommand(Bin("rover_seq") + " " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << bad << ": " << r.output;
  }
  const auto wrapper = RunCommand("./rover seq --help");
  EXPECT_EQ(wrapper.exit_code, 0) << wrapper.output;
  EXPECT_NE(wrapper.output.find("usage: rover_seq"), std::string::npos) << wrapper.output;
}

// A zone that cannot be built (negative radius) neither crashes the hazard monitor nor
// is ignored: the monitor cannot decide, says UNKNOWN, and the executor would stop.
TEST(HazardMonitor, InvalidZoneMessageGivesUnknownAndKeepsRunning) {
  const std::string dir = OutDir("hazard_bad_zone");
  const std::string url = PrivateUrl(6);
  bus::Bus bus(url);
  std::string unknown_detail;
  bus.Subscribe<rover_msgs::hazard_status_t>(channels::kHazardStatus, [&](const rover_msgs::hazard_status_t& h) {
    if (h.state == rover_msgs::hazard_status_t::STATE_UNKNOWN &&
        h.detail.find("invalid keep-out zones") != std::string::npos) {
      unknown_detail = h.detail;
    }
  });
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  set.Start({"hazard_monitor", "hazard_monitor", {"--config", SourceDir() + "/configs/rover.yaml"}},
            {"ROVER_LCM_URL=" + url});
  rover_msgs::keepout_zones_t zones{};
  rover_msgs::keepout_zone_t zone{};
  zone.name = "rock";
  zone.shape = rover_msgs::keepout_zone_t::SHAPE_CIRCLE;
  zone.radius_m = -1.0;
  zones.zones.push_back(zone);
  zones.num_zones = 1;
  const auto start = std::chrono::steady_clock::now();
  while (unknown_detail.empty() && std::chrono::steady_clock::now() - start < std::chrono::seconds(10)) {
    bus.Publish(channels::kKeepOutZones, zones);
    bus.Handle(200);
  }
  EXPECT_NE(unknown_detail.find("rock"), std::string::npos) << unknown_detail;
  EXPECT_TRUE(set.Running("hazard_monitor"));
  set.StopAll();
}

TEST(Launcher, ReportsAProcessThatDiesAndStopsTheRest) {
  const std::string dir = OutDir("launcher");
  const std::string deployment = dir + "/deploy.yaml";
  std::ofstream(deployment) << "processes:\n"
                               "  - name: hazard_monitor\n"
                               "    args: [--config, configs/rover.yaml]\n"
                               "  - name: state_estimator\n"
                               "    args: [--config, /nonexistent/rover.yaml]\n";
  const auto r = RunCommand("ROVER_LCM_URL='" + PrivateUrl(3) + "' timeout 30 " + Bin("launcher") +
                            " " + deployment);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  // The child's own error line, prefixed with its name, then the launcher's verdict.
  EXPECT_NE(r.output.find("[state_estimator] /nonexistent/rover.yaml: cannot open file"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("launcher: state_estimator exited with code 2 unexpectedly"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("launcher: all processes stopped"), std::string::npos) << r.output;
}

TEST(Launcher, StopsEverythingCleanlyOnSigterm) {
  const auto r = RunCommand("ROVER_LCM_URL='" + PrivateUrl(4) + "' timeout --preserve-status -s TERM 3 " +
                            Bin("launcher") + " configs/deploy/sim.yaml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("launcher: started sequence_executor"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("launcher: all processes stopped"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("unexpectedly"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("killing it"), std::string::npos) << r.output;
}

// kill -9 of the launcher: it cannot stop its children, so the kernel does
// (PR_SET_PDEATHSIG): every child exits within a few seconds.
TEST(Launcher, ChildrenDieWithItEvenOnSigkill) {
  const std::string dir = OutDir("launcher_sigkill");
  const auto r = RunCommand(
      "export ROVER_LCM_URL='" + PrivateUrl(7) + "'; " + Bin("launcher") + " configs/deploy/sim.yaml > " + dir +
      "/launch.log 2>&1 & L=$!; sleep 2; C=$(pgrep -P $L | tr '\\n' ' '); echo \"children: $C\"; "
      "kill -KILL $L; sleep 3; "
      "for p in $C; do s=$(ps -o stat= -p $p); case \"$s\" in ''|Z*) ;; *) echo \"alive: $p $s\"; kill -KILL $p;; esac; done; "
      "echo done");
  const auto at = r.output.find("children: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  std::istringstream pids(r.output.substr(at + 10, r.output.find('\n', at) - at - 10));
  int children = 0;
  for (std::string pid; pids >> pid;) ++children;
  EXPECT_GE(children, 4) << r.output;  // the deployment's processes
  EXPECT_EQ(r.output.find("alive:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("done"), std::string::npos) << r.output;
}

TEST(Launcher, BadDeploymentIsOneLine) {
  const std::string dir = OutDir("launcher_bad");
  const std::string deployment = dir + "/deploy.yaml";
  std::ofstream(deployment) << "processes:\n  - nam: rover_sim\n";
  const auto r = RunCommand(Bin("launcher") + " " + deployment);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, deployment + ": processes[0].nam: unknown key (expected one of: name, program, args, host)\n");
}

}  // namespace
}  // namespace rover::test
