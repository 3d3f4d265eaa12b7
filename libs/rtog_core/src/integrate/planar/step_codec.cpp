#include "integrate/planar/step_codec.hpp"

#include <cmath>
#include <cstring>

namespace rtog {
namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Whether `v` is k * unit exactly for a whole k in [-127, 127].
bool onLattice(float v, float unit, int& k) {
  if (!std::isfinite(v)) return false;
  const float q = v / unit;  // exact for a power-of-two unit, short of underflow
  if (!(q >= -127.0f && q <= 127.0f) || q != std::nearbyint(q)) return false;
  k = static_cast<int>(q);
  return sameBits(static_cast<float>(k) * unit, v);
}

}  // namespace

bool StepCodec::encode(float v, std::int8_t& c) const {
  int k = 0;
  if (!usable() || !onLattice(v, unit_, k)) return false;
  c = static_cast<std::int8_t>(k);
  return true;
}

StepCodec StepCodec::make(const StepRule& rule, float prior) {
  StepCodec codec;
  // The coarsest power of two that all the rule's numbers and the prior are multiples of.
  for (int e = 4; e >= -24 && !codec.usable(); --e) {
    const float unit = std::ldexp(1.0f, e);
    int k = 0;
    bool all = onLattice(prior, unit, k);
    for (std::size_t i = 0; i < 3 && all; ++i)
      all = onLattice(rule.delta[i], unit, k) && onLattice(rule.limit[i], unit, k) && onLattice(rule.bound[i], unit, k);
    if (all) codec.unit_ = unit;
  }
  if (!codec.usable()) return codec;
  for (int c = -128; c <= 127; ++c)
    codec.values_[index(static_cast<std::int8_t>(c))] = c == kUnknown ? prior : static_cast<float>(c) * codec.unit_;
  // Every step of every code must land on the lattice again; a rule that leaves it is stepped
  // in floats.
  for (std::size_t kind = 0; kind < 3; ++kind)
    for (int c = -128; c <= 127; ++c) {
      const float before = codec.values_[index(static_cast<std::int8_t>(c))];
      const float after = rule.apply(before, static_cast<StepKind>(kind));
      std::int8_t next = 0;
      if (!codec.encode(after, next)) return StepCodec{};
      const std::uint32_t same = sameBits(after, before) ? std::uint32_t{1} << kSameBit : 0u;
      codec.tables_[kind][index(static_cast<std::int8_t>(c))] = same | static_cast<std::uint8_t>(next);
    }
  return codec;
}

}  // namespace rtog
