// Starting, watching and stopping a set of rover processes (the launcher and the
// scenario runner share this; systemd does the same job on a rover computer).
#pragma once

#include <sys/resource.h>
#include <sys/types.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rover::launch {

struct ProcessSpec {
  std::string name;                // label in output, e.g. "state_estimator"
  std::string program;             // executable; a bare name is looked up in the bin dir
  std::vector<std::string> args;
  std::string host = "";           // the computer it runs on (`host:`); "" in a one-host set
};

struct Deployment {
  std::string source;              // file it came from
  std::string lcm_url;             // empty = the caller's default
  std::vector<ProcessSpec> processes;
  // The host names the processes are assigned to, in order of first appearance; empty
  // when the file names none (the whole set runs on one host). Either every process has
  // `host:` or none has.
  std::vector<std::string> hosts;
  // "virtual" (a set with rover_sim, unless the file's `time:` says "real") or "real":
  // every process gets it as $ROVER_TIME (README, "Simulated time").
  std::string time = "real";
};

// Every process of the set but rover_sim, comma-separated: the clock's barrier.
std::string BarrierMembers(const Deployment& d);
// `spec` as started: in virtual time rover_sim gets `--hold-for` with the barrier's
// members (every other process of the set, on every host) unless the file gives one.
ProcessSpec WithBarrier(const Deployment& d, ProcessSpec spec);

// Reads configs/deploy/*.yaml. Throws config::ConfigError naming the file and key.
Deployment LoadDeployment(const std::string& path);

// The processes of `deployment` that run on `host`. Throws config::ConfigError (one line
// listing the file's host names) when the file has no such host, or names no hosts at all.
std::vector<ProcessSpec> ProcessesOnHost(const Deployment& deployment, const std::string& host);

// The directory holding this executable (build/bin): where process binaries live.
std::string BinDir();

class ProcessSet {
 public:
  // Output of each child goes, line by line, to stdout prefixed "[name] ", and/or to
  // `log_dir`/name.log when `log_dir` is set.
  ProcessSet(std::string bin_dir, std::string log_dir, bool echo);
  ~ProcessSet();
  ProcessSet(const ProcessSet&) = delete;
  ProcessSet& operator=(const ProcessSet&) = delete;

  // Starts a child with extra environment entries ("KEY=VALUE"). Throws on failure.
  // The child gets SIGTERM when the thread that called Start exits, however it exits
  // (PR_SET_PDEATHSIG), so a launcher killed with SIGKILL leaves no process behind: call
  // Start from the thread that lives as long as the set (the main thread).
  void Start(const ProcessSpec& spec, const std::vector<std::string>& env = {});

  // Forwards children's output and reaps exits; waits at most `timeout_ms`.
  // Returns the names of children that exited since the last call, with their status.
  std::vector<std::pair<std::string, std::string>> Poll(int timeout_ms);

  bool Running(const std::string& name) const;
  // Sends `signal` to one child (a test kills a process to prove the abort).
  void Signal(const std::string& name, int signal);
  // SIGTERM to all, then SIGKILL after `grace_ms`; drains remaining output.
  void StopAll(int grace_ms = 3000);
  // Names of children still running.
  std::vector<std::string> RunningNames() const;
  // User + sys CPU seconds of each child that has exited (and been reaped), in start order.
  std::vector<std::pair<std::string, double>> CpuSeconds() const;

 private:
  struct Child {
    std::string name;
    pid_t pid = -1;
    int out_fd = -1;
    std::string partial;
    FILE* log = nullptr;
    bool running = false;
    double cpu_s = 0;  // user + sys, once reaped
  };
  // Reaps `child` (blocking or not); true when it was reaped, with its status and CPU time.
  bool Reap(Child& child, bool block, int* status);
  void Forward(Child& child, bool flush_partial);
  void EmitLine(Child& child, const std::string& line);

  std::string bin_dir_;
  std::string log_dir_;
  bool echo_;
  std::vector<Child> children_;
  std::chrono::steady_clock::time_point next_sweep_{};  // Poll: when every child is asked again
};

// "exited with code 3", "killed by signal 9".
std::string DescribeWaitStatus(int status);

// User + sys CPU seconds of a getrusage/wait4 result.
double CpuSeconds(const rusage& usage);

}  // namespace rover::launch
