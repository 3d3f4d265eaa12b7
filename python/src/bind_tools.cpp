// rtog.Map's fusion, priors and risk-aware planning, and the readers of the TUM depth frames.
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "py_map.hpp"
#include "rtog/core/plan.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/prior_map_options.h"

namespace rtog::python {
namespace {

PlanOptions planOptions(double te, double ta, double unknown_risk, double radius, double min_z, double max_z) {
  PlanOptions o;
  o.te = te, o.ta = ta, o.unknown_risk = unknown_risk, o.radius = radius, o.min_z = min_z, o.max_z = max_z;
  return o;
}

template <class Result>
pyb::dict planDict(const Result& r, int dims) {
  pyb::array_t<double> path({static_cast<pyb::ssize_t>(r.path.size()), pyb::ssize_t{dims}});
  for (std::size_t i = 0; i < r.path.size(); ++i)
    for (int a = 0; a < dims; ++a) path.mutable_at(pyb::ssize_t(i), a) = r.path[i][a];
  pyb::dict d;
  d["found"] = r.found;
  d["path"] = path;
  d["length"] = r.length;
  d["risk"] = r.risk;
  d["cost"] = r.cost;
  return d;
}

}  // namespace

void bindTools(pyb::module_& m) {
  auto cls = pyb::class_<PyMap, std::shared_ptr<PyMap>>(m.attr("Map"));
  cls.def(
      "fuse",
      [](PyMap& self, const PyMap& other, const pyb::object& pose) {
        if (&self == &other) throw pyb::value_error("fuse: a map cannot be fused into itself");
        const mrpt::poses::CPose3D placed = pose.is_none() ? mrpt::poses::CPose3D() : mrptPose(DoubleArray::ensure(pose), "pose");
        InsertStats s;
        {
          pyb::gil_scoped_release nogil;
          // Both locks at once, so that a.fuse(b) and b.fuse(a) in two threads cannot deadlock.
          std::shared_lock<std::shared_mutex> theirs(other.mutex, std::defer_lock);
          std::unique_lock<std::shared_mutex> mine(self.mutex, std::defer_lock);
          std::lock(theirs, mine);
          s = self.map->fuse(*other.map, placed);
        }
        return statsDict(s);
      },
      pyb::arg("other"), pyb::arg("pose") = pyb::none(),
      R"doc(Fuses another map (robot, sensor, day) into this one by the independent opinion pool: each
cell becomes l1 + l2 - l0, clamped; `other` placed by `pose` ((x, y, yaw), 6 numbers or 4x4) and
resampled into this lattice, its evidence conserved.)doc");
  cls.def(
      "set_cells",
      [](PyMap& self, const Int32Array& min_keys, const Int32Array& max_keys, const FloatArray& log_odds) {
        const std::size_t n = rowsOf(min_keys, 3, "min_keys");
        if (rowsOf(max_keys, 3, "max_keys") != n || log_odds.size() != static_cast<pyb::ssize_t>(n))
          throw pyb::value_error("set_cells: min_keys, max_keys and log_odds must have the same length");
        std::vector<Box> boxes(n);
        for (std::size_t i = 0; i < n; ++i) {
          const std::int32_t *a = min_keys.data() + 3 * i, *b = max_keys.data() + 3 * i;
          boxes[i] = Box{Key{a[0], a[1], a[2]}, Key{b[0], b[1], b[2]}};
        }
        const float* v = log_odds.data();
        return statsDict(self.write([&](CRTreeOccupancyGridMap& map) {
          const InsertStats s = map.map().assignCells(boxes.data(), v, n);
          map.notifyMapChanged();
          return s;
        }));
      },
      pyb::arg("min_keys"), pyb::arg("max_keys"), pyb::arg("log_odds"),
      R"doc(Sets cells to absolute log-odds (a prior from arrays, an imported grid): the cells of box i
(inclusive keys, as leaves() gives them) take log_odds[i]. Boxes must not overlap and values must
lie within the clamping bounds.)doc");
  cls.def(
      "load_prior",
      [](PyMap& self, const std::string& path, double confidence, double resolution, double origin_x, double origin_y) {
        TPriorMapOptions o;
        o.priorMap = path, o.priorConfidence = confidence, o.priorResolution = resolution;
        o.priorOriginX = origin_x, o.priorOriginY = origin_y;
        self.write([&](CRTreeOccupancyGridMap& map) { map.loadPrior(o); });
      },
      pyb::arg("path"), pyb::arg("confidence") = 0.7, pyb::arg("resolution") = 0.05, pyb::arg("origin_x") = 0.0,
      pyb::arg("origin_y") = 0.0,
      R"doc(Starts the map from a prior (doc/priors.md): a .gridmap or an image (white free, black
occupied; `resolution` m per pixel, lower-left corner at origin), trusted to `confidence` in (0.5, 1].)doc");
  cls.def(
      "plan",
      [](const PyMap& self, const DoubleArray& start, const DoubleArray& goal, double te, double ta,
         double unknown_risk, double radius, double min_z, double max_z) {
        if (start.size() != 2 || goal.size() != 2) throw pyb::value_error("plan: start and goal are (x, y)");
        const Eigen::Vector2d a(start.data()[0], start.data()[1]), b(goal.data()[0], goal.data()[1]);
        const PlanOptions o = planOptions(te, ta, unknown_risk, radius, min_z, max_z);
        return planDict(self.read([&](const CRTreeOccupancyGridMap& map) { return planPath2D(map.map(), a, b, o); }), 2);
      },
      pyb::arg("start"), pyb::arg("goal"), pyb::arg("te") = 1.0, pyb::arg("ta") = 1.0, pyb::arg("unknown_risk") = 0.5,
      pyb::arg("radius") = 0.0, pyb::arg("min_z") = -1000.0, pyb::arg("max_z") = 1000.0,
      R"doc(The path of least f(P) = te * sum T(C) + ta * length(P) over the band's columns (A*, exact):
a dict with found, path (K, 2) [m], length, risk, cost. T(C) is a cell's P(occupied), unknown cells
`unknown_risk`; no path cell nearer than `radius` to an occupied one.)doc");
  cls.def(
      "plan_3d",
      [](const PyMap& self, const DoubleArray& start, const DoubleArray& goal, double te, double ta,
         double unknown_risk, double radius) {
        const Eigen::Vector3d a = point3(start, "start"), b = point3(goal, "goal");
        const PlanOptions o = planOptions(te, ta, unknown_risk, radius, -1000.0, 1000.0);
        return planDict(self.read([&](const CRTreeOccupancyGridMap& map) { return planPath3D(map.map(), a, b, o); }), 3);
      },
      pyb::arg("start"), pyb::arg("goal"), pyb::arg("te") = 1.0, pyb::arg("ta") = 1.0, pyb::arg("unknown_risk") = 0.5,
      pyb::arg("radius") = 0.0, "plan() through the cells in 3D (26-connected); path (K, 3).");

