#include "calib/arguments.hpp"

#include <cstdio>

namespace rover::calib {

void Arguments::Size(int min, const std::string& expected, int* width, int* height) {
  const std::string v = Value();
  char tail = 0;
  if (std::sscanf(v.c_str(), "%dx%d%c", width, height, &tail) != 2 || *width < min || *height < min) {
    throw BadArgument("argument " + option_ + ": \"" + v + "\": expected " + expected);
  }
}

}  // namespace rover::calib
