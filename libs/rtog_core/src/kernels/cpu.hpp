// The one CPU dispatch of the core: the default build targets any x86-64 (SSE2); kernels for
// newer CPUs are compiled with a target attribute and chosen here at run time.
#pragma once

namespace rtog {
namespace detail {

/// True if the CPU runs AVX2 and POPCNT code (every AVX2 CPU has POPCNT).
bool cpuHasAvx2();
/// True if the CPU runs AVX-512F code (with the OS saving its registers).
bool cpuHasAvx512();
/// True if the CPU has AVX-512F and its kernels are faster there than the AVX2 ones: on Intel
/// cores, where masks replace blends of three micro-ops; not on AMD's, which split each 512-bit
/// operation in two (the lane walk measured slower there, doc/performance-notes.md).
bool cpuPrefersAvx512();

}  // namespace detail
}  // namespace rtog
