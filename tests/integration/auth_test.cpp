// Authenticated commands on real processes (configs/deploy/sim_vo_auth.yaml, with a key
// made here in the build tree): a SEQUENCE_SUBMIT with no tag, one signed with another
// key, and a replay of a genuinely signed one (its bytes captured off the bus and sent
// again) are all refused by the executor with one line each and never run; a submit
// signed by `rover_seq --key` runs to completion, through commands the executor itself
// signs (MOBILITY_COMMAND to rover_sim, KEEPOUT_ZONES to hazard_monitor, NEW_SITE to
// state_estimator), none of which any receiver refuses. Unsigned commands on those
// channels, sent by a process without the key, are refused by each receiver.
#include "auth/auth.hpp"
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/signing.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <set>
#include <sstream>

namespace rover::test {
namespace {

namespace fs = std::filesystem;
using rover_msgs::sequence_status_t;
using rover_msgs::sequence_submit_t;
using Clock = std::chrono::steady_clock;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Every packet on one channel, as a listener on the LAN receives it.
struct RawCapture {
  std::vector<std::vector<std::uint8_t>> packets;
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    packets.emplace_back(p, p + rbuf->data_size);
  }
};

// The committed deployment with its key path pointed at `key` (every process holds it).
std::string DeploymentWithKey(const std::string& dir, const std::string& key) {
  std::string text = ReadText(SourceDir() + "/configs/deploy/sim_vo_auth.yaml");
  const std::string placeholder = "build/keys/rover.key";
  std::size_t replaced = 0;
  for (auto at = text.find(placeholder); at != std::string::npos; at = text.find(placeholder, at)) {
    text.replace(at, placeholder.size(), key);
    at += key.size();
    ++replaced;
  }
  // Six processes, each with --key; the comment's three mentions are replaced too.
  EXPECT_GE(replaced, 6u) << "configs/deploy/sim_vo_auth.yaml no longer names " << placeholder;
  EXPECT_EQ(Count(text, "--key, " + key), 6) << text;
  const std::string path = dir + "/sim_vo_auth.yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(AuthenticatedCommands, ForgedAndReplayedSubmitsAreRefusedAndASignedOneRuns) {
  const std::string dir = OutDir("auth");
  const std::string key = dir + "/rover.key", wrong_key = dir + "/wrong.key";
  // The operator's tool makes the keys (mode 0600), as a user would.
  for (const auto& k : {key, wrong_key}) {
    const auto r = RunCommand(Bin("rover_seq") + " keygen " + k);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_EQ(fs::status(key).permissions() & fs::perms::all, fs::perms::owner_read | fs::perms::owner_write);

  const std::string url = PrivateUrl(41);
  const auto deployment = launch::LoadDeployment(DeploymentWithKey(dir, key));
  fs::current_path(SourceDir());  // the deployment's paths are relative to the repository root

  bus::Bus bus(url);  // holds no key: what anyone on the LAN can do
  std::set<std::string> alive;
  std::map<std::string, std::int64_t> dropped;
  std::map<std::int64_t, std::vector<sequence_status_t>> statuses;
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
    alive.insert(hb.process);
    dropped[hb.process] = hb.dropped;
  });
  bus.Subscribe<sequence_status_t>(channels::kSequenceStatus, [&](const sequence_status_t& st) {
    statuses[st.submission_id].push_back(st);
  });
  std::int64_t rover_now = 0;
  bus.Subscribe<rover_msgs::rover_clock_t>(channels::kClock, [&](const rover_msgs::rover_clock_t& c) {
    rover_now = c.utime;
  });
  std::set<std::int64_t> mobility_ids;
  bus.Subscribe<rover_msgs::mobility_status_t>(channels::kMobilityStatus,
                                               [&](const rover_msgs::mobility_status_t& m) {
                                                 mobility_ids.insert(m.command_id);
                                               });
  RawCapture submits;
  bus.lcm().subscribe(channels::kSequenceSubmit, &RawCapture::OnMessage, &submits);

  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  std::string others;  // the simulator holds its clock until these are up (as the scenario runner does)
  for (const auto& p : deployment.processes)
    if (p.name != "rover_sim") others += (others.empty() ? "" : ",") + p.name;
  for (auto p : deployment.processes) {
    if (p.name == "rover_sim") {
      p.args.push_back("--hold-for");
      p.args.push_back(others);
    }
    set.Start(p, {"ROVER_LCM_URL=" + url, "ROVER_TIME=" + deployment.time});  // virtual: load cannot change it
  }
  const auto start = Clock::now();
  while (alive.size() < deployment.processes.size() && Seconds(start) < 60) bus.Handle(50);
  ASSERT_EQ(alive.size(), deployment.processes.size()) << "not every process sent a heartbeat";
  ASSERT_EQ(set.RunningNames().size(), deployment.processes.size());

