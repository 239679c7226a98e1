// Campaigns on a real Slurm cluster: a one-node cluster of Debian's slurmctld, slurmd and
// munged (slurm_cluster.sh) runs a 4-variant demo campaign and a 4-run navbench as job
// arrays (./rover campaign|navbench --slurm, slurm_flow.sh), one campaign task cancelled
// while it runs. The merge must name that task and table the other three as a local run
// does; --resume must submit it alone; the final merges must give the rows, log digests,
// campaign.json and results.json of a local --jobs 2 run of the same seeds.
#include "integration/run_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using rover::test::Bin;
using rover::test::OutDir;
using rover::test::RunCommand;
using rover::test::SourceDir;

namespace {

constexpr const char* kSeed = "11";
constexpr const char* kNavbenchArgs = "--quick --runs 4 --min-goal 5 --max-goal 6 --seed 3";

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int Code(const std::string& out, const std::string& step) { return std::stoi(ReadFile(out + "/" + step + ".code")); }

// A node as text with the keys in `drop` left out, wherever they are (folders differ).
std::string Canon(const YAML::Node& n, const std::set<std::string>& drop) {
  std::string s;
  if (n.IsMap()) {
    s += "{";
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (!drop.count(key)) s += key + ":" + Canon(kv.second, drop) + ",";
    }
    return s + "}";
  }
  if (n.IsSequence()) {
    s += "[";
    for (const auto& e : n) s += Canon(e, drop) + ",";
    return s + "]";
  }
  return n.IsNull() ? "null" : n.as<std::string>();
}

// The table's rows (a variant number, then its seeds), with the run's folder as DIR.
std::vector<std::string> Rows(const std::string& output, const std::string& dir) {
  std::vector<std::string> rows;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || !std::isdigit(static_cast<unsigned char>(line[0])) || line.find('/') > 30) continue;
    for (auto at = line.find(dir); at != std::string::npos; at = line.find(dir)) line.replace(at, dir.size(), "DIR");
    rows.push_back(line);
  }
  return rows;
}

}  // namespace

