// CRTreeOccupancyGridMap's derived data, kept out of the installed header (the pimpl behind
// CachesHolder) so that the public API names no third-party hash map.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include <tsl/robin_map.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

/// std::hash of an integer is the identity in libstdc++, and robin_map picks a bucket by the low
/// bits: a packed key's low bits are its x, so a block of cells would share a few buckets. The
/// splitmix64 finalizer spreads every bit of the key over the bucket index.
struct MixedKeyHash {
  std::size_t operator()(std::uint64_t k) const noexcept {
    k ^= k >> 30;
    k *= 0xbf58476d1ce4e5b9ULL;
    k ^= k >> 27;
    k *= 0x94d049bb133111ebULL;
    k ^= k >> 31;
    return static_cast<std::size_t>(k);
  }
};

struct CRTreeOccupancyGridMap::ScanAngles {
  std::size_t beams;
  float aperture;
  bool right_to_left;
  std::vector<double> cos, sin;
};

/// Derived data; copies start empty (a copy rebuilds them on demand).
struct CRTreeOccupancyGridMap::Caches {
  std::mutex mutex;
  tsl::robin_map<std::uint64_t, float, MixedKeyHash> lf;  ///< packed key -> likelihood-field term
  std::optional<FieldParams> lf_params;  ///< what the terms in `lf` were computed with
  bool points_dirty{true};
  mrpt::maps::CSimplePointsMap occupied_points;
  bool band_points_dirty{true};
  float band_lo{0}, band_hi{0};  ///< the band `band_points` holds
  mrpt::maps::CSimplePointsMap band_points;
  /// Sensor-frame points of the last decoded observation (Velodyne raw packets, depth image),
  /// so that evaluating one observation at many poses (particle filters) decodes it once. Keyed
  /// by content: addresses and timestamps are reused by different scans.
  bool local_valid{false};
  std::uint64_t local_key{0};
  std::vector<Eigen::Vector3f> local_points;
  std::size_t local_invalid{0};
  /// cos/sin of the beam angles of the last 2D scan geometry (a log's scans share one), so
  /// that a scan is turned into points without trigonometry, as MRPT's grids do.
  std::shared_ptr<const ScanAngles> scan_angles;
  std::shared_ptr<GridView> grid_view;  ///< gridView(); reset when the map changes
  Caches() = default;
  Caches(const Caches&) {}
  Caches& operator=(const Caches&) {
    std::lock_guard<std::mutex> lk(mutex);
    lf.clear();
    lf_params.reset();
    points_dirty = true;
    band_points_dirty = true;
    local_valid = false;
    grid_view.reset();
    return *this;
  }
};

}  // namespace rtog
