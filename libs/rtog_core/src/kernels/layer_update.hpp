// The planar cache's layer update, the innermost loop of 2D insertion, in a portable form and
// in one for CPUs with AVX2 (chosen at run time); tests hold them to the same results.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace rtog {
namespace detail {

/// What a layer update adds to a scan's counts.
struct LayerCounts {
  std::size_t unchanged = 0, free = 0, occupied = 0;
};

/// Updates a 16 x 16 layer's cells (`values`, `known`: 4 mask words) from a tile's marks
/// (`occupied` winning over `free`), deltas = {hit, miss, clamp low, clamp high}.
using UpdateLayerFn = void (*)(float* values, std::uint64_t* known, const std::uint64_t* occupied,
                               const std::uint64_t* free, const float deltas[4], LayerCounts& counts);

/// {portable (SSE2 where compiled for it), AVX2 or null when the CPU lacks it}.
std::array<UpdateLayerFn, 2> layerUpdateKernels();
/// The fastest of layerUpdateKernels() this CPU runs (chosen once).
UpdateLayerFn bestLayerUpdate();

}  // namespace detail
}  // namespace rtog
