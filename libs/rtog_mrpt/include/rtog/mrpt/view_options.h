// The view, matching and rendering options of rtog::CRTreeOccupancyGridMap (its TGridViewOptions,
// TMatchingOptions and TRenderingOptions), in their own header as the map's class is large:
// every field with its default, the .ini key being the member's name (doc/mrpt_map.md).
#pragma once

#include <cstddef>
#include <string>

#include <mrpt/config/CLoadableOptions.h>

namespace rtog {

/// The 2D view (gridView()): a COccupancyGridMap2D of the cells within a height band.
struct RTreeGridViewOptions : public mrpt::config::CLoadableOptions {
  void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
  void validate() const;  ///< throws std::invalid_argument unless gridView_minZ <= gridView_maxZ
  /// A 2D cell takes the highest log-odds among the observed cells of its column whose height
  /// interval meets [gridView_minZ, gridView_maxZ] [m]; unknown if none. (Default: -1000 / 1000)
  float gridView_minZ{-1000.0f};
  float gridView_maxZ{1000.0f};
};

/// Options for ICP against the map ([<prefix>_matchingOpts]).
struct RTreeMatchingOptions : public mrpt::config::CLoadableOptions {
  void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
  void validate() const;

  /// Height band [m]: determineMatching2D and squareDistanceToClosestCorrespondence pair 2D
  /// points only with occupied cells whose centre z lies in [matching2D_minZ, matching2D_maxZ]
  /// (a 3D map's floor and ceiling are not walls of a 2D scan). (Default: -1000)
  float matching2D_minZ{-1000.0f};
  float matching2D_maxZ{1000.0f};  ///< (Default: 1000)
};

/// How getVisualizationInto draws the map.
struct RTreeRenderingOptions {
  bool showOccupied{true};    ///< Draw occupied cuboids. (Default: true)
  bool showFree{false};       ///< Draw free cuboids, translucent. (Default: false)
  bool colorByHeight{true};   ///< Colour by height (true) or by occupancy (false). (Default: true)
  std::size_t maxBoxes{2000000};  ///< Cap on drawn cuboids. (Default: 2e6)
};

}  // namespace rtog
