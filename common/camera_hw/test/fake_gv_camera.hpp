// arv-fake-gv-camera-0.8 (aravis-tools), Aravis's simulated GigE Vision camera, as a child
// process bound to one loopback address, so that a test can kill and restart it.
#pragma once

#include <string>
#include <sys/types.h>

namespace rover::camera_hw::test {

class FakeGvCamera {
 public:
  static constexpr const char* kProgram = "arv-fake-gv-camera-0.8";
  static bool Installed();  // on the PATH

  FakeGvCamera(std::string address, std::string serial) : address_(std::move(address)), serial_(std::move(serial)) {}
  ~FakeGvCamera() { Kill(); }
  FakeGvCamera(const FakeGvCamera&) = delete;
  FakeGvCamera& operator=(const FakeGvCamera&) = delete;

  // Starts it and waits (up to 5 s) until its control port answers a discovery; false if it did not.
  // `lost_per_thousand`: GVSP packets the fake drops on purpose (its -r option).
  bool Start(int lost_per_thousand = 0);
  void Kill();  // SIGKILL, as a camera losing power; waits for the process
  bool running() const { return pid_ > 0; }

 private:
  std::string address_, serial_;
  pid_t pid_ = -1;
};

}  // namespace rover::camera_hw::test
