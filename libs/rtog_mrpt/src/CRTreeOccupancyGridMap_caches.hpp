// CRTreeOccupancyGridMap's derived data, kept out of the installed header (the pimpl behind
// CachesHolder) so that the public API names no container of the implementation.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "util/flat_hash_map.hpp"

namespace rtog {

struct CRTreeOccupancyGridMap::ScanAngles {
  std::size_t beams;
  float aperture;
  bool right_to_left;
  std::vector<double> cos, sin;
};

/// Derived data; copies start empty (a copy rebuilds them on demand).
struct CRTreeOccupancyGridMap::Caches {
  std::mutex mutex;
  /// packed key -> likelihood-field term (its float bits): the project's one hash map, which
  /// mixes the key (a packed key's low bits are its x, shared by a block of cells).
  detail::FlatHashMap64 lf;
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
