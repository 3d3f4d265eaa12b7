// A vector of fixed-size chunks: growing never moves or copies what it holds, so a pool of
// large elements (the planar cache's 1 KiB layers, an update batch's 1 KiB brick masks) costs
// one first touch per element instead of the copies and fresh pages of each doubling, and
// clear() keeps the chunks for the next scan. A chunk is allocated uninitialized and each element
// is value-initialized when appended: a scan that touches three bricks writes three masks, not a
// zero-filled chunk of 256 (256 KiB, in fresh pages, for every short-lived map).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

namespace rtog {
namespace detail {

template <class T, std::size_t kChunk>
class ChunkedVector {
 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t capacity() const { return chunks_.size() * kChunk; }
  T& operator[](std::size_t i) { return chunks_[i / kChunk][i % kChunk]; }
  const T& operator[](std::size_t i) const { return chunks_[i / kChunk][i % kChunk]; }
  /// Appends a value-initialized element (zeroed, for the plain structs held here) and returns it.
  T& emplaceBack() {
    if (size_ == capacity()) chunks_.push_back(std::unique_ptr<T[]>(new T[kChunk]));
    T& e = (*this)[size_++];
    e = T();
    return e;
  }
  /// Empties, keeping the chunks.
  void clear() { size_ = 0; }
  /// Empties and frees the chunks.
  void release() {
    chunks_.clear();
    chunks_.shrink_to_fit();
    size_ = 0;
  }

 private:
  std::vector<std::unique_ptr<T[]>> chunks_;
  std::size_t size_ = 0;
};

}  // namespace detail
}  // namespace rtog
