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

/// The skeleton of every integrator's tracing: `count` work items in chunks of `chunk`, claimed
/// (ChunkClaims) by `threads` threads. Each thread t calls begin(t), then trace(t, first, n,
/// counts[t]) for each chunk it claims, then finish(t). A trace that returns false stops every
/// thread at its next chunk (finish is then skipped: the caller drops what was traced). Returns
/// whether all chunks were traced. The counts are per thread, summed by the caller in thread
/// order: the split of the work among threads must not change what the callers produce.
template <class Counts, class Begin, class Trace, class Finish>
bool traceChunks(std::size_t count, std::size_t chunk, std::vector<Counts>& counts, Begin&& begin, Trace&& trace,
                 Finish&& finish) {
  const std::size_t threads = counts.size();
  ChunkClaims claims((count + chunk - 1) / chunk, threads);
  std::atomic<bool> stopped{false};
  run(threads, [&](std::size_t t) {
    Counts own{};  // counted locally: neighbouring entries of `counts` share a cache line
    begin(t);
    for (std::size_t c; (c = claims.next(t)) != ChunkClaims::kNone;) {
      if (stopped.load(std::memory_order_relaxed)) break;
      if (!trace(t, c * chunk, chunk < count - c * chunk ? chunk : count - c * chunk, own)) {
        stopped.store(true, std::memory_order_relaxed);
        break;
      }
    }
    if (!stopped.load(std::memory_order_relaxed)) finish(t);
    counts[t] = own;
  });
  return !stopped.load();
}

}  // namespace parallel
}  // namespace rtog
