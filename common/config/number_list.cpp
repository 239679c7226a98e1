#include "config/number_list.hpp"

#include <cmath>
#include <sstream>

namespace rover::config {

bool ParseNumberList(const std::string& text, std::vector<double>* out) {
  out->clear();
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v)) return false;
      out->push_back(v);
    } catch (const std::exception&) {
      return false;  // not a number, or out of double's range
    }
  }
  // getline drops a trailing empty item ("1,2,"): refuse it too.
  return !out->empty() && text.back() != ',';
}

bool ParseNumberInRange(const std::string& text, double lo, double hi, double* out) {
  std::vector<double> v;
  if (!ParseNumberList(text, &v) || v.size() != 1 || v[0] < lo || v[0] > hi) return false;
  *out = v[0];
  return true;
}

bool ParseIntList(const std::string& text, int lo, int hi, std::vector<int>* out) {
  std::vector<double> v;
  out->clear();
  if (!ParseNumberList(text, &v)) return false;
  for (double x : v) {
    if (x != std::floor(x) || x < lo || x > hi) return false;
    out->push_back(static_cast<int>(x));
  }
  return true;
}

}  // namespace rover::config