  m.def(
      "read_tum",
      [](const std::string& dir) {
        const image::DepthSequence seq = image::readTumSequence(dir);
        pyb::list frames;
        for (const auto& f : seq.frames) {
          pyb::array_t<double> pose({4, 4});
          for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) pose.mutable_at(r, c) = f.camera_to_world.matrix()(r, c);
          frames.append(pyb::make_tuple(f.depth_path, pose));
        }
        return frames;
      },
      pyb::arg("dir"),
      "A TUM RGB-D style sequence (dir/groundtruth_poses.txt): a list of (depth PNG path, 4x4 camera-to-map pose).");
  m.def(
      "read_depth_png",
      [](const std::string& path) {
        cv::Mat d = cv::imread(path, cv::IMREAD_ANYDEPTH);
        if (d.empty()) throw std::runtime_error("cannot read depth image " + path);
        if (d.type() != CV_16UC1) throw std::runtime_error(path + ": expected a 16-bit single-channel PNG");
        pyb::array_t<std::uint16_t> out({d.rows, d.cols});
        for (int r = 0; r < d.rows; ++r) std::memcpy(out.mutable_data(r, 0), d.ptr(r), std::size_t(d.cols) * 2);
        return out;
      },
      pyb::arg("path"), "A 16-bit depth PNG as a uint16 (H, W) array.");
}

}  // namespace rtog::python
