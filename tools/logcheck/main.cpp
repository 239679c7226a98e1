// logcheck LOG.lcm: says whether an LCM log lost messages (./rover logcheck LOG).
//
// Per channel: messages, publishers, and every gap in the publishers' counts (pub_seq, and
// the heartbeat seq), then consistency warnings (a capture with no frame, a VO frame with no
// VO update, a completed motion with no step report) and one verdict line,
// "log complete: yes" or "log complete: no (...)". Exit code 0 when complete, 1 when not,
// 2 when the arguments or the file are bad.
#include "logcheck/log_check.hpp"

#include <iostream>
#include <stdexcept>
#include <string>

int main(int argc, char** argv) {
  std::string path;
  rover::logcheck::TrackerOptions options;
  options.detect_joined = true;  // a recording started after the processes is not lossy
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << "usage: logcheck [--joined | --from-start] LOG.lcm\n\n"
                   "Checks an LCM log for lost messages: per channel and publisher, the counts in\n"
                   "pub_seq (and the heartbeat seq) must run on by one; a count back at 0 is a\n"
                   "restart. Prints counts, gaps, consistency warnings and a verdict line.\n"
                   "A process heard in the log's first 2 s (every process heartbeats once a second)\n"
                   "was running when the recording began: its messages before the log are said,\n"
                   "not counted as lost. A process first heard later must count from 0.\n\n"
                   "  --joined       no publisher's first recorded count need be 0\n"
                   "  --from-start   every publisher's must be (the recording started first)\n\n"
                   "Exit code: 0 complete, 1 not complete, 2 bad arguments or file.\n";
      return 0;
    } else if (arg == "--joined") {
      options.from_start = false;
      options.detect_joined = false;
    } else if (arg == "--from-start") {
      options.from_start = true;
      options.detect_joined = false;
    } else if (path.empty() && arg.rfind("--", 0) != 0) {
      path = arg;
    } else {
      std::cerr << "logcheck: argument " << arg << ": unexpected (expected [--joined | --from-start] LOG.lcm)\n";
      return 2;
    }
  }
  if (path.empty()) {
    std::cerr << "logcheck: missing LOG.lcm (expected [--joined | --from-start] LOG.lcm)\n";
    return 2;
  }
  try {
    const auto report = rover::logcheck::CheckLog(path, options);
    std::cout << rover::logcheck::FormatReport(report);
    return report.complete ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "logcheck: " << e.what() << "\n";
    return 2;
  }
}
