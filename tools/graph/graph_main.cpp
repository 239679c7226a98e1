// ./rover graph DEPLOYMENT.yaml [--out FILE.svg|png|dot] [--list] [--every-edge]:
// the picture of a process set, built from what each process declares. Every process of
// the deployment is run with its own arguments and --channels (on memq://, so no bus is
// joined): it prints what it publishes and what it subscribes and exits before running.
// Graphviz's `dot` draws the SVG or PNG.
#include "bus/process.hpp"
#include "graph/channel_graph.hpp"
#include "launch/process_set.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

namespace {

using rover::config::ConfigError;

struct Args {
  std::string deployment, out;
  bool list = false, every_edge = false;
};

constexpr const char* kUsage =
    "usage: rover_graph DEPLOYMENT.yaml [--out FILE.svg|FILE.png|FILE.dot] [--list] [--every-edge]\n\n"
    "Draws a process set (configs/deploy/*.yaml): every process, every channel, an arrow from\n"
    "each publisher to its channel and from the channel to each subscriber. Built from what\n"
    "the code declares: each process is run with its deployment arguments and --channels.\n"
    "  --out FILE     .svg or .png (drawn with Graphviz's dot) or .dot; default: DOT on stdout\n"
    "  --list         print one line per declaration instead (NAME publishes|subscribes CHANNEL)\n"
    "  --every-edge   also draw the edges every process has (HEARTBEAT out, ROVER_CLOCK in)\n"
    "Run it from the repository root (deployment paths are relative to it).\n";

Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      std::exit(0);
    } else if (arg == "--list") {
      a.list = true;
    } else if (arg == "--every-edge") {
      a.every_edge = true;
    } else if (arg == "--out") {
      if (i + 1 >= argc || argv[i + 1][0] == '\0') {
        throw ConfigError("rover_graph: argument --out: missing value (expected FILE.svg, FILE.png or FILE.dot)");
      }
      a.out = argv[++i];
    } else if (a.deployment.empty() && arg.rfind("--", 0) != 0) {
      a.deployment = arg;
    } else {
      throw ConfigError("rover_graph: argument " + arg + ": unexpected (expected DEPLOYMENT.yaml [--out FILE] [--list])");
    }
  }
  if (a.deployment.empty()) throw ConfigError("rover_graph: missing argument (expected DEPLOYMENT.yaml)");
  return a;
}

std::string Extension(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? "" : path.substr(dot + 1);
}

std::string ReadAll(int fd) {
  std::string text;
  char buffer[4096];
  ssize_t n;
  while ((n = read(fd, buffer, sizeof buffer)) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) text.append(buffer, static_cast<std::size_t>(n));
  }
  return text;
}

// Runs `argv` with `input` on its stdin (when not null); returns its stdout, its stderr
// and its wait status.
struct Ran {
  std::string out, err;
  int status = 0;
};
Ran Run(const std::vector<std::string>& argv, const std::string* input) {
  int out_pipe[2], err_pipe[2], in_pipe[2];
  if (pipe(out_pipe) != 0 || pipe(err_pipe) != 0 || pipe(in_pipe) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(in_pipe[0], 0);
    dup2(out_pipe[1], 1);
    dup2(err_pipe[1], 2);
    for (int fd : {in_pipe[0], in_pipe[1], out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]}) close(fd);
    unsetenv("ROVER_TIME");  // a listing runs in real time: no barrier, no sync reports
    std::vector<char*> c_argv;
    for (const auto& a : argv) c_argv.push_back(const_cast<char*>(a.c_str()));
    c_argv.push_back(nullptr);
    execvp(c_argv[0], c_argv.data());
    std::fprintf(stderr, "cannot run %s: %s\n", c_argv[0], std::strerror(errno));
    _exit(127);
  }
  close(in_pipe[0]);
  close(out_pipe[1]);
  close(err_pipe[1]);
  if (input != nullptr && write(in_pipe[1], input->data(), input->size()) != static_cast<ssize_t>(input->size())) {
    // dot reads all of it; a short write means it died, and its status says why
  }
  close(in_pipe[1]);
  Ran r;
  r.out = ReadAll(out_pipe[0]);  // the listings are small: stderr cannot fill meanwhile
  r.err = ReadAll(err_pipe[0]);
  close(out_pipe[0]);
  close(err_pipe[0]);
  while (waitpid(pid, &r.status, 0) < 0 && errno == EINTR) {
  }
  return r;
}

std::vector<rover::graph::ProcessChannels> Declarations(const rover::launch::Deployment& d) {
  const std::string bin = rover::launch::BinDir();
  std::vector<rover::graph::ProcessChannels> set;
  for (const auto& spec : d.processes) {
    std::vector<std::string> argv{spec.program.find('/') == std::string::npos ? bin + "/" + spec.program
                                                                               : spec.program};
    argv.insert(argv.end(), spec.args.begin(), spec.args.end());
    argv.insert(argv.end(), {"--channels", "--lcm-url", "memq://"});
    const Ran r = Run(argv, nullptr);
    if (!WIFEXITED(r.status) || WEXITSTATUS(r.status) != 0) {
      const auto first = r.err.substr(0, r.err.find('\n'));
      throw std::runtime_error(d.source + ": process " + spec.name + ": --channels " +
                               rover::launch::DescribeWaitStatus(r.status) + (first.empty() ? "" : ": " + first));
    }
    auto p = rover::graph::ParseListing(r.out, d.source + ": " + spec.name + " --channels");
    p.name = spec.name;  // the deployment's label (a set may run one program twice)
    set.push_back(std::move(p));
  }
  return set;
}

void Write(const Args& a, const std::string& dot) {
  const std::string ext = Extension(a.out);
  if (ext == "dot") {
    std::ofstream f(a.out);
    if (!(f << dot)) throw std::runtime_error("cannot write " + a.out);
    return;
  }
  const Ran r = Run({"dot", "-T" + ext, "-o", a.out}, &dot);
  if (WIFEXITED(r.status) && WEXITSTATUS(r.status) == 127) {
    throw std::runtime_error("Graphviz's dot is not installed (Debian package graphviz; ./rover setup installs it)");
  }
  if (!WIFEXITED(r.status) || WEXITSTATUS(r.status) != 0) {
    throw std::runtime_error("dot -T" + ext + " " + rover::launch::DescribeWaitStatus(r.status) + ": " +
                             r.err.substr(0, r.err.find('\n')));
  }
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("rover_graph", [&]() -> int {
    const Args a = ParseArgs(argc, argv);
    if (!a.out.empty() && Extension(a.out) != "svg" && Extension(a.out) != "png" && Extension(a.out) != "dot") {
      throw ConfigError("rover_graph: argument --out: " + a.out + ": expected a name ending .svg, .png or .dot");
    }
    const auto deployment = rover::launch::LoadDeployment(a.deployment);
    const auto set = Declarations(deployment);
    if (a.list) {
      std::cout << rover::graph::ListText(set);
      return 0;
    }
    rover::graph::DotOptions options;
    options.title = deployment.source;
    options.every_edge = a.every_edge;
    const std::string dot = rover::graph::Dot(set, options);
    if (a.out.empty()) {
      std::cout << dot;
    } else {
      Write(a, dot);
      std::cerr << "rover_graph: wrote " << a.out << "\n";
    }
    return 0;
  });
}
