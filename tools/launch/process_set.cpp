#include "launch/process_set.hpp"

#include "config/yaml_config.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <thread>

namespace rover::launch {
namespace {

bool ValidHostName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') return false;
  }
  return true;
}

}  // namespace

Deployment LoadDeployment(const std::string& path) {
  const auto root = config::ConfigNode::LoadFile(path);
  root.CheckKeys({"lcm_url", "processes", "description", "time"});
  Deployment d;
  d.source = path;
  root.Get("lcm_url", d.lcm_url);
  std::string time;
  // system: the system clock, no time source (rover_sim, if any, as the rover's hardware).
  root.GetEnum("time", time, {"virtual", "real", "system"});
  const auto list = root["processes"];
  if (!list.IsSequence() || list.size() == 0) {
    list.Fail("expected a non-empty list of processes (name, args)");
  }
  for (std::size_t i = 0; i < list.size(); ++i) {
    const auto item = list.at(i);
    item.CheckKeys({"name", "program", "args", "host"});
    ProcessSpec spec;
    spec.name = item.RequireString("name");
    spec.program = spec.name;
    item.Get("program", spec.program);
    if (item.Has("args")) {
      const auto args = item["args"];
      if (!args.IsSequence()) args.Fail("expected a list of arguments");
      for (std::size_t k = 0; k < args.size(); ++k) spec.args.push_back(args.at(k).AsString());
    }
    if (item.Has("host")) {
      spec.host = item.RequireString("host");
      if (!ValidHostName(spec.host)) {
        item["host"].Fail("expected a host name (letters, digits, '.', '_' or '-')");
      }
    }
    for (const auto& other : d.processes) {
      if (other.name == spec.name) item.Fail("duplicate process name \"" + spec.name + "\"");
    }
    // All or none: a process left without a host in a split set would run nowhere.
    if (i > 0 && spec.host.empty() != d.processes.front().host.empty()) {
      item.Fail(spec.host.empty() ? "missing host (expected host: NAME on every process, as processes[0] has)"
                                  : "host: given here but not on processes[0] (expected it on every process or on none)");
    }
    if (!spec.host.empty() && std::find(d.hosts.begin(), d.hosts.end(), spec.host) == d.hosts.end()) {
      d.hosts.push_back(spec.host);
    }
    d.processes.push_back(spec);
  }
  // A set with the simulator runs in virtual time unless the file says `time: real`.
  bool simulated = false;
  for (const auto& p : d.processes) simulated = simulated || p.name == "rover_sim";
  // Without the simulator there is no clock on the bus: the system clock (a rover).
  d.time = !time.empty() ? time : simulated ? "virtual" : "system";
  if (d.time == "virtual" && !simulated) root["time"].Fail("virtual time needs rover_sim in the set (its clock)");

  return d;
}

std::string BarrierMembers(const Deployment& d) {
  std::string members;
  for (const auto& p : d.processes)
    if (p.name != "rover_sim") members += (members.empty() ? "" : ",") + p.name;
  return members;
}

ProcessSpec WithBarrier(const Deployment& d, ProcessSpec spec) {
  if (d.time != "virtual" || spec.name != "rover_sim" ||
      std::find(spec.args.begin(), spec.args.end(), "--hold-for") != spec.args.end())
    return spec;
  spec.args.push_back("--hold-for");
  spec.args.push_back(BarrierMembers(d));
  return spec;
}

std::vector<ProcessSpec> ProcessesOnHost(const Deployment& deployment, const std::string& host) {
  if (deployment.hosts.empty()) {
    throw config::ConfigError(deployment.source + ": no host \"" + host +
                              "\": this deployment assigns no process a host (it runs whole on one "
                              "host: leave out --host)");
  }
  std::vector<ProcessSpec> on_host;
  for (const auto& p : deployment.processes) {
    if (p.host == host) on_host.push_back(p);
  }
  if (on_host.empty()) {
    std::string names;
    for (const auto& h : deployment.hosts) names += (names.empty() ? "" : ", ") + h;
    throw config::ConfigError(deployment.source + ": no host \"" + host + "\" (expected one of: " +
                              names + ")");
  }
  return on_host;
}

std::string BinDir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this executable's directory");
  return exe.parent_path().string();
}

std::string DescribeWaitStatus(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")";
  }
  return "stopped";
}

ProcessSet::ProcessSet(std::string bin_dir, std::string log_dir, bool echo)
    : bin_dir_(std::move(bin_dir)), log_dir_(std::move(log_dir)), echo_(echo) {}

ProcessSet::~ProcessSet() { StopAll(1000); }

void ProcessSet::Start(const ProcessSpec& spec, const std::vector<std::string>& env) {
  const std::string program =
      spec.program.find('/') == std::string::npos ? bin_dir_ + "/" + spec.program : spec.program;
  if (access(program.c_str(), X_OK) != 0) {
    throw std::runtime_error(spec.name + ": cannot execute " + program +
                             " (expected a built process; run ./rover build)");
  }
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    // Die with the launcher, even when it is killed with SIGKILL and cannot stop us: the
    // kernel sends SIGTERM (a clean exit: the executor commands STOP on its way out) when
    // the thread that forked this child exits. The flag survives execv. If the parent died
    // before the prctl took effect, no signal will come: leave now.
    if (prctl(PR_SET_PDEATHSIG, SIGTERM) != 0 || getppid() != parent) _exit(1);
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    // Nothing else of the parent's: LCM opens its sockets without close-on-exec, and a
    // child holding the launcher's bus socket has two on the bus's port (which of them is
    // its own cannot be told, so its channel filter stays off: bus/kernel_filter.hpp).
    if (close_range(3, ~0U, 0) != 0) {
      for (int fd = 3; fd < 1024; ++fd) close(fd);
    }
    setpgid(0, 0);
    for (const auto& e : env) putenv(const_cast<char*>(e.c_str()));
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(program.c_str()));
    for (const auto& a : spec.args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(program.c_str(), argv.data());
    std::fprintf(stderr, "cannot exec %s: %s\n", program.c_str(), std::strerror(errno));
    _exit(127);
  }
  close(fds[1]);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  Child child;
  child.name = spec.name;
  child.pid = pid;
  child.out_fd = fds[0];
  child.running = true;
  if (!log_dir_.empty()) {
    child.log = std::fopen((log_dir_ + "/" + spec.name + ".log").c_str(), "w");
  }
  children_.push_back(std::move(child));
}

