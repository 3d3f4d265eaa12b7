// rtog.Map: making, copying, reading and writing maps, their options and figures.
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>

#include "py_map.hpp"
#include "rtog/mrpt/map_file.h"
#include "rtog/mrpt/tiled_map.h"

namespace rtog::python {
namespace {

using Options = CRTreeOccupancyGridMap::TInsertionOptions;
constexpr const char* kSection = "insertOpts";

/// An option's value as an .ini states it.
std::string iniValue(const pyb::handle& v) {
  if (pyb::isinstance<pyb::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  return pyb::str(v).cast<std::string>();
}

/// The map Map(resolution, **options) makes. Without sensorModelPreset, or with "octomap", it
/// starts from OctoMap's rule as `rtog build` states it (TInsertionOptions::fromCore); with
/// "mrpt_grid" from the MRPT map's defaults, as an .ini section would. The options are then read
/// as an .ini section holding them is, by the map's own reader: one set of names and checks.
std::shared_ptr<CRTreeOccupancyGridMap> makeMap(double resolution, const pyb::kwargs& kw) {
  MapParams mp;
  mp.resolution = resolution;
  mp.validate();
  const bool grid = kw.contains("sensorModelPreset") && iniValue(kw["sensorModelPreset"]) == "mrpt_grid";
  Options io = grid ? Options{} : Options::fromCore(mp, InsertParams{});
  if (kw.size() > 0) {
    mrpt::config::CConfigFileMemory known, given;
    io.saveToConfigFile(known, kSection);
    std::vector<std::string> keys;
    known.getAllKeys(kSection, keys);
    const std::set<std::string> names(keys.begin(), keys.end());
    for (const auto& [k, v] : kw) {
      const std::string key = pyb::str(k).cast<std::string>();
      if (!names.count(key)) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        throw pyb::value_error("unknown map option '" + key + "' (the insertion options are: " + list + ")");
      }
      given.write(kSection, key, iniValue(v));
    }
    io.loadFromConfigFile(given, kSection);
  }
  io.validate();
  return std::make_shared<CRTreeOccupancyGridMap>(resolution, io);
}

pyb::dict optionsDict(const Options& io) {
  mrpt::config::CConfigFileMemory cfg;
  io.saveToConfigFile(cfg, kSection);
  std::vector<std::string> keys;
  cfg.getAllKeys(kSection, keys);
  pyb::dict d;
  for (const auto& k : keys) d[pyb::str(k)] = cfg.read_string(kSection, k, "");
  return d;
}

pyb::dict mapStats(const MapStatistics& s, double res) {
  pyb::dict d;
  d["leaves"] = s.leaves;
  d["occupied_leaves"] = s.occupied_leaves;
  d["free_leaves"] = s.free_leaves;
  d["cells"] = s.cells;
  d["occupied_cells"] = s.occupied_cells;
  d["free_cells"] = s.free_cells;
  d["bricks"] = s.bricks;
  d["tree_height"] = s.tree_height;
  d["tree_nodes"] = s.tree_nodes;
  d["memory_bytes"] = s.memory_bytes;
  if (!s.bounds.isEmpty()) {
    const Box& b = s.bounds;
    d["bounds_min"] = pyb::make_tuple(b.min.x * res, b.min.y * res, b.min.z * res);
    d["bounds_max"] = pyb::make_tuple((b.max.x + 1) * res, (b.max.y + 1) * res, (b.max.z + 1) * res);
  }
  return d;
}

std::shared_ptr<PyMap> copyOf(const PyMap& self) {
  auto copy = self.read([](const CRTreeOccupancyGridMap& map) { return std::make_shared<CRTreeOccupancyGridMap>(map); });
  return std::make_shared<PyMap>(std::move(copy));
}

}  // namespace

void bindMap(pyb::module_& m) {
  pyb::class_<PyMap, std::shared_ptr<PyMap>>(m, "Map", R"doc(
A probabilistic occupancy map stored as an R-tree of cuboids.

Map(resolution=0.05, **options): an empty map of cells `resolution` metres wide. The options are
the insertion options of the MRPT map type rtreeOccupancyGrid, by their .ini names (doc/mrpt_map.md),
e.g. sensorModelPreset="mrpt_grid" (COccupancyGridMap2D/3D's rule), sensorModel="rangeNoise",
rangeNoiseStd=0.03, maxDistanceInsertion=4.0, poseUncertainty="on", threads=2. Without a preset the
map follows OctoMap's rule as `rtog build` does (hit 0.7, miss 0.4, clamping 0.1192/0.971).
Insertions and queries release the GIL; one map may be queried from several Python threads.
)doc")
      .def(pyb::init([](double resolution, const pyb::kwargs& kw) { return std::make_shared<PyMap>(makeMap(resolution, kw)); }),
           pyb::arg("resolution") = 0.05)
      .def_static(
          "from_ini", [](const std::string& path, const std::string& section) { return std::make_shared<PyMap>(mapFromIni(path, section)); },
          pyb::arg("path"), pyb::arg("section") = "MappingApplication",
          "The rtreeOccupancyGrid map an .ini section defines (rtreeOccupancyGrid_count=1), as MRPT's apps make it.")
      .def_static(
          "load", [](const std::string& path) { return std::make_shared<PyMap>(loadMapFile(path)); }, pyb::arg("path"),
          "Reads a map file of either format: the MRPT map's (.rtog as MRPT's apps and save() write it) or the "
          "core's (rtog build --out, save(format='core')). Raises RuntimeError naming the file and what is wrong.")
      .def_static(
          "load_tiles",
          [](const std::string& dir, const DoubleArray& lo, const DoubleArray& hi) {
            return std::make_shared<PyMap>(loadTiledMap(dir, point3(lo, "lo"), point3(hi, "hi")));
          },
          pyb::arg("dir"), pyb::arg("lo"), pyb::arg("hi"),
          "The tiles of a tiled map (rtog build --tiles) that meet the box [lo, hi] (metres) as one map: a robot's "
          "neighbourhood in a map too large to load whole.")
      .def(
          "save",
          [](const PyMap& self, const std::string& path, const std::string& format) {
            if (format != "mrpt" && format != "core") throw pyb::value_error("format must be 'mrpt' or 'core'");
            self.read([&](const CRTreeOccupancyGridMap& map) {
              if (format == "mrpt") return map.saveToFile(path);
              std::ofstream out(path, std::ios::binary);
              if (!out) throw std::runtime_error("cannot write '" + path + "'");
              map.map().write(out);
              if (!out.flush()) throw std::runtime_error("cannot write '" + path + "'");
            });
          },
          pyb::arg("path"), pyb::arg("format") = "mrpt",
          "Writes the map: format='mrpt' the MRPT map's file with its options (gzip), 'core' the core's "
          "(what `rtog build --out` writes; cells and rule, not the MRPT options).")
      .def(
          "copy", &copyOf,
          "An independent copy.")
      .def("__copy__", &copyOf)
      .def("__deepcopy__", [](const PyMap& self, const pyb::dict&) { return copyOf(self); })
      .def("clear", [](PyMap& self) { self.write([](CRTreeOccupancyGridMap& map) { map.clear(); }); }, "Removes every cell; the options stay.")
      .def_property_readonly("resolution", [](const PyMap& self) { return self.map->resolution(); }, "Cell edge [m].")
      .def_property_readonly("options", [](const PyMap& self) { return optionsDict(self.map->insertionOptions); },
                             "The insertion options as .ini key -> value strings.")
      .def("__len__", [](const PyMap& self) { return self.read([](const CRTreeOccupancyGridMap& map) { return map.map().leafCount(); }); },
           "The number of leaves (cuboids of cells of one value).")
      .def_property_readonly("cell_count", [](const PyMap& self) { return self.read([](const CRTreeOccupancyGridMap& map) { return map.map().cellCount(); }); },
                             "Known cells (a merged cuboid counts all its cells).")
      .def("stats", [](const PyMap& self) {
            const MapStatistics s = self.read([](const CRTreeOccupancyGridMap& map) { return map.map().statistics(); });
            return mapStats(s, self.map->resolution());
          }, "Leaves, cells, bricks, tree and memory figures (what `rtog info` prints), bounds in metres.")
      .def_property_readonly("total_insert_stats", [](const PyMap& self) { return statsDict(self.map->totalInsertStats); },
                             "Every insertion's figures summed.")
      .def("check_invariants", [](const PyMap& self) { return self.read([](const CRTreeOccupancyGridMap& map) { return map.map().checkInvariants(); }); },
           "'' if the R-tree and the brick index are sound, else the first problem found.")
      .def("__repr__", [](const PyMap& self) {
        std::ostringstream s;
        s << "<rtog.Map resolution=" << self.map->resolution() << " preset=" << self.map->insertionOptions.sensorModelPreset
          << " leaves=" << self.read([](const CRTreeOccupancyGridMap& map) { return map.map().leafCount(); }) << ">";
        return s.str();
      });
}

}  // namespace rtog::python
