// A copy-on-write pointer: copies share the object; write() clones it first if another copy
// holds it. Maps share their bricks and index this way, so that copying a map (a particle
// filter resampling its particles) copies pointers, and a write clones only what it touches.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <utility>

namespace rtog::detail {

template <class T>
class CowPtr {
 public:
  CowPtr() : p_(std::make_shared<T>()) {}
  explicit CowPtr(T value) : p_(std::make_shared<T>(std::move(value))) {}
  /// No object until the first write() (a default-constructed T then).
  explicit CowPtr(std::nullptr_t) {}

  explicit operator bool() const { return p_ != nullptr; }
  const T& operator*() const { return *p_; }
  const T* operator->() const { return p_.get(); }
  const T* get() const { return p_.get(); }

  /// The object for writing, cloned first if another copy shares it. Not to be called while
  /// another thread reads or copies this pointer (a write to its owner); other owners of the
  /// shared object may meanwhile read it, copy or drop their pointers.
  T& write() {
    if (!p_) {
      p_ = std::make_shared<T>();
    } else if (p_.use_count() != 1) {
      p_ = std::make_shared<T>(*p_);
    } else {
      // The last other owner dropped it: its reads happen before our writes (as Rust's
      // Arc::get_mut orders them), which use_count()'s relaxed load alone would not give.
      // (ThreadSanitizer models no fences and warns of them: left out of its builds.)
#if !defined(__SANITIZE_THREAD__)
      std::atomic_thread_fence(std::memory_order_acquire);
#endif
    }
    return *p_;
  }
  /// Replaces the object (no clone of the old one).
  void reset(T value) { p_ = std::make_shared<T>(std::move(value)); }
  /// Drops this copy's object (null until the next write()).
  void drop() { p_.reset(); }
  /// True if another copy holds the object.
  bool shared() const { return p_.use_count() > 1; }

 private:
  std::shared_ptr<T> p_;
};

}  // namespace rtog::detail
