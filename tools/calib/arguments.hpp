// The command lines of calib_import and calib_check: options as `--name VALUE`, --help,
// and one-line errors that name the option ("argument --size: \"12\": expected ...").
#pragma once

#include <stdexcept>
#include <string>

namespace rover::calib {

struct BadArgument : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Arguments {
 public:
  Arguments(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Moves to the next option; false when there is none left.
  bool Next() {
    if (++i_ >= argc_) return false;
    option_ = argv_[i_];
    return true;
  }
  const std::string& option() const { return option_; }
  bool IsHelp() const { return option_ == "--help" || option_ == "-h"; }

  // The option's value: the next word.
  std::string Value() {
    if (i_ + 1 >= argc_) throw BadArgument("argument " + option_ + ": missing value");
    return argv_[++i_];
  }

  // The option's value as WIDTHxHEIGHT, each at least `min`; `expected` says what it is.
  void Size(int min, const std::string& expected, int* width, int* height);

  BadArgument Unknown() const {
    return BadArgument("argument " + option_ + ": unknown option (expected one of the options in --help)");
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string option_;
};

}  // namespace rover::calib
