// The other map of a fusion, placed by a rigid pose and resampled into this map's lattice so that
// its evidence is conserved: each cell of this lattice receives, from each leaf of the other map,
// the leaf's change (l - l0) times the volume of the placed leaf inside the cell over the volume
// of one cell of the other map. Summed over any region of whole cells the evidence is the other
// map's, whatever the pose; a cell centre on a face of the other lattice loses nothing.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "rtog/core/key.hpp"
#include "rtog/core/stats.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

/// The shift in cells that `pose` is, if the lattices are equal, the pose has no rotation and its
/// translation is a whole number of cells (exactly); none otherwise.
std::optional<std::array<std::int64_t, 3>> wholeCellShift(const Lattice& dst, const Lattice& src,
                                                          const Eigen::Isometry3d& pose);

/// The cells of `dst` overlapped by cuboids of `src` placed by a rigid pose, with the overlap's
/// volume in cells of `src`. The pose is classified once: a signed permutation of the axes (the
/// identity, quarter turns, within 1e-12) is products of 1D overlaps; one axis kept (a yaw, or a
/// turn about x or y) is a 2D clip times a 1D overlap; any other rotation clips the cell, a cube
/// turned into the other lattice, by the cuboid's six faces.
class Placement {
 public:
  Placement(const Lattice& dst, const Lattice& src, const Eigen::Isometry3d& pose);
  /// Calls emit(key, volume) for each cell of dst that `box`, placed, overlaps with a positive
  /// volume (in cells of src: the cells of the box sum to its volume). The part beyond the key
  /// range is left out, the box counted once in stats.skipped_out_of_range.
  void overlaps(const Box& box, InsertStats& stats, const std::function<void(const Key&, double)>& emit) const;

 private:
  enum class Kind { Axes, OneAxis, General };
  void axes(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
            const std::function<void(const Key&, double)>& emit) const;
  void oneAxis(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
               const std::function<void(const Key&, double)>& emit) const;
  void general(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
               const std::function<void(const Key&, double)>& emit) const;
  /// The interval of dst lattice coordinates along dst axis `a` of source coordinates [u0, u1]
  /// along the source axis it is aligned with (Axes, or OneAxis's kept axis).
  std::array<double, 2> alignedInterval(int a, double u0, double u1) const;

  Kind kind_;
  Eigen::Matrix3d r_;   // the rotation, snapped to 0 / +-1 where within 1e-12
  Eigen::Vector3d t_;   // the translation in cells of dst
  double scale_;        // a cell of src in cells of dst
  Eigen::Matrix3d back_;     // dst lattice coordinates -> src lattice coordinates: back_ x + back_t_
  Eigen::Vector3d back_t_;
  int axis_of_[3] = {0, 1, 2};  // Axes / OneAxis: the src axis that dst axis a is aligned with (-1: none)
  int kept_ = -1;               // OneAxis: the dst axis kept
};

/// Leaves per block of the resampling: blocks are summed apart (by the threads) and added in
/// order, so the sums do not depend on the thread count.
constexpr std::size_t kResampleBlock = 1024;

/// The other map's evidence in this lattice: per cell, the sum over placed leaves of
/// (l - l0) * overlap volume, in the order the leaves were added (results do not depend on threads).
class ResampledEvidence {
 public:
  void add(const Key& k, double evidence) {
    const auto i = static_cast<std::uint32_t>(keys_.size());
    const std::uint32_t at = index_.findOrInsert(packKey(k), i);
    if (at == i)
      keys_.push_back(k), sums_.push_back(evidence);
    else
      sums_[at] += evidence;
  }
  void clear() {
    index_.clear();
    keys_.clear();
    sums_.clear();
  }
  const std::vector<Key>& keys() const { return keys_; }
  const std::vector<double>& sums() const { return sums_; }

 private:
  detail::FlatHashMap64 index_;
  std::vector<Key> keys_;
  std::vector<double> sums_;
};

}  // namespace rtog
