#include "scenario/slurm_array.hpp"

#include "config/yaml_config.hpp"

#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;
using rover::config::ConfigError;

namespace rover::tools::slurm {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The last line of `text` that is not blank and, when `pattern` is given, matches it.
std::string LastLine(const std::string& text, const std::string& pattern = "") {
  std::istringstream in(text);
  std::string line, last;
  const std::regex re(pattern.empty() ? "." : pattern);
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos && std::regex_search(line, re)) last = line;
  }
  while (!last.empty() && (last.back() == '\r' || last.back() == ' ')) last.pop_back();
  return last;
}

// Runs argv (no shell); returns its exit status (127: not found) and its stdout and stderr.
int RunCapture(const std::vector<std::string>& argv, std::string* output) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(fds[1]);
  char buf[4096];
  ssize_t n = 0;
  while ((n = read(fds[0], buf, sizeof buf)) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) output->append(buf, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string StatusPath(const ArrayPlan& plan, int task, const std::string& ext) {
  return plan.slurm_dir() + "/status/" + std::to_string(task) + "." + ext;
}

std::string Rel(const ArrayPlan& plan, const std::string& path) {
  const std::string prefix = plan.out_dir + "/";
  return path.rfind(prefix, 0) == 0 ? path.substr(prefix.size()) : path;
}

}  // namespace

std::string ShellQuote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string ArrayScript(const ArrayPlan& plan) {
  std::ostringstream s;
  s << "#!/bin/bash\n"
       "# A task of the Slurm job array of a campaign, written by scenario_campaign (./rover campaign\n"
       "# --slurm or --prepare). Task K runs the scenario on line K of tasks.txt with ./rover scenario,\n"
       "# on a private network namespace of its own, into the folder that holds that scenario file.\n"
       "# The source tree and the build must be at these paths on every node (a shared file system).\n"
    << "#SBATCH --job-name=" << plan.job_name << "\n"
    << "#SBATCH --array=1-" << plan.scenarios.size() << "\n"
    << "#SBATCH --output=" << plan.slurm_dir() << "/task-%a.out\n"
    << "set -u\n"
    << "ROOT=" << ShellQuote(plan.source_dir) << "\n"
    << "export ROVER_BUILD_DIR=" << ShellQuote(plan.build_dir) << "\n"
    << "SLURM_DIR=" << ShellQuote(plan.slurm_dir()) << "\n"
    << "k=\"${SLURM_ARRAY_TASK_ID:?not a Slurm array task (expected sbatch --array=1-N)}\"\n"
       "scenario=\"$(sed -n \"${k}p\" \"$SLURM_DIR/tasks.txt\")\"\n"
       "[ -n \"$scenario\" ] || { echo \"task $k: no line $k in $SLURM_DIR/tasks.txt\" >&2; exit 2; }\n"
       "[ -x \"$ROVER_BUILD_DIR/bin/scenario_runner\" ] || { echo \"task $k: $ROVER_BUILD_DIR/bin/scenario_runner\" \\\n"
       "  \"is missing on $(hostname) (expected the build at the same path on every node)\" >&2; exit 2; }\n"
       "dir=\"$(dirname \"$scenario\")\"\n"
       "rm -f \"$SLURM_DIR/status/$k.exit\" \"$dir/summary.json\"\n"
       "echo \"job ${SLURM_ARRAY_JOB_ID:-?}_$k on $(hostname) at $(date -u +%FT%TZ)\" > \"$SLURM_DIR/status/$k.start\"\n"
    << "\"$ROOT/rover\" scenario \"$scenario\" --out \"$dir\" --quiet" << (plan.plot ? "" : " --no-plot")
    << (plan.rate.empty() ? "" : " --rate " + ShellQuote(plan.rate))
    << " > \"$dir/runner.log\" 2>&1\n"
       "code=$?\n"
       "echo \"$code\" > \"$SLURM_DIR/status/$k.exit\"\n"
       "echo \"task $k: scenario_runner exit $code ($dir)\"\n"
       "# 1: the run did not end as its scenario expects, a result the merge tables.\n"
       "[ \"$code\" -le 1 ] || exit \"$code\"\n";
  return s.str();
}