  auto pump = [&](double seconds) {
    const auto t0 = Clock::now();
    while (Seconds(t0) < seconds) bus.Handle(20);
  };
  auto submit = [](std::int64_t id, const std::string& name) {
    sequence_submit_t msg{};
    msg.submission_id = id;
    msg.name = name;
    msg.text = "vo off\ndrive 1 m\n";
    return msg;
  };
  auto publish_raw = [&](const std::vector<std::uint8_t>& bytes) {
    bus.lcm().publish(channels::kSequenceSubmit, bytes.data(), static_cast<unsigned>(bytes.size()));
  };

  // 1. No tag at all.
  publish_raw(bus::EncodeMessage(submit(101, "unsigned.seq")));
  // 2. Signed, but with a key that is not the deployment's.
  auth::Signer forger(auth::Key::LoadFile(wrong_key), "rover_seq");
  sequence_submit_t forged = submit(102, "wrong_key.seq");
  bus::SignMessage(forged, forger);
  publish_raw(bus::EncodeMessage(forged));
  pump(3.0);
  EXPECT_EQ(statuses.count(101), 0u) << "the executor ran an unsigned submit";
  EXPECT_EQ(statuses.count(102), 0u) << "the executor ran a submit signed with the wrong key";

  // 3. Signed with the deployment's key by the operator's tool: it runs to completion,
  // including a keep-out zone (KEEPOUT_ZONES), a drive (MOBILITY_COMMAND) and a new
  // site (NEW_SITE), each signed by the executor and checked by its receiver.
  const std::string seq = dir + "/signed.seq";
  std::ofstream(seq) << "vo off step 50 cm\nkeepout far circle 30 m 30 m radius 1 m\ndrive 1 m\nsite\n";
  auto operator_run = std::async(std::launch::async, [&] {
    return RunCommand("timeout 120 " + Bin("rover_seq") + " submit " + seq + " --key " + key +
                      " --lcm-url '" + url + "'");
  });
  while (operator_run.wait_for(std::chrono::milliseconds(0)) != std::future_status::ready) bus.Handle(20);
  const CommandResult signed_run = operator_run.get();
  EXPECT_EQ(signed_run.exit_code, 0) << signed_run.output;
  EXPECT_NE(signed_run.output.find("submitted (signed)"), std::string::npos) << signed_run.output;
  EXPECT_NE(signed_run.output.find("[completed"), std::string::npos) << signed_run.output;
  pump(0.5);

  // 4. The signed submit's own bytes, captured off the bus, sent again.
  ASSERT_EQ(submits.packets.size(), 3u) << "expected the two forgeries and the signed submit";
  sequence_submit_t captured;
  ASSERT_GT(captured.decode(submits.packets[2].data(), 0, static_cast<int>(submits.packets[2].size())), 0);
  EXPECT_EQ(captured.auth.sender.rfind("rover_seq@", 0), 0u) << captured.auth.sender;
  ASSERT_EQ(captured.auth.tag_size, 32);
  const std::int64_t signed_id = captured.submission_id;
  ASSERT_TRUE(statuses.count(signed_id));
  const std::size_t statuses_before_replay = statuses[signed_id].size();
  publish_raw(submits.packets[2]);
  pump(3.0);
  // A replay that ran would start the sequence again (a running, non-terminal state).
  for (std::size_t i = statuses_before_replay; i < statuses[signed_id].size(); ++i) {
    const auto state = statuses[signed_id][i].state;
    EXPECT_TRUE(state == sequence_status_t::STATE_COMPLETED) << "the replayed submit ran again (state "
                                                             << static_cast<int>(state) << ")";
  }

