// Which vector instructions VO's inner loops take (correlation.cpp's scores, features.cpp's
// grid of corner peaks): AVX2 where the CPU runs it, else the portable loops. Both give the
// same numbers bit for bit (tests run each path: VO3_RowsOfScoresAreBitForBitThePlainArithmetic,
// VO2_GridPeaksAreThePlainScansOfTheResponse, VO1_ThePortableLoopsGiveTheSameMotionBitForBit).
// ROVER_VO_SIMD=portable in the environment takes the portable loops on any CPU, so that a
// run can be checked on the path an older computer takes (any other value, or none: the
// best the CPU has).
#pragma once

namespace rover::vo {

// AVX2 for the loops that have it: the CPU runs it, and the portable path is not forced.
bool UseAvx2();

// Forces the portable loops (true) or gives the choice back to the CPU and the environment
// (false). For tests; not thread-safe against VO running at the same time.
void ForcePortableLoops(bool portable);

// The portable loops for as long as it lives, or the CPU's choice (portable false): a test
// runs its body on each path so.
class PathForScope {
 public:
  explicit PathForScope(bool portable) { ForcePortableLoops(portable); }
  ~PathForScope() { ForcePortableLoops(false); }
  PathForScope(const PathForScope&) = delete;
  PathForScope& operator=(const PathForScope&) = delete;
};

}  // namespace rover::vo
