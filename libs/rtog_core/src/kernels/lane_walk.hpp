// Walking many short rays at once into a dense window of cells, eight at a time with AVX2 or
// sixteen with AVX-512 (the batch's queued free walks). The marks equal walkRay's, cell for cell.
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

/// Window geometry: whole bricks, a power of two of them along each axis, stored cell-linear
/// (x fastest): a step along an axis moves a cell's index by a constant stride, so that a lane
/// steps with one add. Word i of the window holds the cells 64 i .. 64 i + 63.
struct LaneWindow {
  Key origin;   // brick coordinates of the window's first brick
  int bits[3];  // log2 of the bricks along each axis
  std::size_t bricks() const { return std::size_t{1} << (bits[0] + bits[1] + bits[2]); }
  /// log2 of the index stride of a step along `axis`.
  int shift(int axis) const {
    return axis == 0 ? 0 : axis == 1 ? bits[0] + kBrickBits : bits[0] + bits[1] + 2 * kBrickBits;
  }
  std::int64_t cellIndex(const Key& cell) const {
    std::int64_t i = 0;
    for (int a = 0; a < 3; ++a) i |= (std::int64_t{cell[a]} - std::int64_t{origin[a]} * kBrickSize) << shift(a);
    return i;
  }
};

/// The lane walks: none (each ray walked alone), AVX2 (two groups of four lanes) or AVX-512 (two
/// groups of eight). Their marks are the same.
enum class LaneKernel : std::uint8_t { None, Avx2, Avx512 };

/// The kernel for this CPU: AVX-512 where it is worth it (cpuPrefersAvx512), else AVX2 where the
/// CPU has it, else none.
LaneKernel laneKernel();
/// True if `kernel` runs on this CPU (None always does).
bool laneKernelRuns(LaneKernel kernel);

/// Rays are ordered for the lanes in blocks of this many (a multiple of every kernel's wave).
constexpr std::size_t kWaveBlock = 256;

/// `rays` in an order walkLanes walks well, block by block: a block whose rays are about as long
/// as their neighbours (a depth image's pixels) as given, with shared[block] = 1 (neighbouring
/// rays share cells); else by length (a LiDAR's rings alternate), shared[block] = 0, so that a
/// wave's lanes do not wait long for its longest ray.
void orderForWaves(const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays,
                   std::vector<std::uint32_t>& order, std::vector<std::uint8_t>& shared);

/// Walks queued[i] for each i of `rays` (each leaving its z-layer, inside the window) into
/// `window` (kBrickWords words a brick, cell-linear; the kBrickWords words before it are
/// scratch), setting touched[k] for each run k of kBrickWords words marked. `shared`: as
/// orderForWaves gives it. Only with a kernel other than None that laneKernelRuns().
void walkLanes(LaneKernel kernel, const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays,
               const std::vector<std::uint8_t>& shared, const LaneWindow& w, std::uint64_t* window,
               std::uint8_t* touched);

}  // namespace detail
}  // namespace rtog
