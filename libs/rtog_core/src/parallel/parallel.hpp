// The one place of the core that starts threads. Work is split by the callers into parts
// whose results do not depend on which thread ran them, so a map is the same for any count.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace rtog {
namespace parallel {

/// Runs part(0) .. part(n - 1) and returns when all have returned: part(0) on the calling
/// thread, each other on a thread of its own (a part may wait for another: they all run at
/// once). Rethrows the exception of the lowest part that threw, after all have returned.
void run(std::size_t n, const std::function<void(std::size_t)>& part);

/// Splits [0, count) into `parts` contiguous ranges and runs fn(begin, end) for each, in
/// parallel; parts < 2 runs fn(0, count) here.
void forRanges(std::size_t count, std::size_t parts, const std::function<void(std::size_t, std::size_t)>& fn);

/// Chunks of a scan's beams for threads to claim. A pair of threads shares a range of chunks,
/// one taking chunks from its front and the other from its back: each traces neighbouring beams,
/// which touch the same bricks (a scan's beams come in sweep order), so the two batches share
/// few bricks, and they meet wherever their work balances. A thread whose range is used up
/// helps with the others' from their front (or back).
class ChunkClaims {
 public:
  static constexpr std::size_t kNone = ~std::size_t{0};
  ChunkClaims(std::size_t chunks, std::size_t threads);
  /// The next chunk for `thread`, or kNone when all are taken.
  std::size_t next(std::size_t thread);

 private:
  struct alignas(64) Range {
    std::atomic<std::uint64_t> ends;  // [front, back) in the high and low 32 bits
  };
  std::vector<Range> ranges_;
};

}  // namespace parallel
}  // namespace rtog