void WritePlan(const ArrayPlan& plan) {
  fs::create_directories(plan.slurm_dir() + "/status");
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "out_dir" << YAML::Value << plan.out_dir;
  y << YAML::Key << "source_dir" << YAML::Value << plan.source_dir;
  y << YAML::Key << "build_dir" << YAML::Value << plan.build_dir;
  y << YAML::Key << "job_name" << YAML::Value << plan.job_name;
  y << YAML::Key << "plot" << YAML::Value << plan.plot;
  y << YAML::Key << "rate" << YAML::Value << plan.rate;
  y << YAML::Key << "sbatch_args" << YAML::Value << YAML::BeginSeq;
  for (const auto& a : plan.sbatch_args) y << a;
  y << YAML::EndSeq;
  y << YAML::Key << "settings" << YAML::Value << YAML::BeginMap;
  for (const auto& [k, v] : plan.settings) y << YAML::Key << k << YAML::Value << v;
  y << YAML::EndMap;
  y << YAML::Key << "tasks" << YAML::Value << static_cast<int>(plan.scenarios.size());
  y << YAML::EndMap;
  const std::string dir = plan.slurm_dir();
  std::ofstream(dir + "/plan.yaml") << "# A campaign as a Slurm job array (scenario_campaign)\n" << y.c_str() << "\n";
  std::ofstream tasks(dir + "/tasks.txt");
  for (const auto& s : plan.scenarios) tasks << s << "\n";
  tasks.close();
  std::ofstream(dir + "/array.sbatch") << ArrayScript(plan);
  fs::permissions(dir + "/array.sbatch", fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  if (!tasks || !fs::exists(dir + "/plan.yaml")) throw std::runtime_error(dir + ": cannot write the Slurm plan");
}

ArrayPlan ReadPlan(const std::string& out_dir) {
  const std::string path = out_dir + "/slurm/plan.yaml";
  if (!fs::exists(path)) {
    throw ConfigError(out_dir + ": no Slurm campaign here (expected " + path + ", written by --slurm or --prepare)");
  }
  ArrayPlan plan;
  try {
    const YAML::Node y = YAML::LoadFile(path);
    plan.out_dir = y["out_dir"].as<std::string>();
    plan.source_dir = y["source_dir"].as<std::string>();
    plan.build_dir = y["build_dir"].as<std::string>();
    plan.job_name = y["job_name"].as<std::string>();
    plan.plot = y["plot"].as<bool>();
    // A plan written before --rate ran each scenario at its own sim_rate.
    plan.rate = y["rate"] ? y["rate"].as<std::string>() : std::string();
    for (const auto& a : y["sbatch_args"]) plan.sbatch_args.push_back(a.as<std::string>());
    for (const auto& kv : y["settings"]) plan.settings[kv.first.as<std::string>()] = kv.second.as<std::string>();
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": not a campaign's Slurm plan (" + e.what() + ")");
  }
  std::ifstream tasks(plan.slurm_dir() + "/tasks.txt");
  for (std::string line; std::getline(tasks, line);) {
    if (!line.empty()) plan.scenarios.push_back(line);
  }
  if (plan.scenarios.empty()) throw ConfigError(plan.slurm_dir() + "/tasks.txt: no task listed");
  return plan;
}

std::string ArraySpec(const std::vector<int>& tasks) {
  std::string spec;
  for (std::size_t i = 0; i < tasks.size();) {
    std::size_t j = i;
    while (j + 1 < tasks.size() && tasks[j + 1] == tasks[j] + 1) ++j;
    if (!spec.empty()) spec += ",";
    spec += std::to_string(tasks[i]) + (j > i ? "-" + std::to_string(tasks[j]) : "");
    i = j + 1;
  }
  return spec;
}

std::string Submit(const ArrayPlan& plan, const std::vector<int>& tasks) {
  const std::string spec = ArraySpec(tasks);
  std::vector<std::string> argv = {"sbatch", "--parsable", "--array=" + spec};
  argv.insert(argv.end(), plan.sbatch_args.begin(), plan.sbatch_args.end());
  argv.push_back(plan.slurm_dir() + "/array.sbatch");
  std::string output;
  const int code = RunCapture(argv, &output);
  if (code == 127) throw std::runtime_error("sbatch: not found (expected Slurm's client commands on this host's PATH)");
  const std::string job = LastLine(output).substr(0, LastLine(output).find(';'));  // "ID" or "ID;CLUSTER"
  if (code != 0 || job.empty() || job.find_first_not_of("0123456789") != std::string::npos) {
    throw std::runtime_error("sbatch failed (exit " + std::to_string(code) + "): " + LastLine(output));
  }
  std::ofstream(plan.slurm_dir() + "/jobs.txt", std::ios::app) << job << " " << spec << "\n";
  return job;
}

