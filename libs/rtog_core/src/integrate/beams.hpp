// The sensor-model rules, in one place: what a beam is (skipped, cut, returned), where its
// walk ends and what it marks. Every integration path (the general batch, the planar batch)
// goes through these.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/range_noise.hpp"
#include "rtog/core/stats.hpp"

namespace rtog {

enum class BeamEnd { Hit, Truncated, NonFinite, ZeroLength, OutOfRange, TooLong };

class BeamRules {
 public:
  BeamRules(const Lattice& lattice, const InsertParams& ip)
      : lattice_(lattice),
        max_range_(ip.max_range),
        longest_(ip.max_ray_cells * lattice.resolution()),
        bounded_(ip.max_ray_cells > 0),
        discretize_(ip.discretize),
        traces_free_(ip.model != SensorModel::BeamEndPoint) {}

  /// Where a beam from `origin` to `p` ends (cut at max_range: then not returned) and its end
  /// cell. `returned` is false for a beam flagged as no-return.
  BeamEnd classify(const Eigen::Vector3d& origin, const Eigen::Vector3d& p, bool returned, Eigen::Vector3d& end,
                   Key& end_key) const {
    if (!p.allFinite()) return BeamEnd::NonFinite;
    const Eigen::Vector3d diff = p - origin;
    const double dist2 = diff.squaredNorm();
    if (!(dist2 > 0.0)) return BeamEnd::ZeroLength;
    end = p;
    if (max_range_ > 0.0 && std::isfinite(max_range_) && dist2 > max_range_ * max_range_) {
      const double dist = std::sqrt(dist2);
      if (dist > max_range_) {
        end = origin + diff * (max_range_ / dist);
        returned = false;
      }
    }
    if (!lattice_.tryKey(end, end_key)) return BeamEnd::OutOfRange;
    if (bounded_ && (end - origin).squaredNorm() > longest_ * longest_) return BeamEnd::TooLong;
    return returned ? BeamEnd::Hit : BeamEnd::Truncated;
  }

  /// Counts a beam in `stats`; true if it is traced (hit or truncated), false if skipped.
  static bool count(BeamEnd kind, InsertStats& stats) {
    switch (kind) {
      case BeamEnd::Hit: ++stats.rays_hit; return true;
      case BeamEnd::Truncated: ++stats.rays_truncated; return true;
      case BeamEnd::NonFinite: ++stats.skipped_non_finite; return false;
      case BeamEnd::ZeroLength: ++stats.skipped_zero_length; return false;
      case BeamEnd::OutOfRange: ++stats.skipped_out_of_range; return false;
      default: ++stats.skipped_too_long; return false;
    }
  }

  /// Where the free walk of a traced beam ends, in lattice coordinates: the centre of the end
  /// cell with discretized ends (OctoMap's `discretize`), else the end point.
  Eigen::Vector3d walkEnd(const Eigen::Vector3d& end, const Key& end_key) const {
    return discretize_ ? Eigen::Vector3d(end_key.x + 0.5, end_key.y + 0.5, end_key.z + 0.5) : lattice_.toLattice(end);
  }

  /// Marks a traced beam in `batch`: its end cell occupied if it returned; then the cells up to
  /// the end cell free by walk_free(), in the beam model only. With discretized ends, a returned
  /// beam to a cell this batch marked already adds nothing.
  template <class Batch, class WalkFree>
  void mark(bool hit, const Key& end_key, Batch& batch, WalkFree&& walk_free) const {
    if (hit && !batch.markOccupied(end_key) && discretize_) return;
    if (traces_free_) walk_free();
  }

  bool discretize() const { return discretize_; }
  bool tracesFree() const { return traces_free_; }

 private:
  const Lattice& lattice_;
  double max_range_, longest_;
  bool bounded_, discretize_, traces_free_;
};

}  // namespace rtog
