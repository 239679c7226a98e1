// Deployment files split over hosts (`host:` per process, launcher --host), and what the
// operator's tools read from an LCM URL and the routing table.
#include "config/yaml_config.hpp"
#include "launch/lcm_url.hpp"
#include "launch/process_set.hpp"
#include "integration/run_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace rover::test {
namespace {

std::string Write(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string LoadError(const std::string& path) {
  try {
    launch::LoadDeployment(path);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string HostError(const launch::Deployment& d, const std::string& host) {
  try {
    launch::ProcessesOnHost(d, host);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MultiHostDeployment, ShippedTwoHostFileSplitsTheWholeSet) {
  const auto d = launch::LoadDeployment(SourceDir() + "/configs/deploy/sim_vo_two_hosts.yaml");
  ASSERT_EQ(d.hosts, (std::vector<std::string>{"rover", "ground"}));
  const auto rover = launch::ProcessesOnHost(d, "rover");
  const auto ground = launch::ProcessesOnHost(d, "ground");
  EXPECT_EQ(rover.size() + ground.size(), d.processes.size());
  ASSERT_EQ(ground.size(), 1u);
  EXPECT_EQ(ground[0].name, "sequence_executor");
  for (const auto& p : rover) EXPECT_EQ(p.host, "rover") << p.name;
  // The same processes, with the same arguments, as the one-host sim_vo.yaml.
  const auto one = launch::LoadDeployment(SourceDir() + "/configs/deploy/sim_vo.yaml");
  EXPECT_TRUE(one.hosts.empty());
  ASSERT_EQ(one.processes.size(), d.processes.size());
  for (const auto& p : one.processes) {
    bool found = false;
    for (const auto& q : d.processes) found = found || (q.name == p.name && q.args == p.args);
    EXPECT_TRUE(found) << p.name;
  }
  // Its bus reaches the other host.
  const auto url = launch::ParseLcmUrl(d.lcm_url);
  EXPECT_TRUE(url.udpm);
  EXPECT_EQ(url.ttl, 1);
}

TEST(MultiHostDeployment, UnknownHostIsOneLineListingTheHosts) {
  const auto d = launch::LoadDeployment(SourceDir() + "/configs/deploy/sim_vo_two_hosts.yaml");
  EXPECT_EQ(HostError(d, "mars"), SourceDir() + "/configs/deploy/sim_vo_two_hosts.yaml: no host \"mars\" "
                                                "(expected one of: rover, ground)");
  const auto one = launch::LoadDeployment(SourceDir() + "/configs/deploy/sim.yaml");
  EXPECT_NE(HostError(one, "rover").find("assigns no process a host"), std::string::npos);
}

TEST(MultiHostDeployment, HostOnEveryProcessOrNone) {
  const std::string dir = OutDir("multihost_deploy");
  const auto missing = Write(dir, "missing.yaml",
                             "processes:\n  - name: rover_sim\n    host: a\n  - name: hazard_monitor\n");
  EXPECT_EQ(LoadError(missing),
            missing + ": processes[1]: missing host (expected host: NAME on every process, as processes[0] has)");
  const auto late = Write(dir, "late.yaml",
                          "processes:\n  - name: rover_sim\n  - name: hazard_monitor\n    host: b\n");
  EXPECT_NE(LoadError(late).find("processes[1]: host: given here but not on processes[0]"), std::string::npos)
      << LoadError(late);
  const auto bad = Write(dir, "bad.yaml", "processes:\n  - name: rover_sim\n    host: \"a b\"\n");
  EXPECT_NE(LoadError(bad).find("processes[0].host"), std::string::npos) << LoadError(bad);
  const auto ok = Write(dir, "ok.yaml",
                        "processes:\n  - name: rover_sim\n    host: b\n  - name: hazard_monitor\n    host: a\n"
                        "  - name: state_estimator\n    host: b\n");
  const auto d = launch::LoadDeployment(ok);
  EXPECT_EQ(d.hosts, (std::vector<std::string>{"b", "a"}));
  const auto on_b = launch::ProcessesOnHost(d, "b");
  ASSERT_EQ(on_b.size(), 2u);
  EXPECT_EQ(on_b[0].name, "rover_sim");
  EXPECT_EQ(on_b[1].name, "state_estimator");
}

TEST(MultiHostDeployment, LauncherHostFlag) {
  const auto r = RunCommand(Bin("launcher") + " configs/deploy/sim_vo_two_hosts.yaml --host mars");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output,
            "launcher: --host mars: configs/deploy/sim_vo_two_hosts.yaml: no host \"mars\" (expected one of: "
            "rover, ground)\n");
  const auto none = RunCommand(Bin("launcher") + " configs/deploy/sim.yaml --host");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_EQ(none.output, "launcher: argument --host: missing value (expected NAME)\n");
}

TEST(MultiHostUrl, ParsesGroupPortAndTtl) {
  auto u = launch::ParseLcmUrl("udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304");
  EXPECT_TRUE(u.udpm);
  EXPECT_EQ(u.group, "239.255.76.67");
  EXPECT_EQ(u.port, 7667);
  EXPECT_EQ(u.ttl, 1);
  u = launch::ParseLcmUrl("udpm://239.1.2.3:40001?recv_buf_size=1");
  EXPECT_EQ(u.group, "239.1.2.3");
  EXPECT_EQ(u.port, 40001);
  EXPECT_EQ(u.ttl, 0);  // LCM's default
  EXPECT_FALSE(launch::ParseLcmUrl("file:///tmp/x.lcm").udpm);
}

TEST(MultiHostUrl, MulticastRouteIsTheLongestMatch) {
  const std::string dir = OutDir("multihost_routes");
  const std::string header =
      "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n";
  // default via eth0; 10.0.0.0/8 on eth0; 224.0.0.0/4 on eth1 (host byte order, little endian).
  const auto routes = Write(dir, "route", header +
                                              "eth0\t00000000\t0100000A\t0003\t0\t0\t0\t00000000\t0\t0\t0\n"
                                              "eth0\t0000000A\t00000000\t0001\t0\t0\t0\t000000FF\t0\t0\t0\n"
                                              "eth1\t000000E0\t00000000\t0001\t0\t0\t0\t000000F0\t0\t0\t0\n");
  EXPECT_EQ(launch::MulticastRouteInterface("239.255.76.67", routes), "eth1");
  const auto only_default =
      Write(dir, "route_default", header + "eth0\t00000000\t0100000A\t0003\t0\t0\t0\t00000000\t0\t0\t0\n");
  EXPECT_EQ(launch::MulticastRouteInterface("239.255.76.67", only_default), "eth0 (default route)");
  const auto none = Write(dir, "route_none", header);
  EXPECT_FALSE(launch::MulticastRouteInterface("239.255.76.67", none).has_value());
}

TEST(MultiHostUrl, NothingHeardNamesEveryCause) {
  const std::string msg =
      launch::NothingHeardCauses("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=1", "sequence_executor");
  for (const char* want : {"ttl=0 in the LCM URL (this one has it", "224.0.0.0/4", "239.255.76.67:7667",
                           "sequence_executor not running"}) {
    EXPECT_NE(msg.find(want), std::string::npos) << want << " in: " << msg;
  }
  EXPECT_EQ(msg.find('\n'), std::string::npos);
  EXPECT_NE(launch::NothingHeardCauses("udpm://239.255.76.67:7667?ttl=1", "x").find("this one has ttl=1"),
            std::string::npos);
}

}  // namespace
}  // namespace rover::test
