// Comma-separated numbers from a command-line argument ("1.5,-2,30"), for the tools'
// options (poses, sizes, fractions). Every item must be a whole, finite number; the
// caller turns a false return into its one-line usage error.
#pragma once

#include <string>
#include <vector>

namespace rover::config {

// At least one number; false on an empty item, trailing text or a non-finite value.
bool ParseNumberList(const std::string& text, std::vector<double>* out);

// Exactly one number in [lo, hi].
bool ParseNumberInRange(const std::string& text, double lo, double hi, double* out);

// At least one integer, each in [lo, hi].
bool ParseIntList(const std::string& text, int lo, int hi, std::vector<int>* out);

}  // namespace rover::config
