// ./rover launch DEPLOYMENT.yaml: starts a process set, prefixes each process's output
// with its name, and stops everything cleanly on Ctrl-C. A process that dies on its own
// is reported and the launcher exits non-zero (after stopping the rest).
#include "bus/process.hpp"
#include "launch/process_set.hpp"

#include <csignal>
#include <iostream>

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("launcher", [&]() -> int {
    std::string deployment_path, url;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << "usage: launcher DEPLOYMENT.yaml [--lcm-url URL]\n\n"
                     "Starts the processes listed in DEPLOYMENT.yaml (see configs/deploy/),\n"
                     "prefixes their output with their names, and stops them on Ctrl-C.\n";
        return 0;
      } else if (arg == "--lcm-url" && i + 1 < argc) {
        url = argv[++i];
      } else if (deployment_path.empty() && arg.rfind("--", 0) != 0) {
        deployment_path = arg;
      } else {
        throw rover::config::ConfigError("launcher: argument " + arg +
                                         ": unexpected (expected DEPLOYMENT.yaml [--lcm-url URL])");
      }
    }
    if (deployment_path.empty()) {
      throw rover::config::ConfigError("launcher: missing argument (expected DEPLOYMENT.yaml)");
    }
    const auto deployment = rover::launch::LoadDeployment(deployment_path);
    if (url.empty()) url = deployment.lcm_url;
    std::vector<std::string> env;
    if (!url.empty()) env.push_back("ROVER_LCM_URL=" + url);

    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    rover::launch::ProcessSet set(rover::launch::BinDir(), "", true);
    for (const auto& spec : deployment.processes) {
      set.Start(spec, env);
      std::cout << "launcher: started " << spec.name << "\n";
    }
    int code = 0;
    while (!g_stop) {
      const auto exited = set.Poll(100);
      if (!exited.empty()) {
        for (const auto& [name, how] : exited) {
          std::cerr << "launcher: " << name << " " << how << " unexpectedly; stopping the set\n";
        }
        code = 1;
        break;
      }
    }
    set.StopAll();
    std::cout << "launcher: all processes stopped\n";
    return code;
  });
}
