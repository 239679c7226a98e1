// A udpm:// URL checked before LCM opens it.
#pragma once

#include <set>
#include <string>

namespace rover::bus {

// What is wrong with a udpm:// URL, in one phrase, or "" when nothing is. LCM 1.3.1 prints
// its own "Error:" lines for a bad group or port and then fails; the Bus and the processes
// refuse such a URL first, with one line of ours. Other providers (file://, memq://) are
// LCM's to judge.
std::string LcmUrlProblem(const std::string& url);

// One line to say at start, or "": a udpm:// URL that names no recv_buf_size leaves the
// socket at the kernel's default buffer (about 200 KB), which a stereo pair's fragments
// (hundreds of KB at once) overflow, so the pair is lost without a word from LCM's own
// code. Said by a process (`who`) that takes image channels (STEREO_FRAME, HAZCAM_FRAME)
// or every channel (`all`, a recorder).
std::string SmallReceiveBufferWarning(const std::string& who, const std::string& url,
                                      const std::set<std::string>& subscribed, bool all = false);

// What a good one looks like, for the error line.
inline constexpr const char* kLcmUrlExpected =
    "udpm://GROUP:PORT?ttl=N, GROUP in 224.0.0.0/4, PORT 1-65535, ttl 0-255";

}  // namespace rover::bus
