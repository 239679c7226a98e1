// The conformance kit's verdicts: each rule of a contract (docs/HARDWARE.md, "Contracts")
// passes or fails, and a failure is one line naming the rule, what was expected and what
// was seen. No LCM here: the checks (sensor_checks.hpp, mobility_checks.hpp,
// camera_checks.hpp) judge what a probe recorded, so they are unit-tested on made-up traces.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rover::conformance {

// A rule of a contract: its id (`mobility.deadman.stop`) and what it asks, in one sentence.
struct Rule {
  std::string id;
  std::string text;
};

// The contracts the kit knows: mobility, imu, wheel_odometry, camera.
const std::vector<std::string>& ContractNames();
// The rules of one contract, in the order they are checked. Throws std::invalid_argument
// naming the contract when there is no such one.
const std::vector<Rule>& RulesOf(const std::string& contract);

// The option without which a rule of `contract` is not checked ("--drive" or "--key": its
// text starts so), or "".
std::string NeededOption(const std::string& contract, const std::string& rule);

struct Finding {
  std::string rule;
  std::string expected;
  std::string seen;
};

// "FAIL mobility.deadman.stop: expected ...; seen ..."
std::string FailureLine(const Finding& f);

class Report {
 public:
  // The first failure of a rule is kept; later ones of the same rule add nothing.
  void Fail(const std::string& rule, const std::string& expected, const std::string& seen);
  // A rule that was checked and held (unless it also failed).
  void Pass(const std::string& rule);
  // Pass or Fail; returns `ok`.
  bool Expect(bool ok, const std::string& rule, const std::string& expected, const std::string& seen);

  bool ok() const { return failures_.empty(); }
  bool Failed(const std::string& rule) const;
  bool Passed(const std::string& rule) const;
  const std::vector<Finding>& failures() const { return failures_; }
  // Rules of `contract` neither passed nor failed (a probe that could not run them).
  std::vector<std::string> Unchecked(const std::string& contract) const;

 private:
  std::vector<Finding> failures_;
  std::vector<std::string> passed_;
};

// A number for a line: fixed with `digits` decimals.
std::string Num(double v, int digits = 3);

// When a message was received: wall seconds since the probe started, the message's own
// utime, and the reference clock's rover time at that moment (ROVER_CLOCK extrapolated, or
// the system clock on a bus without one).
struct Stamp {
  double wall_s = 0;
  std::int64_t utime = 0;
  std::int64_t clock_utime = 0;
};

template <class Msg>
struct Received {
  Stamp at;
  Msg msg;
};

}  // namespace rover::conformance