  // 5. Unsigned commands on the other command channels, at a plausible rover time (so
  // that only their missing tag can be why they are refused).
  ASSERT_GT(rover_now, 0);
  rover_msgs::mobility_command_t drive{};
  drive.utime = rover_now;
  drive.command_id = 777001;
  drive.type = rover_msgs::mobility_command_t::TYPE_ARC;
  drive.distance_m = 5.0;
  bus.Publish(channels::kMobilityCommand, drive);
  rover_msgs::keepout_zones_t zones{};
  zones.utime = rover_now;
  bus.Publish(channels::kKeepOutZones, zones);  // "no zones": would clear the rover's keep-outs
  rover_msgs::new_site_t site{};
  site.utime = rover_now;
  site.site_index = 9;
  bus.Publish(channels::kNewSite, site);
  rover_msgs::sequence_control_t abort{};
  abort.utime = rover_now;
  abort.action = rover_msgs::sequence_control_t::ACTION_ABORT;
  abort.reason = "spoofed";
  bus.Publish(channels::kSequenceControl, abort);
  pump(3.0);  // the executor's next heartbeat (1 Hz) carries its drop count
  EXPECT_EQ(mobility_ids.count(777001), 0u) << "rover_sim obeyed an unsigned MOBILITY_COMMAND";

  // Every process is still up; each receiver said why it refused each one, in one line.
  EXPECT_EQ(set.RunningNames().size(), deployment.processes.size());
  set.StopAll();
  const std::string executor_log = ReadText(dir + "/sequence_executor.log");
  EXPECT_EQ(Count(executor_log, "SEQUENCE_SUBMIT: dropped a sequence_submit_t: rejected: "), 3) << executor_log;
  EXPECT_EQ(Count(executor_log, "SEQUENCE_SUBMIT: dropped a sequence_submit_t: rejected: no authentication tag"), 1)
      << executor_log;
  EXPECT_EQ(Count(executor_log, "rejected: wrong tag from \"rover_seq\""), 1) << executor_log;
  EXPECT_EQ(Count(executor_log, "rejected: replayed or old counter " + std::to_string(captured.auth.counter) +
                                    " from \"" + captured.auth.sender + "\""), 1) << executor_log;
  EXPECT_EQ(Count(executor_log, "SEQUENCE_CONTROL: dropped a sequence_control_t: rejected: no authentication tag"), 1)
      << executor_log;
  EXPECT_GE(dropped["sequence_executor"], 4) << "the heartbeat counts the refused commands";
  const std::map<std::string, std::string> refused_by = {
      {"rover_sim", "MOBILITY_COMMAND: dropped a mobility_command_t: rejected: no authentication tag"},
      {"hazard_monitor", "KEEPOUT_ZONES: dropped a keepout_zones_t: rejected: no authentication tag"},
      {"state_estimator", "NEW_SITE: dropped a new_site_t: rejected: no authentication tag"}};
  // Nothing else was refused anywhere: every genuinely signed command was accepted.
  for (const auto& p : deployment.processes) {
    const std::string log = ReadText(dir + "/" + p.name + ".log");
    int expected = 0;
    if (p.name == "sequence_executor") expected = 4;
    if (auto it = refused_by.find(p.name); it != refused_by.end()) {
      EXPECT_EQ(Count(log, it->second), 1) << p.name << ":\n" << log;
      expected = 1;
    }
    EXPECT_EQ(Count(log, "rejected: "), expected) << p.name << ":\n" << log;
  }
}

// A process told to hold a key it cannot use refuses to start, with one line.
TEST(AuthenticatedCommands, UnusableKeyStopsAProcessAtStart) {
  const std::string dir = OutDir("auth_bad_key");
  const std::string key = dir + "/open.key";
  ASSERT_EQ(RunCommand(Bin("rover_seq") + " keygen " + key).exit_code, 0);
  fs::permissions(key, fs::perms::others_read, fs::perm_options::add);
  auto r = RunCommand(Bin("sequence_executor") + " --config configs/rover.yaml --key " + key);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, "sequence_executor: argument --key: " + key + ": mode 0604 gives other users access to the key "
                      "(expected none: chmod o-rwx " + key + ")\n");
  const std::string config = dir + "/required.yaml";
  std::ofstream(config) << "auth: {required: true}\n";
  r = RunCommand("env -u ROVER_KEY_FILE " + Bin("hazard_monitor") + " --config " + config);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, config + ": auth.key_file: missing, and no --key or $ROVER_KEY_FILE (auth.required "
                      "is true: expected the deployment's key file; ./rover seq keygen FILE makes one)\n");
}

}  // namespace
}  // namespace rover::test
