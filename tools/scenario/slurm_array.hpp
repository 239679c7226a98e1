// A campaign as a Slurm job array (./rover campaign --slurm, ./rover navbench --slurm): the
// files its tasks need in DIR/slurm/, the sbatch submission, and, for the merge, what became
// of each task. No LCM here: the tasks run scenario_runner through ./rover scenario.
//
// DIR/slurm/ holds:
//   plan.yaml      what the tasks run and how the campaign was asked for (the merge reads it)
//   tasks.txt      task K runs the scenario file on line K, into the folder that holds it
//   array.sbatch   the batch script (sbatch --array=1-N array.sbatch runs the campaign)
//   jobs.txt       "JOB_ID ARRAY" for every submission (--slurm, then each --resume)
//   status/K.start "job J_K on HOST at TIME", written as task K starts
//   status/K.exit  scenario_runner's exit status, written as task K ends
//   task-K.out     Slurm's output of task K (a cancellation or time limit is noted there)
#pragma once

#include <map>
#include <string>
#include <vector>

namespace rover::tools::slurm {

struct ArrayPlan {
  std::string out_dir;     // absolute: the campaign's folder
  std::string source_dir;  // absolute: the source tree (its ./rover) as every node sees it
  std::string build_dir;   // absolute: the build (bin/scenario_runner) as every node sees it
  std::string job_name = "rover-campaign";
  bool plot = true;                      // the runs draw their pictures (else --no-plot)
  std::string rate = "max";             // every run's --rate (a number or max); empty: its scenario's sim_rate
  std::vector<std::string> scenarios;    // task K runs scenarios[K - 1] (absolute paths)
  std::vector<std::string> sbatch_args;  // passed to sbatch at every submission
  // How the campaign was asked for (its SCENARIO, --variants, --seed, ...), for the merge.
  std::map<std::string, std::string> settings;
  std::string slurm_dir() const { return out_dir + "/slurm"; }
};

// Writes plan.yaml, tasks.txt and array.sbatch into plan.slurm_dir() (made if missing).
void WritePlan(const ArrayPlan& plan);
// Reads DIR/slurm/plan.yaml. Throws config::ConfigError naming DIR when there is none or it
// is not a plan.
ArrayPlan ReadPlan(const std::string& out_dir);
// The batch script of the array (see the file's comment inside).
std::string ArrayScript(const ArrayPlan& plan);

// Task numbers (1-based) as sbatch's --array value: "1-4", "2,5-7".
std::string ArraySpec(const std::vector<int>& tasks);

// Runs sbatch for `tasks` of the plan (--parsable, the plan's sbatch_args, then `extra`),
// appends the job to jobs.txt and returns its id. Throws std::runtime_error with sbatch's
// own message when it fails or is not installed.
std::string Submit(const ArrayPlan& plan, const std::vector<int>& tasks);

// What became of a task, from its status files, its run folder and the queue.
struct TaskStatus {
  enum class State { kDone, kQueued, kFailed, kUnfinished, kNotStarted };
  int task = 0;
  State state = State::kNotStarted;
  int exit_code = -1;  // scenario_runner's, when the task recorded one
  std::string why;     // one line, for every state but kDone
  bool done() const { return state == State::kDone; }
  bool resubmit() const { return state != State::kDone && state != State::kQueued; }
};

// Task K (1-based) of the plan. `queue` maps a task to its state in Slurm's queue
// ("PENDING", "RUNNING"), for tasks still there. A task is done when it recorded a
// scenario_runner exit of 0 or 1 (1: the run did not end as its scenario expects, a result)
// and its run wrote summary.json.
TaskStatus ReadTaskStatus(const ArrayPlan& plan, int task, const std::map<int, std::string>& queue);
// Every task's status, the queue asked once per submitted job (squeue; nothing when squeue
// is missing or knows none of the jobs).
std::vector<TaskStatus> ReadStatuses(const ArrayPlan& plan);
// The tasks of `squeue -h -r -o "%i %T"` lines of job `job_id`: "12_3 RUNNING" and
// "12_[4-6,8] PENDING" give 3 -> RUNNING, 4, 5, 6, 8 -> PENDING.
std::map<int, std::string> ParseQueue(const std::string& squeue_output, const std::string& job_id);

// Removes task K's status files and its run's summary.json (before it runs again).
void ClearTask(const ArrayPlan& plan, int task);

// `text` as one shell word in single quotes.
std::string ShellQuote(const std::string& text);

}  // namespace rover::tools::slurm