TEST(SlurmCampaign, ArraysMergeAsTheLocalRunAndResumeACancelledTask) {
  const std::string out = OutDir("slurm");
  const std::string slurm_camp = out + "/slurm_campaign", local_camp = out + "/local_campaign";
  const std::string slurm_nb = out + "/slurm_navbench", local_nb = out + "/local_navbench";

  // The cluster's side first: it skips, saying why, where the daemons cannot start.
  const auto cluster = RunCommand("ROVER_BUILD_DIR='" + std::string(ROVER_BINARY_DIR) +
                                  "' bash tests/slurm/slurm_cluster.sh " + out + "/cluster bash tests/slurm/slurm_flow.sh '" +
                                  SourceDir() + "' " + out + " " + kSeed + " '" + kNavbenchArgs + "'");
  if (cluster.exit_code == 77) GTEST_SKIP() << cluster.output;
  ASSERT_EQ(cluster.exit_code, 0) << cluster.output;

  // The same seeds here, two at a time.
  const auto local = RunCommand(Bin("scenario_campaign") + " configs/scenarios/demo.yaml --variants 4 --seed " + kSeed +
                                " --no-plot --jobs 2 --out " + local_camp);
  ASSERT_TRUE(local.exit_code == 0 || local.exit_code == 1) << local.output;
  const auto local_bench = RunCommand(Bin("navbench") + " " + kNavbenchArgs + " --jobs 2 --out " + local_nb);
  ASSERT_EQ(local_bench.exit_code, 0) << local_bench.output;
  const YAML::Node want = YAML::LoadFile(local_camp + "/campaign.json");
  ASSERT_EQ(want["runs"].size(), 4u);
  std::set<std::string> digests;
  for (const auto& run : want["runs"]) digests.insert(run["log_digest"].as<std::string>());
  ASSERT_EQ(digests.size(), 4u) << "four variants, four logs";
  EXPECT_EQ(digests.count(""), 0u);

  // Task 2, cancelled while it ran: named with Slurm's reason; the other three tabled.
  EXPECT_NE(ReadFile(out + "/queue_at_cancel.txt").find("_2 RUNNING"), std::string::npos)
      << ReadFile(out + "/queue_at_cancel.txt");
  EXPECT_EQ(Code(out, "merge_cancelled"), 3) << ReadFile(out + "/merge_cancelled.txt");
  const std::string cancelled = ReadFile(out + "/merge_cancelled.txt");
  EXPECT_NE(cancelled.find("1 missing or failed"), std::string::npos) << cancelled;
  EXPECT_NE(cancelled.find("  task 2: started"), std::string::npos) << cancelled;
  EXPECT_NE(cancelled.find("CANCELLED"), std::string::npos) << cancelled;
  const YAML::Node partial = YAML::LoadFile(out + "/campaign_cancelled.json");
  ASSERT_EQ(partial["tasks_missing"].size(), 1u);
  EXPECT_EQ(partial["tasks_missing"][0]["variant"].as<int>(), 2);
  EXPECT_NE(partial["tasks_missing"][0]["why"].as<std::string>().find("CANCELLED"), std::string::npos);
  EXPECT_EQ(partial["runs"][1]["outcome"].as<std::string>(), "incomplete");
  for (int i : {0, 2, 3}) EXPECT_EQ(Canon(partial["runs"][i], {"dir"}), Canon(want["runs"][i], {"dir"})) << i;

  // --resume submits task 2 alone, and the merge is then the local run's.
  EXPECT_EQ(Code(out, "resume"), 0) << ReadFile(out + "/resume.txt");
  EXPECT_NE(ReadFile(out + "/resume.txt").find(": tasks 2 again"), std::string::npos) << ReadFile(out + "/resume.txt");
  EXPECT_EQ(Code(out, "merge_campaign"), local.exit_code) << ReadFile(out + "/merge_campaign.txt");
  const YAML::Node merged = YAML::LoadFile(slurm_camp + "/campaign.json");
  EXPECT_EQ(merged["tasks_missing"].size(), 0u);
  EXPECT_EQ(Canon(merged, {"dir", "scenario"}), Canon(want, {"dir", "scenario"}));
  const auto rows = Rows(ReadFile(out + "/merge_campaign.txt"), slurm_camp);
  EXPECT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows, Rows(local.output, local_camp));

  // The navbench: its campaign's rows and digests, its table and results.json, its plots.
  EXPECT_EQ(Code(out, "merge_navbench"), 0) << ReadFile(out + "/merge_navbench.txt");
  const YAML::Node nb_want = YAML::LoadFile(local_nb + "/campaign.json");
  const YAML::Node nb_got = YAML::LoadFile(slurm_nb + "/campaign.json");
  ASSERT_EQ(nb_want["runs"].size(), 4u);
  EXPECT_EQ(Canon(nb_got["runs"], {"dir"}), Canon(nb_want["runs"], {"dir"}));
  const YAML::Node results_want = YAML::LoadFile(local_nb + "/results.json");
  const YAML::Node results_got = YAML::LoadFile(slurm_nb + "/results.json");
  EXPECT_EQ(Canon(results_got["groups"], {}), Canon(results_want["groups"], {}));
  EXPECT_EQ(Canon(results_got["runs"], {}), Canon(results_want["runs"], {}));
  for (const auto& run : results_got["runs"]) {
    EXPECT_TRUE(run["ran"].as<bool>());
    EXPECT_TRUE(fs::exists(slurm_nb + "/plots/" + run["id"].as<std::string>() + ".png")) << run["id"];
  }
  // results.txt: the same table under its own command line.
  auto table = [](const std::string& path) {
    const std::string text = ReadFile(path);
    return text.substr(std::min(text.size(), text.find('\n')));
  };
  EXPECT_GT(table(local_nb + "/results.txt").size(), 100u);
  EXPECT_EQ(table(slurm_nb + "/results.txt"), table(local_nb + "/results.txt"));
}
