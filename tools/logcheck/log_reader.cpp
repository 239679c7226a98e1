#include "logcheck/log_reader.hpp"

#include <lcm/eventlog.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>

namespace rover::logcheck {

LogReader::LogReader(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return;
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ == 0) {
    empty_ = true;  // fmemopen takes no empty buffer; an empty log has no events
    ::close(fd);
    return;
  }
  void* map = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) return;
  map_ = map;
  ::madvise(map_, size_, MADV_SEQUENTIAL);
  FILE* f = fmemopen(map_, size_, "r");
  if (f == nullptr) return;
  // LCM's handle is a plain struct (lcm/eventlog.h): its stream and a count.
  log_ = static_cast<lcm_eventlog_t*>(std::calloc(1, sizeof(lcm_eventlog_t)));
  if (log_ == nullptr) {
    std::fclose(f);
    return;
  }
  log_->f = f;
}

LogReader::~LogReader() {
  if (last_ != nullptr) lcm_eventlog_free_event(static_cast<lcm_eventlog_event_t*>(last_));
  if (log_ != nullptr) lcm_eventlog_destroy(log_);  // fclose and free, as for its own
  if (map_ != nullptr) ::munmap(map_, size_);
}

const lcm::LogEvent* LogReader::readNextEvent() {
  if (log_ == nullptr) return nullptr;
  lcm_eventlog_event_t* e = lcm_eventlog_read_next_event(log_);
  if (last_ != nullptr) lcm_eventlog_free_event(static_cast<lcm_eventlog_event_t*>(last_));
  last_ = e;
  if (e == nullptr) return nullptr;
  event_.eventnum = e->eventnum;
  event_.timestamp = e->timestamp;
  event_.channel.assign(e->channel, static_cast<std::size_t>(e->channellen));
  event_.datalen = e->datalen;
  event_.data = e->data;
  return &event_;
}

FILE* LogReader::getFilePtr() { return log_ != nullptr ? log_->f : nullptr; }

}  // namespace rover::logcheck
