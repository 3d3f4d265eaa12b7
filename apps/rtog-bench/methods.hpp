// The 3D methods rtog-bench measures: rtog's insertion modes, OctoMap's variants, MRPT's COctoMap
// and dense 3D grid, and a yardstick of the machine, behind one interface.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench.hpp"

namespace octomap {
class OcTree;
}

namespace rtog::bench {

/// A method under test: build() inserts every scan into a fresh map and returns the
/// insertion time; the rest reads the map it built last.
struct Method {
  virtual ~Method() = default;
  virtual std::string name() const = 0;
  virtual double build(const Dataset& d) = 0;
  virtual std::size_t structureBytes() const = 0;
  virtual std::size_t leaves() const = 0;
  virtual double queryNs(const std::vector<Eigen::Vector3d>& pts) const = 0;
  virtual std::size_t fileBytes() const { return 0; }
  virtual const OccupancyMap* rtogMap() const { return nullptr; }
  virtual const octomap::OcTree* octree() const { return nullptr; }
  /// Not a map but a yardstick of the machine, built in the same rounds (no map figures).
  virtual bool calibration() const { return false; }
  /// A build that allocates so much memory (a dense grid: up to 1.7 GB) that the kernel, paging
  /// it in and out, keeps a core busy after it: builds after the other methods' rounds.
  virtual bool heavy() const { return false; }
};

/// Every method on a dataset at a resolution, those `opts.methods` selects.
std::vector<std::unique_ptr<Method>> methodsFor(const Dataset& d, double res, const Options& opts);

}  // namespace rtog::bench
