// A udpm:// URL checked before LCM opens it.
#pragma once

#include <string>

namespace rover::bus {

// What is wrong with a udpm:// URL, in one phrase, or "" when nothing is. LCM 1.3.1 prints
// its own "Error:" lines for a bad group or port and then fails; the Bus and the processes
// refuse such a URL first, with one line of ours. Other providers (file://, memq://) are
// LCM's to judge.
std::string LcmUrlProblem(const std::string& url);

// What a good one looks like, for the error line.
inline constexpr const char* kLcmUrlExpected =
    "udpm://GROUP:PORT?ttl=N, GROUP in 224.0.0.0/4, PORT 1-65535, ttl 0-255";

}  // namespace rover::bus
