// A vector of trivially copyable values that keeps up to N of them inline: a brick's leaf-node
// handles are one or two for most bricks, and a heap block each cost a malloc per brick when
// the upper tree is rebuilt (19,609 bricks for one VLP-16 scan) and 16 bytes of heap overhead.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

namespace rtog::detail {

template <class T, std::uint32_t N>
class SmallVector {
  static_assert(std::is_trivially_copyable_v<T>, "SmallVector holds trivially copyable values");

 public:
  SmallVector() = default;
  SmallVector(const SmallVector& other) { assign(other); }
  SmallVector(SmallVector&& other) noexcept { steal(other); }
  SmallVector& operator=(const SmallVector& other) {
    if (this != &other) {
      size_ = 0;
      assign(other);
    }
    return *this;
  }
  SmallVector& operator=(SmallVector&& other) noexcept {
    if (this != &other) {
      release();
      steal(other);
    }
    return *this;
  }
  ~SmallVector() { release(); }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Bytes held on the heap (none while the values fit inline).
  std::size_t heapBytes() const { return onHeap() ? std::size_t{capacity_} * sizeof(T) : 0; }
  T& operator[](std::size_t i) { return data()[i]; }
  const T& operator[](std::size_t i) const { return data()[i]; }
  T& back() { return data()[size_ - 1]; }
  void push_back(const T& v) {
    if (size_ == capacity_) grow(2 * std::size_t{capacity_});
    data()[size_++] = v;
  }
  void pop_back() { --size_; }
  /// New values are value-initialized.
  void resize(std::size_t n) {
    if (n > capacity_) grow(n);
    if (n > size_) std::fill(data() + size_, data() + n, T{});
    size_ = static_cast<std::uint32_t>(n);
  }

 private:
  bool onHeap() const { return capacity_ > N; }
  T* data() { return onHeap() ? heap_ : inline_; }
  const T* data() const { return onHeap() ? heap_ : inline_; }
  void grow(std::size_t want) {
    const auto cap = static_cast<std::uint32_t>(std::max<std::size_t>(want, N + 1));
    T* fresh = std::allocator<T>().allocate(cap);
    std::memcpy(fresh, data(), std::size_t{size_} * sizeof(T));
    release();
    heap_ = fresh;
    capacity_ = cap;
  }
  void release() {
    if (onHeap()) std::allocator<T>().deallocate(heap_, capacity_);
    capacity_ = N;
  }
  void assign(const SmallVector& other) {
    if (other.size_ > capacity_) grow(other.size_);
    std::memcpy(data(), other.data(), std::size_t{other.size_} * sizeof(T));
    size_ = other.size_;
  }
  void steal(SmallVector& other) {
    size_ = other.size_;
    capacity_ = other.capacity_;
    if (other.onHeap()) {
      heap_ = other.heap_;
    } else {
      std::memcpy(inline_, other.inline_, std::size_t{size_} * sizeof(T));
    }
    other.size_ = 0;
    other.capacity_ = N;
  }

  std::uint32_t size_ = 0;
  std::uint32_t capacity_ = N;  // N while inline
  union {
    T inline_[N];
    T* heap_;
  };
};

}  // namespace rtog::detail
