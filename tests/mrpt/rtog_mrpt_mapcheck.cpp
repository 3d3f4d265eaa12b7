// Loads a .rtog file written by an MRPT app (through our code), checks it and prints its
// statistics as `key value` lines. Exit 0 iff the map loads, is sound and has at least
// --min-occupied occupied cells.
// `rtog_mrpt_mapcheck --build RAWLOG PREFIX RESOLUTION` instead inserts every observation of an
// observation-only rawlog (robot at the origin) and saves the map's representation files
// (PREFIX.rtog, PREFIX.3Dscene, PREFIX_slice.png), e.g. a 3D scene for SceneViewer3D.
#include <cstdlib>
#include <iostream>
#include <string>

#include <mrpt/obs/CRawlog.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: rtog_mrpt_mapcheck <file.rtog> [--min-occupied N]\n";
    return 2;
  }
  if (std::string(argv[1]) == "--build" && argc == 5) {
    try {
      mrpt::obs::CRawlog rl;
      if (!rl.loadFromRawLogFile(argv[2])) throw std::runtime_error(std::string("cannot read ") + argv[2]);
      rtog::CRTreeOccupancyGridMap m(std::atof(argv[4]));
      m.insertionOptions.maxDistanceInsertion = 40;
      std::size_t inserted = 0;
      for (std::size_t i = 0; i < rl.size(); ++i)
        if (rl.getType(i) == mrpt::obs::CRawlog::etObservation && m.insertObservation(*rl.getAsObservation(i)))
          ++inserted;
      m.saveMetricMapRepresentationToFile(argv[3]);
      std::cout << "inserted " << inserted << "\n" << m.asString() << "\n";
      return inserted ? 0 : 1;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
  }
  long long min_occupied = 1;
  for (int i = 2; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--min-occupied") min_occupied = std::atoll(argv[i + 1]);
  try {
    const auto m = rtog::CRTreeOccupancyGridMap::loadFromFile(argv[1]);
    const auto s = m->map().statistics();
    const std::string problem = m->map().checkInvariants();
    std::cout << "resolution " << m->resolution() << "\nleaves " << s.leaves << "\noccupied_cells " << s.occupied_cells
              << "\nfree_cells " << s.free_cells << "\ninvariants " << (problem.empty() ? "ok" : problem) << "\n";
    if (!problem.empty() || s.occupied_cells < min_occupied) return 1;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
