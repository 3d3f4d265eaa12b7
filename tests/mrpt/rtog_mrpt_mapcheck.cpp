// Loads a .rtog file written by an MRPT app (through our code), checks it and prints its
// statistics as `key value` lines. Exit 0 iff the map loads, is sound and has at least
// --min-occupied occupied cells.
// `rtog_mrpt_mapcheck --build RAWLOG PREFIX RESOLUTION` instead inserts every observation of an
// observation-only rawlog (robot at the origin) and saves the map's representation files
// (PREFIX.rtog, PREFIX.3Dscene, PREFIX_slice.png), e.g. a 3D scene for SceneViewer3D.
// `rtog_mrpt_mapcheck --prior-kept WITH.rtog SCANS.rtog PRIOR CONFIDENCE` checks a map an app made
// with `priorMap = PRIOR` against the same app's map of the scans alone: every cell of the prior
// (made here by loadPrior on a map with WITH's options) is in WITH, bit for bit where the scans
// never reached; every cell of SCANS is in WITH. SCANS is made on the prior's lattice with a
// prior of no known cell: `rtog_mrpt_mapcheck --blank-gridmap IN OUT` writes IN's geometry with every
// cell at 0.5.
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/serialization/CArchive.h>

#include "map_cells.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace {

int priorKept(const std::string& with_file, const std::string& scans_file, const std::string& prior_file,
              double confidence) {
  const auto with = rtog::CRTreeOccupancyGridMap::loadFromFile(with_file);
  const auto scans = rtog::CRTreeOccupancyGridMap::loadFromFile(scans_file);
  rtog::CRTreeOccupancyGridMap prior(*with);  // WITH's lattice and options
  prior.clear();
  rtog::TPriorMapOptions o;
  o.priorMap = prior_file;
  o.priorConfidence = confidence;
  prior.loadPrior(o);
  const auto cw = rtog::test::cellsOf(with->map()), cs = rtog::test::cellsOf(scans->map()),
             cp = rtog::test::cellsOf(prior.map());
  const std::map<std::uint64_t, float> withOf(cw.begin(), cw.end()), scanOf(cs.begin(), cs.end());
  std::size_t untouched = 0, updated = 0, missing = 0, changed = 0, scans_missing = 0;
  for (const auto& [key, v] : cp) {
    const auto w = withOf.find(key);
    if (w == withOf.end()) {
      ++missing;
    } else if (scanOf.count(key)) {
      ++updated;
    } else {
      ++untouched;
      changed += w->second != v;
    }
  }
  for (const auto& [key, v] : cs) scans_missing += withOf.count(key) == 0;
  std::cout << "prior_cells " << cp.size() << "\nscan_cells " << cs.size() << "\nmap_cells " << cw.size()
            << "\nprior_untouched " << untouched << "\nprior_updated " << updated << "\nprior_missing " << missing
            << "\nprior_untouched_changed " << changed << "\nscan_cells_missing " << scans_missing << "\ninvariants "
            << (with->map().checkInvariants().empty() ? "ok" : with->map().checkInvariants()) << "\n";
  const bool ok = !cp.empty() && missing == 0 && changed == 0 && scans_missing == 0 && untouched > 0 &&
                  with->map().checkInvariants().empty();
  return ok ? 0 : 1;
}

int blankGridmap(const std::string& in, const std::string& out) {
  mrpt::maps::COccupancyGridMap2D g;
  {
    mrpt::io::CFileGZInputStream f(in);
    auto ar = mrpt::serialization::archiveFrom(f);
    ar >> g;
  }
  for (unsigned y = 0; y < g.getSizeY(); ++y) {
    auto* row = g.getRow(static_cast<int>(y));
    for (unsigned x = 0; x < g.getSizeX(); ++x) row[x] = 0;  // log-odds 0: P = 0.5, unknown
  }
  mrpt::io::CFileGZOutputStream f(out);
  auto ar = mrpt::serialization::archiveFrom(f);
  ar << g;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--blank-gridmap") {
    try {
      return blankGridmap(argv[2], argv[3]);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
  }
  if (argc == 6 && std::string(argv[1]) == "--prior-kept") {
    try {
      return priorKept(argv[2], argv[3], argv[4], std::atof(argv[5]));
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
  }
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
