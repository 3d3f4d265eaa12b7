// rtog prior: a blueprint image or an MRPT .gridmap as a map's first layer (doc/priors.md).
#include <ostream>
#include <stdexcept>

#include "commands.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::cli {

int prior(const PriorOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("prior: --out FILE is required (where the map goes)");
  if (o.image_path.empty() == o.gridmap_path.empty())
    throw std::invalid_argument("prior: give one of --image FILE or --gridmap FILE");
  TPriorMapOptions p;
  p.priorMap = o.image_path.empty() ? o.gridmap_path : o.image_path;
  p.priorConfidence = o.confidence;
  p.priorResolution = o.resolution;
  p.priorOriginX = o.origin[0];
  p.priorOriginY = o.origin[1];
  // The kind is told by the name, as for priorMap in an .ini: say so rather than misread a file.
  if (!o.gridmap_path.empty() && !p.isGridmap())
    throw std::invalid_argument("prior: --gridmap '" + o.gridmap_path + "' must be named .gridmap or .gridmap.gz");
  if (!o.image_path.empty() && p.isGridmap())
    throw std::invalid_argument("prior: --image '" + o.image_path + "' is named as a .gridmap: use --gridmap");
  p.validate();
  app::OutputSet files({{o.image_path.empty() ? "--gridmap" : "--image", p.priorMap}});
  std::ostream& dst = files.add("--out", o.out_path);
  CRTreeOccupancyGridMap m(o.resolution);
  m.loadPrior(p);
  m.map().write(dst);
  files.commit();
  const auto& f = m.gridFrame();
  out << "prior " << p.priorMap << " (confidence " << p.priorConfidence << "): " << m.map().cellCount() << " known cells, "
      << m.map().leafCount() << " leaves, resolution " << m.resolution() << " m, x " << f.x_min << " .. " << f.x_max
      << " m, y " << f.y_min << " .. " << f.y_max << " m\n"
      << "wrote " << o.out_path << "\n";
  return 0;
}

}  // namespace rtog::cli
