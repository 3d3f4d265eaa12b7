// CRTreeOccupancyGridMap's derived data, kept out of the installed header (the pimpl behind
// CachesHolder) so that the public API names no container of the implementation.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "grid_tiles.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "util/flat_hash_map.hpp"

namespace rtog {

struct CRTreeOccupancyGridMap::ScanAngles {
  std::size_t beams;
  float aperture;
  bool right_to_left;
  std::vector<double> cos, sin;
};

/// Derived data. A copy shares the 2D view's tiles (the particles of a filter share their map's
/// view that way) and starts without the rest (rebuilt on demand).
struct CRTreeOccupancyGridMap::Caches {
  mutable std::mutex mutex;
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
  /// The 2D view as copy-on-write tiles, in the mrpt_grid preset: followed by grid scans,
  /// dropped by any other change. Owned by this map (its tiles are what copies share).
  std::unique_ptr<GridTiles> tiles;
  /// What the tiles' likelihood reads of the options (COccupancyGridMap2D's own structs).
  mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions tiles_likelihood;
  Caches() = default;
  Caches(const Caches& o) {
    std::lock_guard<std::mutex> lk(o.mutex);
    if (o.tiles) tiles = std::make_unique<GridTiles>(*o.tiles);
  }
  Caches& operator=(const Caches& o) {
    if (this == &o) return *this;
    std::scoped_lock lk(mutex, o.mutex);
    tiles = o.tiles ? std::make_unique<GridTiles>(*o.tiles) : nullptr;
    dropCellData();
    lf_params.reset();
    local_valid = false;
    return *this;
  }
  /// Drops what the map's cells were rendered into (the field's terms, point clouds, the dense
  /// view); the tiles are the caller's to drop or to update. The caller holds `mutex`.
  void dropCellData() {
    lf.clear();
    points_dirty = true;
    band_points_dirty = true;
    grid_view.reset();
  }
};

}  // namespace rtog
