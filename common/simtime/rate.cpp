#include "simtime/rate.hpp"

#include <cstdlib>

namespace rover::simtime {

bool ParseRate(const std::string& text, double* rate) {
  if (text == "max") {
    *rate = 0.0;
    return true;
  }
  char* end = nullptr;
  const double r = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(r >= kMinRate && r <= kMaxRate)) return false;
  *rate = r;
  return true;
}

}  // namespace rover::simtime
