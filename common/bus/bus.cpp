#include "bus/bus.hpp"

#include <cerrno>
#include <iostream>

namespace rover::bus {

Bus::Bus(const std::string& url) : url_(url), lcm_(url) {
  if (!lcm_.good()) {
    throw std::runtime_error("cannot open the LCM bus at " + url +
                             " (expected a working udpm:// URL; is there a multicast route? "
                             "see README, \"The bus\")");
  }
}

bool Bus::Handle(int timeout_ms) {
  const int status = lcm_.handleTimeout(timeout_ms);
  if (pending_error_) {
    std::exception_ptr error = pending_error_;
    pending_error_ = nullptr;
    std::rethrow_exception(error);
  }
  // A signal (SIGTERM from systemd or the launcher) interrupts the wait: not an error.
  if (status < 0 && errno == EINTR) return false;
  if (status < 0) throw std::runtime_error("LCM handle failed on " + url_);
  return status > 0;
}

void Bus::ReportCorrupt(const std::string& channel, const char* type, std::uint32_t size) {
  ++corrupt_count_;
  // Rate-limited: the first few, then every 100th, so a flood cannot fill the disk.
  if (corrupt_count_ <= 5 || corrupt_count_ % 100 == 0) {
    std::cerr << "bus: " << channel << ": dropped a corrupt message of " << size
              << " bytes (expected " << type << "); " << corrupt_count_ << " so far\n";
  }
}

}  // namespace rover::bus
