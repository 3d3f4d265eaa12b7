// The one CPU dispatch of the core: the default build targets any x86-64 (SSE2); kernels for
// newer CPUs are compiled with a target attribute and chosen here at run time.
#pragma once

namespace rtog {
namespace detail {

/// True if the CPU runs AVX2 and POPCNT code (every AVX2 CPU has POPCNT).
bool cpuHasAvx2();

}  // namespace detail
}  // namespace rtog
