// Walking many short rays at once into a dense window of bricks, eight at a time with AVX2
// (the batch's queued free walks). The marks equal walkRay's, cell for cell.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "storage/brick.hpp"

namespace rtog {
namespace detail {

/// A ray waiting for a lane walk: from `from` to `to` (lattice coordinates), cells from_key, to_key.
struct QueuedRay {
  Eigen::Vector3d from, to;
  Key from_key, to_key;
};

/// Window geometry: bricks along each axis a power of two, so that a step into the next brick
/// moves a word offset by a shift of the step.
struct LaneWindow {
  Key origin;   // brick coordinates of the window's first brick
  int bits[3];  // log2 of the bricks along each axis
  std::size_t bricks() const { return std::size_t{1} << (bits[0] + bits[1] + bits[2]); }
  std::int64_t wordOffset(const Key& cell) const {
    const std::int64_t bx = (cell.x >> kBrickBits) - origin.x, by = (cell.y >> kBrickBits) - origin.y,
                       bz = (cell.z >> kBrickBits) - origin.z;
    return ((bz << (bits[0] + bits[1])) | (by << bits[0]) | bx) * kBrickWords;
  }
};

/// True where walkLanes() runs (x86-64 with AVX2).
bool laneWalkAvailable();

/// Walks queued[i] for each i of `rays` (each leaving its z-layer, inside the window) into
/// `window` (kBrickWords words a brick; the kBrickWords words before it are scratch), setting
/// touched[b] for each brick b marked. Only where laneWalkAvailable().
void walkLanes(const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays, const LaneWindow& w,
               std::uint64_t* window, std::uint8_t* touched);

}  // namespace detail
}  // namespace rtog
