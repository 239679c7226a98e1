// ./rover launch DEPLOYMENT.yaml: starts a process set, prefixes each process's output
// with its name, and stops everything cleanly on Ctrl-C. A process that dies on its own
// is reported and the launcher exits non-zero (after stopping the rest).
//
// A deployment split over several computers gives every process a `host:`; each computer
// runs `launcher DEPLOYMENT.yaml --host NAME` to start its share (README, "Several hosts").
#include "bus/process.hpp"
#include "launch/lcm_url.hpp"
#include "launch/process_set.hpp"

#include <csignal>
#include <cstdlib>
#include <iostream>

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("launcher", [&]() -> int {
    std::string deployment_path, url, host;
    bool has_host = false, list = false;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << "usage: launcher DEPLOYMENT.yaml [--host NAME] [--lcm-url URL] [--list]\n\n"
                     "Starts the processes listed in DEPLOYMENT.yaml (see configs/deploy/),\n"
                     "prefixes their output with their names, and stops them on Ctrl-C.\n"
                     "--host NAME: start only the processes with `host: NAME` (a set split over\n"
                     "several computers; their bus needs ttl=1, see README \"Several hosts\").\n"
                     "--lcm-url URL: the bus (default: the file's lcm_url, else $ROVER_LCM_URL,\n"
                     "else " << rover::bus::kDefaultLcmUrl << ").\n"
                     "--list: print the processes it would start (name, program, host), start none.\n";
        return 0;
      } else if (arg == "--list") {
        list = true;
      } else if (arg == "--lcm-url" || arg == "--host") {
        if (i + 1 >= argc || argv[i + 1][0] == '\0') {
          throw rover::config::ConfigError("launcher: argument " + arg + ": missing value (expected " +
                                           (arg == "--host" ? "NAME" : "URL") + ")");
        }
        (arg == "--host" ? host : url) = argv[++i];
        if (arg == "--host") has_host = true;
      } else if (deployment_path.empty() && arg.rfind("--", 0) != 0) {
        deployment_path = arg;
      } else {
        throw rover::config::ConfigError(
            "launcher: argument " + arg +
            ": unexpected (expected DEPLOYMENT.yaml [--host NAME] [--lcm-url URL] [--list])");
      }
    }
    if (deployment_path.empty()) {
      throw rover::config::ConfigError("launcher: missing argument (expected DEPLOYMENT.yaml)");
    }
    const auto deployment = rover::launch::LoadDeployment(deployment_path);
    std::vector<rover::launch::ProcessSpec> processes = deployment.processes;
    if (has_host) {
      try {
        processes = rover::launch::ProcessesOnHost(deployment, host);
      } catch (const rover::config::ConfigError& e) {
        throw rover::config::ConfigError(std::string("launcher: --host ") + host + ": " + e.what());
      }
    }
    if (list) {  // for scripts (configs/systemd/install.sh --host): one process a line
      for (const auto& p : processes) {
        std::cout << p.name << " " << p.program << " " << (p.host.empty() ? "-" : p.host) << "\n";
      }
      return 0;
    }
    if (url.empty()) url = deployment.lcm_url;
    std::vector<std::string> env;
    if (!url.empty()) env.push_back("ROVER_LCM_URL=" + url);
    env.push_back("ROVER_TIME=" + deployment.time);
    // The bus the processes will open (bus/process.hpp: --lcm-url, else the environment).
    const char* env_url = std::getenv("ROVER_LCM_URL");
    const std::string bus_url =
        !url.empty() ? url : (env_url != nullptr && *env_url != '\0' ? env_url : rover::bus::kDefaultLcmUrl);
    if (!deployment.hosts.empty()) {
      std::string names;
      for (const auto& h : deployment.hosts) names += (names.empty() ? "" : ", ") + h;
      if (has_host) {
        std::cout << "launcher: host " << host << ": " << processes.size() << " of "
                  << deployment.processes.size() << " processes (hosts: " << names << ") on " << bus_url
                  << "\n";
      } else {
        std::cout << "launcher: no --host: starting the processes of every host (" << names
                  << ") here, on " << bus_url << "\n";
      }
      const auto info = rover::launch::ParseLcmUrl(bus_url);
      if (has_host && info.udpm && info.ttl == 0) {
        std::cerr << "launcher: warning: " << bus_url
                  << " has ttl=0: the bus stays on this host, so the processes of the other hosts"
                  << " will not hear these, nor these them (use ttl=1 on every host)\n";
      }
    }

    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    rover::launch::ProcessSet set(rover::launch::BinDir(), "", true);
    for (const auto& spec : processes) {
      set.Start(rover::launch::WithBarrier(deployment, spec), env);
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
