#pragma once
// Reads an LCM log with LCM's own event reader (lcm_eventlog_read_next_event), from the
// file mapped into memory rather than through a plain FILE.
//
// Why not lcm::LogFile: LCM 1.3's reader peeks at the next event's magic number and seeks
// back 4 bytes (fseeko) after every event, and glibc turns each such seek on a file into an
// lseek system call: 311,616 of them to read the 187 MB log of a 100 m drive, about half a
// second of system time a pass, and the scenario runner reads each log four times. On a
// stream over memory (fmemopen) the same seek stays in the process. The events, their
// order, what is skipped and where each ends (ftello) are LCM's, byte for byte.
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <string>

struct _lcm_eventlog_t;

namespace rover::logcheck {

class LogReader {
 public:
  // Opens and maps `path`; good() says whether that worked.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  bool good() const { return log_ != nullptr || empty_; }
  // The next whole event, valid until the next call; nullptr at the end (as lcm::LogFile).
  const lcm::LogEvent* readNextEvent();
  // The stream, for ftello: where the last event read ended. nullptr for an empty file.
  FILE* getFilePtr();

 private:
  void* map_ = nullptr;
  std::size_t size_ = 0;
  bool empty_ = false;
  _lcm_eventlog_t* log_ = nullptr;
  void* last_ = nullptr;  // lcm_eventlog_event_t*, freed at the next read
  lcm::LogEvent event_{};
};

}  // namespace rover::logcheck
