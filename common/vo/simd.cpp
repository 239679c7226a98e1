#include "vo/simd.hpp"

#include <cstdlib>
#include <cstring>

namespace rover::vo {

namespace {

bool forced_portable = false;

// The CPU (and the OS) runs AVX2, and the environment does not ask for the portable path:
// asked once, on first use.
bool Avx2Available() {
  static const bool yes = [] {
    const char* simd = std::getenv("ROVER_VO_SIMD");
    if (simd && std::strcmp(simd, "portable") == 0) return false;
    __builtin_cpu_init();
    return static_cast<bool>(__builtin_cpu_supports("avx2"));
  }();
  return yes;
}

}  // namespace

bool UseAvx2() { return !forced_portable && Avx2Available(); }

void ForcePortableLoops(bool portable) { forced_portable = portable; }

}  // namespace rover::vo
