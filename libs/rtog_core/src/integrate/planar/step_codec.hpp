// Step rules on a lattice: when a StepRule's deltas, limits and bounds and the prior are whole
// multiples of one power of two within ±127 of it (MRPT's int8 grids: sixteenths), the planar
// cache holds the cells it steps as int8 codes of that unit and steps them by table. The tables
// are StepRule::apply evaluated on every code, so the floats the codes stand for are those the
// float loop would compute, bit for bit.
#pragma once

#include <array>
#include <cstdint>

#include "rtog/core/log_odds.hpp"

namespace rtog {

class StepCodec {
 public:
  /// The code of a cell never observed (its value is the prior); no value has it.
  static constexpr std::int8_t kUnknown = -128;

  /// The codec of `rule` with unknown cells at `prior`; usable() is false if there is none (a
  /// value off every such lattice, or a step leaving it).
  static StepCodec make(const StepRule& rule, float prior);

  bool usable() const { return unit_ != 0.0f; }
  float unit() const { return unit_; }
  float prior() const { return values_[index(kUnknown)]; }
  /// Whether a codec of another rule reads codes as this one does.
  bool sameCodes(const StepCodec& o) const { return unit_ == o.unit_ && prior() == o.prior(); }

  /// The value code `c` stands for (the prior for kUnknown).
  float value(std::int8_t c) const { return values_[index(c)]; }
  /// The code of `v`, or false if `v` is off the lattice (kept as a float, then).
  bool encode(float v, std::int8_t& c) const;
  /// The bit of a table entry that tells whether the value stayed.
  static constexpr int kSameBit = 24;
  /// Per kind, indexed by a code's byte: the code after one step in the low byte, and in bit
  /// kSameBit whether the value stayed (the step's cells_unchanged).
  const std::uint32_t* table(StepKind k) const { return tables_[static_cast<std::size_t>(k)].data(); }
  /// The values of the codes, indexed by a code's byte.
  const float* values() const { return values_.data(); }

  static std::size_t index(std::int8_t c) { return static_cast<std::uint8_t>(c); }

 private:
  float unit_ = 0.0f;
  std::array<float, 256> values_{};
  std::array<std::array<std::uint32_t, 256>, 3> tables_{};
};

}  // namespace rtog
