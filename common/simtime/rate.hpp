// A run's pace in virtual time: rover seconds per wall second, or max (as fast as the
// barrier allows). rover_sim takes it (--rate, sim.rate); the scenario campaign checks the
// --rate it hands every run against the same range before starting any.
#pragma once

#include <string>

namespace rover::simtime {

constexpr double kMinRate = 0.1, kMaxRate = 10000.0;
// What ParseRate accepts, for error messages.
constexpr const char* kRateExpected = "max or a number in [0.1, 10000]";

// "max" gives 0; a number in [kMinRate, kMaxRate] gives itself. False for anything else.
bool ParseRate(const std::string& text, double* rate);

}  // namespace rover::simtime
