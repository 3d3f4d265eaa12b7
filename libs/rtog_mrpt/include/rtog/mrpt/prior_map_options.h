// A prior map for rtog::CRTreeOccupancyGridMap: a blueprint image or an MRPT .gridmap as the
// map's first layer, trusted to a stated confidence (doc/priors.md). Read from the
// [<prefix>_creationOpts] section of a CMultiMetricMap definition; .ini key = member name.
#pragma once

#include <string>

#include <mrpt/config/CLoadableOptions.h>

namespace rtog {

struct TPriorMapOptions : public mrpt::config::CLoadableOptions {
  void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
  /// Throws std::invalid_argument naming the first bad option.
  void validate() const;
  /// Whether priorMap names a .gridmap (by its name: .gridmap or .gridmap.gz), else an image.
  bool isGridmap() const;

  /// The map the new map starts from: a `.gridmap` / `.gridmap.gz` (a serialized
  /// COccupancyGridMap2D: its geometry and cells) or an image that MRPT's CImage reads (PNG,
  /// JPEG, ...; grey read as COccupancyGridMap2D::loadFromBitmapFile reads it: white free,
  /// black occupied, mid-grey unknown). Relative to the working directory. Empty: none.
  /// (Default: "")
  std::string priorMap;
  /// How far the prior is trusted, c in (0.5, 1]: a cell the prior holds with P(occupied) = p
  /// starts at 0.5 + (2c - 1)(p - 0.5), so a black pixel at c, a white one at 1 - c; 1 keeps the
  /// prior's values exactly. (Default: 0.7)
  double priorConfidence{0.7};
  /// Image only: metres per pixel. (Default: 0.05)
  double priorResolution{0.05};
  /// Image only: the map coordinates [m] of the image's lower-left corner. (Default: 0, 0)
  double priorOriginX{0.0}, priorOriginY{0.0};
};

}  // namespace rtog
