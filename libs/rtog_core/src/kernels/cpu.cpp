#include "kernels/cpu.hpp"

namespace rtog {
namespace detail {

bool cpuHasAvx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  return avx2;
#else
  return false;
#endif
}

bool cpuHasAvx512() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  static const bool avx512 = __builtin_cpu_supports("avx512f");
  return avx512;
#else
  return false;
#endif
}

bool cpuPrefersAvx512() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  static const bool prefer = cpuHasAvx512() && __builtin_cpu_is("intel");
  return prefer;
#else
  return false;
#endif
}

}  // namespace detail
}  // namespace rtog
