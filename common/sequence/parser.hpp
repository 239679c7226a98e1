// The sequence checker: parses a whole file and reports every error before anything runs.
// An error prints as one line:  file:line:col: message (expected ...)
// Columns are 1-based byte offsets into the line. The parser never throws on bad input
// and never crashes: any byte string gives either a Sequence or errors.
#pragma once

#include "sequence/sequence.hpp"

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rover::sequence {

// Ranges the checker enforces. Defaults follow MER practice (LANGUAGE.md).
struct LanguageLimits {
  double max_step_m = 0.75;             // VO overlap: steps of at most ~75 cm
  double max_turn_per_step_deg = 90.0;  // 18 deg keeps 60 % overlap; larger is allowed
                                        // (the large-turn scenario) but VO may fail
  double max_drive_m = 100.0;           // one drive or arc command
  double min_arc_radius_m = 0.1;        // tighter than this is a turn in place
  double max_arc_radius_m = 1000.0;
  double max_turn_deg = 360.0;          // one turn command
  double max_coordinate_m = 10000.0;    // |x|, |y| of goto targets and zones
  double max_goto_tolerance_m = 10.0;
  double max_time_s = 86400.0;          // any time limit or wait
  double max_distance_limit_m = 10000.0;
  double max_tilt_deg = 45.0;
  int max_vo_failures = 1000;
  int max_vo_retries = 10;              // `vo lost retry N`
  int max_over_steps = 100;
  int max_polygon_vertices = 64;
  int max_line_bytes = 1000;
  int max_errors = 100;                 // stop collecting after this many
};

struct SequenceError {
  std::string source;   // file name
  int line = 0;         // 1-based
  int column = 0;       // 1-based byte column
  std::string message;
  std::string expected;
  // "file:line:col: message (expected ...)"
  std::string ToString() const;
};

struct ParseResult {
  Sequence sequence;                  // valid only when errors is empty
  std::vector<SequenceError> errors;  // in file order
  bool ok() const { return errors.empty(); }
};

ParseResult ParseSequence(std::string_view text, const std::string& source_name,
                          const LanguageLimits& limits = {});

// Thrown by ParseSequenceOrThrow and LoadSequenceFile; what() is the first error's line.
class SequenceCheckError : public std::runtime_error {
 public:
  explicit SequenceCheckError(std::vector<SequenceError> errors);
  const std::vector<SequenceError>& errors() const { return errors_; }

 private:
  std::vector<SequenceError> errors_;
};

Sequence ParseSequenceOrThrow(std::string_view text, const std::string& source_name,
                              const LanguageLimits& limits = {});
// Reads and parses a file; an unreadable file is an error at line 1, column 1.
ParseResult ParseSequenceFile(const std::string& path, const LanguageLimits& limits = {});

}  // namespace rover::sequence
