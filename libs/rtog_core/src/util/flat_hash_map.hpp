// Open-addressing hash map from 64-bit keys to 32-bit values (linear probing, no erase):
// the per-scan batch and the brick index look up millions of keys per second.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace rtog::detail {

class FlatHashMap64 {
 public:
  static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  void clear() {
    if (size_ == 0) return;
    std::fill(slots_.begin(), slots_.end(), Slot{});
    size_ = 0;
  }

  std::uint32_t find(std::uint64_t key) const {
    if (slots_.empty()) return kAbsent;
    for (std::size_t i = bucket(key);; i = (i + 1) & mask_) {
      const Slot& s = slots_[i];
      if (s.key == key) return s.value;
      if (s.key == kEmpty) return kAbsent;
    }
  }

  /// Returns the value stored for key, inserting `value` first if the key is new.
  std::uint32_t findOrInsert(std::uint64_t key, std::uint32_t value) {
    if ((size_ + 1) * 4 > slots_.size() * 3) grow();
    for (std::size_t i = bucket(key);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.key == key) return s.value;
      if (s.key == kEmpty) {
        s.key = key;
        s.value = value;
        ++size_;
        return value;
      }
    }
  }

  std::size_t memoryBytes() const { return slots_.capacity() * sizeof(Slot); }

 private:
  static constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
  struct Slot {
    std::uint64_t key = kEmpty;
    std::uint32_t value = 0;
  };

  std::size_t bucket(std::uint64_t key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    return static_cast<std::size_t>(key) & mask_;
  }

  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 64 : old.size() * 2, Slot{});
    mask_ = slots_.size() - 1;
    size_ = 0;
    for (const Slot& s : old)
      if (s.key != kEmpty) findOrInsert(s.key, s.value);
  }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

/// A direct-mapped table of recent lookups in front of a slower map (packed key -> 32-bit
/// value): neighbouring beams and scans ask for the same bricks again and again. The index is a
/// multiplicative hash; the bricks of one plane share low bits of x ^ y ^ z and would collide.
/// Its 2^kBits entries are allocated at the first lookup.
template <int kBits>
class RecentLookups {
 public:
  /// The value for `key`: from the table, or lookup() on a miss (kept, replacing the entry).
  template <class Lookup>
  std::uint32_t get(std::uint64_t key, Lookup&& lookup) {
    if (entries_.empty()) entries_.resize(std::size_t{1} << kBits);
    Entry& e = entries_[(key * 0x9E3779B97F4A7C15ull) >> (64 - kBits)];
    if (e.key != key) e = Entry{key, lookup()};
    return e.value;
  }
  /// Forgets every entry (their values are no longer valid).
  void clear() { std::fill(entries_.begin(), entries_.end(), Entry{}); }

 private:
  struct Entry {
    std::uint64_t key = ~std::uint64_t{0};  // no packed key has all 64 bits set
    std::uint32_t value = 0;
  };
  std::vector<Entry> entries_;
};

}  // namespace rtog::detail