void ProcessSet::EmitLine(Child& child, const std::string& line) {
  if (echo_) std::cout << "[" << child.name << "] " << line << "\n" << std::flush;
  if (child.log != nullptr) {
    std::fprintf(child.log, "%s\n", line.c_str());
    std::fflush(child.log);
  }
}

void ProcessSet::Forward(Child& child, bool flush_partial) {
  if (child.out_fd < 0) return;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(child.out_fd, buf, sizeof(buf));
    if (n > 0) {
      child.partial.append(buf, static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) {  // the child closed its output
      close(child.out_fd);
      child.out_fd = -1;
      flush_partial = true;
    }
    break;
  }
  std::size_t pos;
  while ((pos = child.partial.find('\n')) != std::string::npos) {
    EmitLine(child, child.partial.substr(0, pos));
    child.partial.erase(0, pos + 1);
  }
  if (flush_partial && !child.partial.empty()) {
    EmitLine(child, child.partial);
    child.partial.clear();
  }
}

std::vector<std::pair<std::string, std::string>> ProcessSet::Poll(int timeout_ms) {
  std::vector<pollfd> fds;
  std::vector<std::size_t> owner;  // the child of each pollfd
  for (std::size_t i = 0; i < children_.size(); ++i) {
    if (children_[i].out_fd < 0) continue;
    fds.push_back({children_[i].out_fd, POLLIN, 0});
    owner.push_back(i);
  }
  if (!fds.empty()) {
    poll(fds.data(), fds.size(), timeout_ms);
  } else if (timeout_ms > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
  }
  // A child whose output pipe is open and quiet has not exited (its exit closes the pipe,
  // and poll says so): its read and its wait4 are skipped, two system calls a child on
  // every pass, which the scenario runner makes once or more an instant. Every child is
  // still asked every 100 ms, in case one left its output open in a process of its own.
  std::vector<bool> stirred(children_.size(), fds.empty());
  for (std::size_t f = 0; f < fds.size(); ++f) stirred[owner[f]] = fds[f].revents != 0;
  const auto now = std::chrono::steady_clock::now();
  const bool sweep = now >= next_sweep_;
  if (sweep) next_sweep_ = now + std::chrono::milliseconds(100);
  std::vector<std::pair<std::string, std::string>> exited;
  for (std::size_t i = 0; i < children_.size(); ++i) {
    Child& c = children_[i];
    if (!stirred[i] && c.out_fd >= 0 && !sweep) continue;
    Forward(c, false);
    if (!c.running) continue;
    int status = 0;
    if (Reap(c, false, &status)) {
      Forward(c, true);
      exited.emplace_back(c.name, DescribeWaitStatus(status));
    }
  }
  return exited;
}

bool ProcessSet::Running(const std::string& name) const {
  for (const auto& c : children_)
    if (c.name == name) return c.running;
  return false;
}

std::vector<std::string> ProcessSet::RunningNames() const {
  std::vector<std::string> names;
  for (const auto& c : children_)
    if (c.running) names.push_back(c.name);
  return names;
}

void ProcessSet::Signal(const std::string& name, int signal) {
  for (auto& c : children_) {
    if (c.name == name && c.running) kill(c.pid, signal);
  }
}

double CpuSeconds(const rusage& usage) {
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

bool ProcessSet::Reap(Child& child, bool block, int* status) {
  rusage ru{};
  if (wait4(child.pid, status, block ? 0 : WNOHANG, &ru) != child.pid) return false;
  child.cpu_s = launch::CpuSeconds(ru);
  child.running = false;
  return true;
}

std::vector<std::pair<std::string, double>> ProcessSet::CpuSeconds() const {
  std::vector<std::pair<std::string, double>> cpu;
  for (const auto& c : children_)
    if (!c.running && c.pid > 0) cpu.emplace_back(c.name, c.cpu_s);
  return cpu;
}

void ProcessSet::StopAll(int grace_ms) {
  for (auto& c : children_)
    if (c.running) kill(c.pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(grace_ms);
  while (!RunningNames().empty() && std::chrono::steady_clock::now() < deadline) {
    Poll(20);
  }
  for (auto& c : children_) {
    if (c.running) {
      EmitLine(c, "did not stop within " + std::to_string(grace_ms) + " ms; killing it");
      kill(c.pid, SIGKILL);
      int status = 0;
      Reap(c, true, &status);
    }
    Forward(c, true);
    if (c.out_fd >= 0) {
      close(c.out_fd);
      c.out_fd = -1;
    }
    if (c.log != nullptr) {
      std::fclose(c.log);
      c.log = nullptr;
    }
  }
}

}  // namespace rover::launch