std::map<int, std::string> ParseQueue(const std::string& squeue_output, const std::string& job_id) {
  std::map<int, std::string> queue;
  std::istringstream in(squeue_output);
  const std::regex line_re("^\\s*" + job_id + "_\\[?([0-9,\\-]+)(%[0-9]+)?\\]?\\s+(\\S+)");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, line_re)) continue;
    std::stringstream ranges(m[1].str());
    for (std::string r; std::getline(ranges, r, ',');) {
      const auto dash = r.find('-');
      if (r.empty()) continue;
      const int lo = std::stoi(r.substr(0, dash));
      const int hi = dash == std::string::npos ? lo : std::stoi(r.substr(dash + 1));
      for (int k = lo; k <= hi; ++k) queue[k] = m[3].str();
    }
  }
  return queue;
}

TaskStatus ReadTaskStatus(const ArrayPlan& plan, int task, const std::map<int, std::string>& queue) {
  TaskStatus st;
  st.task = task;
  const std::string scenario = plan.scenarios.at(static_cast<std::size_t>(task - 1));
  const std::string run_dir = fs::path(scenario).parent_path().string();
  const std::string out_file = plan.slurm_dir() + "/task-" + std::to_string(task) + ".out";
  const std::string start = LastLine(ReadText(StatusPath(plan, task, "start")));
  if (const auto q = queue.find(task); q != queue.end()) {
    st.state = TaskStatus::State::kQueued;
    st.why = "still in Slurm's queue: " + q->second + (start.empty() ? "" : " (" + start + ")");
    return st;
  }
  if (fs::exists(StatusPath(plan, task, "exit"))) {
    const std::string code = LastLine(ReadText(StatusPath(plan, task, "exit")));
    st.exit_code = code.empty() || code.find_first_not_of("0123456789") != std::string::npos ? -1 : std::stoi(code);
    const bool summary = fs::exists(run_dir + "/summary.json");
    if ((st.exit_code == 0 || st.exit_code == 1) && summary) {
      st.state = TaskStatus::State::kDone;
      return st;
    }
    st.state = TaskStatus::State::kFailed;
    const std::string last = LastLine(ReadText(run_dir + "/runner.log"));
    st.why = "scenario_runner exit " + code + (summary ? "" : ", no summary.json") + " (" +
             Rel(plan, run_dir) + "/runner.log: " + (last.empty() ? "empty" : last) + ")";
    return st;
  }
  const std::string out = ReadText(out_file);
  if (!start.empty()) {
    st.state = TaskStatus::State::kUnfinished;
    const std::string slurm = LastLine(out, "CANCELLED|TIME LIMIT|NODE FAIL|PREEMPT|error|Killed|killed");
    st.why = "started (" + start + ") but recorded no end: " +
             (slurm.empty() ? "killed, or its node lost (nothing in " + Rel(plan, out_file) + ")" : slurm);
    return st;
  }
  if (!out.empty()) {
    st.state = TaskStatus::State::kFailed;
    st.why = "ended before its run started (" + Rel(plan, out_file) + ": " + LastLine(out) + ")";
    return st;
  }
  st.state = TaskStatus::State::kNotStarted;
  st.why = "never started (not submitted, or cancelled while queued)";
  return st;
}

std::vector<TaskStatus> ReadStatuses(const ArrayPlan& plan) {
  std::map<int, std::string> queue;
  std::ifstream jobs(plan.slurm_dir() + "/jobs.txt");
  for (std::string line; std::getline(jobs, line);) {
    const std::string job = line.substr(0, line.find(' '));
    if (job.empty()) continue;
    std::string output;
    if (RunCapture({"squeue", "-h", "-r", "-o", "%i %T", "-j", job}, &output) != 0) continue;
    for (const auto& [task, state] : ParseQueue(output, job)) queue[task] = state;
  }
  std::vector<TaskStatus> statuses;
  for (int k = 1; k <= static_cast<int>(plan.scenarios.size()); ++k) statuses.push_back(ReadTaskStatus(plan, k, queue));
  return statuses;
}

void ClearTask(const ArrayPlan& plan, int task) {
  fs::remove(StatusPath(plan, task, "start"));
  fs::remove(StatusPath(plan, task, "exit"));
  const std::string scenario = plan.scenarios.at(static_cast<std::size_t>(task - 1));
  fs::remove(fs::path(scenario).parent_path() / "summary.json");
}

}  // namespace rover::tools::slurm
