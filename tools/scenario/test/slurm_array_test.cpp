// A campaign as a Slurm job array without Slurm: the plan written and read back, the batch
// script, array specs, squeue's lines, and what a merge makes of each task's files (done,
// failed, cancelled, never started, still queued), each with its reason.
#include "scenario/slurm_array.hpp"

#include "config/yaml_config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace fs = std::filesystem;
namespace slurm = rover::tools::slurm;
using State = slurm::TaskStatus::State;

namespace {

// A plan of `n` tasks in a fresh folder, each run in DIR/vK.
slurm::ArrayPlan MakePlan(const std::string& name, int n) {
  slurm::ArrayPlan plan;
  plan.out_dir = (fs::temp_directory_path() / ("slurm_array_test_" + name + "_" + std::to_string(getpid()))).string();
  fs::remove_all(plan.out_dir);
  plan.source_dir = "/opt/rover src";
  plan.build_dir = "/opt/rover src/build";
  plan.job_name = "rover-demo";
  plan.plot = false;
  for (int k = 1; k <= n; ++k) {
    const std::string dir = plan.out_dir + "/v" + std::to_string(k);
    fs::create_directories(dir);
    plan.scenarios.push_back(dir + "/scenario.yaml");
  }
  plan.sbatch_args = {"--partition=short", "--time=00:30:00"};
  plan.settings = {{"scenario", "/opt/rover src/configs/scenarios/demo.yaml"}, {"variants", std::to_string(n)}, {"seed", "7"}};
  slurm::WritePlan(plan);
  return plan;
}

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST(SlurmArray, PlanRoundTrip) {
  const auto plan = MakePlan("roundtrip", 3);
  const auto back = slurm::ReadPlan(plan.out_dir);
  EXPECT_EQ(back.out_dir, plan.out_dir);
  EXPECT_EQ(back.source_dir, plan.source_dir);
  EXPECT_EQ(back.build_dir, plan.build_dir);
  EXPECT_EQ(back.scenarios, plan.scenarios);
  EXPECT_EQ(back.sbatch_args, plan.sbatch_args);
  EXPECT_EQ(back.settings, plan.settings);
  EXPECT_FALSE(back.plot);
  EXPECT_EQ(back.rate, "max");
  EXPECT_THROW(slurm::ReadPlan(plan.out_dir + "/v1"), rover::config::ConfigError);
  fs::remove_all(plan.out_dir);
}

// Each task runs at the campaign's --rate; a plan written before the rate was kept (no `rate`
// key) ran each scenario at its own sim_rate, and a resume of it still does.
TEST(SlurmArray, TasksRunAtTheCampaignsRate) {
  auto plan = MakePlan("rate", 2);
  EXPECT_NE(slurm::ArrayScript(plan).find("--quiet --no-plot --rate 'max' >"), std::string::npos)
      << slurm::ArrayScript(plan);
  plan.rate = "25";
  EXPECT_NE(slurm::ArrayScript(plan).find("--no-plot --rate '25' >"), std::string::npos);
  plan.rate = "";
  EXPECT_EQ(slurm::ArrayScript(plan).find("--rate"), std::string::npos);
  const std::string path = plan.out_dir + "/slurm/plan.yaml";
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find("rate: max\n");
  ASSERT_NE(at, std::string::npos) << text;
  text.erase(at, std::string("rate: max\n").size());
  Write(path, text);
  EXPECT_EQ(slurm::ReadPlan(plan.out_dir).rate, "");
  fs::remove_all(plan.out_dir);
}

TEST(SlurmArray, ScriptRunsLineKWithTheRoverScript) {
  const auto plan = MakePlan("script", 4);
  const std::string script = slurm::ArrayScript(plan);
  EXPECT_NE(script.find("#SBATCH --array=1-4\n"), std::string::npos) << script;
  EXPECT_NE(script.find("#SBATCH --output=" + plan.out_dir + "/slurm/task-%a.out"), std::string::npos) << script;
  EXPECT_NE(script.find("ROOT='/opt/rover src'"), std::string::npos) << script;  // quoted: a path with a space
  EXPECT_NE(script.find("\"$ROOT/rover\" scenario \"$scenario\" --out \"$dir\" --quiet --no-plot"), std::string::npos);
  EXPECT_TRUE(fs::exists(plan.out_dir + "/slurm/array.sbatch"));
  std::ifstream tasks(plan.out_dir + "/slurm/tasks.txt");
  std::string second;
  std::getline(tasks, second);
  std::getline(tasks, second);
  EXPECT_EQ(second, plan.scenarios[1]);
  EXPECT_EQ(slurm::ShellQuote("it's"), "'it'\\''s'");
  fs::remove_all(plan.out_dir);
}

TEST(SlurmArray, ArraySpecs) {
  EXPECT_EQ(slurm::ArraySpec({1, 2, 3, 4}), "1-4");
  EXPECT_EQ(slurm::ArraySpec({2, 5, 6, 7, 9}), "2,5-7,9");
  EXPECT_EQ(slurm::ArraySpec({3}), "3");
}

TEST(SlurmArray, QueueLines) {
  const auto q = slurm::ParseQueue("12_3 RUNNING\n12_[4-6,8%2] PENDING\n13_1 RUNNING\n", "12");
  ASSERT_EQ(q.size(), 5u);
  EXPECT_EQ(q.at(3), "RUNNING");
  EXPECT_EQ(q.at(4), "PENDING");
  EXPECT_EQ(q.at(6), "PENDING");
  EXPECT_EQ(q.at(8), "PENDING");
  EXPECT_EQ(q.count(1), 0u);  // job 13's
  EXPECT_TRUE(slurm::ParseQueue("slurm_load_jobs error: Invalid job id specified\n", "12").empty());
}

TEST(SlurmArray, EveryTaskNamedWithWhy) {
  const auto plan = MakePlan("status", 6);
  const std::string st = plan.out_dir + "/slurm/status/";
  // 1: done (a run that did not end as expected, exit 1, is a result too).
  Write(st + "1.start", "job 12_1 on node3 at 2026-12-02T07:00:00Z\n");
  Write(st + "1.exit", "1\n");
  Write(plan.out_dir + "/v1/summary.json", "{}");
  // 2: the runner failed with no summary.
  Write(st + "2.start", "job 12_2 on node3 at 2026-12-02T07:00:00Z\n");
  Write(st + "2.exit", "2\n");
  Write(plan.out_dir + "/v2/runner.log", "starting\nv2/scenario.yaml: world: missing\n\n");
  // 3: cancelled while running.
  Write(st + "3.start", "job 12_3 on node4 at 2026-12-02T07:00:01Z\n");
  Write(plan.out_dir + "/slurm/task-3.out",
        "slurmstepd: error: *** JOB 15 ON node4 CANCELLED AT 2026-12-02T07:00:09 ***\n");
  // 4: never started. 5: still queued. 6: the batch script failed before the run.
  Write(plan.out_dir + "/slurm/task-6.out", "task 6: /opt/rover src/build/bin/scenario_runner is missing on node9\n");
  const std::map<int, std::string> queue = {{5, "PENDING"}};
  std::vector<slurm::TaskStatus> s;
  for (int k = 1; k <= 6; ++k) s.push_back(slurm::ReadTaskStatus(plan, k, queue));
  EXPECT_EQ(s[0].state, State::kDone);
  EXPECT_EQ(s[0].exit_code, 1);
  EXPECT_EQ(s[1].state, State::kFailed);
  EXPECT_NE(s[1].why.find("exit 2, no summary.json"), std::string::npos) << s[1].why;
  EXPECT_NE(s[1].why.find("world: missing"), std::string::npos) << s[1].why;
  EXPECT_EQ(s[2].state, State::kUnfinished);
  EXPECT_NE(s[2].why.find("CANCELLED"), std::string::npos) << s[2].why;
  EXPECT_NE(s[2].why.find("node4"), std::string::npos) << s[2].why;
  EXPECT_EQ(s[3].state, State::kNotStarted);
  EXPECT_EQ(s[4].state, State::kQueued);
  EXPECT_FALSE(s[4].resubmit());
  EXPECT_NE(s[4].why.find("PENDING"), std::string::npos);
  EXPECT_EQ(s[5].state, State::kFailed);
  EXPECT_NE(s[5].why.find("scenario_runner is missing on node9"), std::string::npos) << s[5].why;
  for (int k : {2, 3, 4, 6}) EXPECT_TRUE(s[static_cast<std::size_t>(k - 1)].resubmit()) << k;

  // A task cleared for its second run no longer counts as done.
  slurm::ClearTask(plan, 1);
  EXPECT_EQ(slurm::ReadTaskStatus(plan, 1, {}).state, State::kNotStarted);
  EXPECT_FALSE(fs::exists(plan.out_dir + "/v1/summary.json"));
  fs::remove_all(plan.out_dir);
}
