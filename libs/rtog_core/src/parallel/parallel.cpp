#include "parallel/parallel.hpp"

#include <exception>
#include <thread>

namespace rtog {
namespace parallel {

void run(std::size_t n, const std::function<void(std::size_t)>& part) {
  if (n == 0) return;
  std::vector<std::exception_ptr> errors(n);
  const auto guarded = [&](std::size_t i) {
    try {
      part(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(n - 1);
  for (std::size_t i = 1; i < n; ++i) workers.emplace_back(guarded, i);
  guarded(0);
  for (auto& w : workers) w.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

void forRanges(std::size_t count, std::size_t parts, const std::function<void(std::size_t, std::size_t)>& fn) {
  if (parts < 2) {
    fn(0, count);
    return;
  }
  run(parts, [&](std::size_t p) { fn(count * p / parts, count * (p + 1) / parts); });
}

namespace {
// Chunk indices in 32 bits: a chunk is at least 256 beams.
std::uint64_t pack(std::size_t front, std::size_t back) {
  return (static_cast<std::uint64_t>(front) << 32) | static_cast<std::uint64_t>(back);
}
}  // namespace

ChunkClaims::ChunkClaims(std::size_t chunks, std::size_t threads) : ranges_((threads + 1) / 2) {
  for (std::size_t r = 0; r < ranges_.size(); ++r)
    ranges_[r].ends.store(pack(chunks * r / ranges_.size(), chunks * (r + 1) / ranges_.size()),
                          std::memory_order_relaxed);
}

std::size_t ChunkClaims::next(std::size_t thread) {
  const bool from_back = thread % 2 == 1;
  for (std::size_t k = 0; k < ranges_.size(); ++k) {
    std::atomic<std::uint64_t>& ends = ranges_[(thread / 2 + k) % ranges_.size()].ends;
    std::uint64_t v = ends.load(std::memory_order_relaxed);
    for (;;) {
      const std::uint64_t front = v >> 32, back = v & 0xFFFFFFFFu;
      if (front >= back) break;
      const std::uint64_t claimed = from_back ? pack(front, back - 1) : pack(front + 1, back);
      if (ends.compare_exchange_weak(v, claimed, std::memory_order_relaxed))
        return static_cast<std::size_t>(from_back ? back - 1 : front);
    }
  }
  return kNone;
}

}  // namespace parallel
}  // namespace rtog
