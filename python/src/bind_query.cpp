// rtog.Map's queries: values at N points, the leaves as arrays, rays, nearest obstacles, the
// continuous field O(x), slices as 2D arrays.
#include <cmath>
#include <limits>
#include <vector>

#include "py_map.hpp"
#include "rtog/core/explore.hpp"
#include "rtog/image/slice.hpp"

namespace rtog::python {
namespace {

/// out[i] = fn(map, point i) for the (N, 3) points, without the GIL.
template <class T, class Fn>
pyb::array_t<T> perPoint(const PyMap& self, const DoubleArray& points, Fn&& fn) {
  const std::size_t n = rowsOf(points, 3, "points");
  pyb::array_t<T> out(static_cast<pyb::ssize_t>(n));
  T* o = out.mutable_data();
  const double* p = points.data();
  self.read([&](const CRTreeOccupancyGridMap& map) {
    for (std::size_t i = 0; i < n; ++i) o[i] = fn(map.map(), Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]));
  });
  return out;
}

}  // namespace

/// A cv::Mat handed to NumPy without a copy: the array keeps the matrix alive.
pyb::array matArray(const cv::Mat& mat) {
  auto* held = new cv::Mat(mat);
  pyb::capsule owner(held, [](void* p) { delete static_cast<cv::Mat*>(p); });
  std::vector<pyb::ssize_t> shape{mat.rows, mat.cols}, strides{static_cast<pyb::ssize_t>(mat.step[0]),
                                                               static_cast<pyb::ssize_t>(mat.elemSize())};
  if (mat.channels() > 1) {
    shape.push_back(mat.channels());
    strides.push_back(static_cast<pyb::ssize_t>(mat.elemSize1()));
  }
  pyb::dtype dt = mat.depth() == CV_8U ? pyb::dtype::of<std::uint8_t>()
                  : mat.depth() == CV_32F ? pyb::dtype::of<float>()
                  : mat.depth() == CV_32S ? pyb::dtype::of<std::int32_t>()
                                          : throw std::logic_error("matArray: unexpected image type");
  return pyb::array(dt, shape, strides, held->data, owner);
}

void bindQuery(pyb::module_& m) {
  auto cls = pyb::class_<PyMap, std::shared_ptr<PyMap>>(m.attr("Map"));
  cls.def(
      "log_odds",
      [](const PyMap& self, const DoubleArray& points) {
        return perPoint<float>(self, points, [](const OccupancyMap& map, const Eigen::Vector3d& p) {
          Key k;
          const auto v = map.lattice().tryKey(p, k) ? map.logOdds(k) : std::nullopt;
          return v ? *v : std::numeric_limits<float>::quiet_NaN();
        });
      },
      pyb::arg("points"), "Log-odds of the cell holding each point (N, 3); NaN where the cell is unknown.");
  cls.def(
      "occupancy",
      [](const PyMap& self, const DoubleArray& points) {
        return perPoint<double>(self, points, [](const OccupancyMap& map, const Eigen::Vector3d& p) {
          Key k;
          return map.lattice().tryKey(p, k) ? map.occupancy(k) : std::numeric_limits<double>::quiet_NaN();
        });
      },
      pyb::arg("points"),
      "P(occupied) of the cell holding each point (N, 3): the prior where unknown, NaN for a point without a cell.");
  cls.def(
      "state",
      [](const PyMap& self, const DoubleArray& points) {
        return perPoint<std::int8_t>(self, points, [](const OccupancyMap& map, const Eigen::Vector3d& p) {
          return static_cast<std::int8_t>(map.stateAt(p));
        });
      },
      pyb::arg("points"), "The class of each point's cell: rtog.UNKNOWN, rtog.FREE or rtog.OCCUPIED (int8).");
  cls.def(
      "field",
      [](const PyMap& self, const DoubleArray& points, const pyb::object& band) {
        const std::size_t n = rowsOf(points, 3, "points");
        double zlo = 0, zhi = 0;
        const bool planar = !band.is_none();
        if (planar) std::tie(zlo, zhi) = band.cast<std::pair<double, double>>();
        pyb::array_t<double> prob(static_cast<pyb::ssize_t>(n));
        pyb::array_t<double> grad({static_cast<pyb::ssize_t>(n), pyb::ssize_t{3}});
        double* pr = prob.mutable_data();
        double* g = grad.mutable_data();
        const double* p = points.data();
        self.read([&](const CRTreeOccupancyGridMap& map) {
          for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3d x(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
            const FieldValue f = planar ? occupancyAt2D(map.map(), x, zlo, zhi) : occupancyAt(map.map(), x);
            pr[i] = f.probability;
            for (int a = 0; a < 3; ++a) g[3 * i + a] = f.gradient[a];
          }
        });
        return pyb::make_tuple(prob, grad);
      },
      pyb::arg("points"), pyb::arg("band") = pyb::none(),
      R"doc(The continuous occupancy field O(x) at each point (N, 3): (P, d log-odds / dx (N, 3)),
log-odds interpolated trilinearly between cell centres, unknown cells at the prior; with
band=(zmin, zmax) bilinearly between the band's columns.)doc");
  cls.def(
      "leaves",
      [](const PyMap& self, const pyb::object& region) {
        std::vector<Box> boxes;
        std::vector<float> values;
        std::optional<Box> r;
        if (!region.is_none()) {
          const Int32Array a = Int32Array::ensure(region);
          if (!a || a.size() != 6) throw pyb::value_error("region: expected keys ((x0, y0, z0), (x1, y1, z1)), inclusive");
          const std::int32_t* k = a.data();
          r = Box{Key{k[0], k[1], k[2]}, Key{k[3], k[4], k[5]}};
        }
        self.read([&](const CRTreeOccupancyGridMap& map) {
          const auto take = [&](const Box& b, float v) {
            boxes.push_back(b);
            values.push_back(v);
          };
          if (r)
            map.map().forEachLeafIn(*r, take);
          else
            map.map().forEachLeaf(take);
        });
        const auto n = static_cast<pyb::ssize_t>(boxes.size());
        pyb::array_t<std::int32_t> lo({n, pyb::ssize_t{3}}), hi({n, pyb::ssize_t{3}});
        pyb::array_t<float> v(n);
        for (pyb::ssize_t i = 0; i < n; ++i) {
          for (int a = 0; a < 3; ++a) {
            lo.mutable_at(i, a) = boxes[std::size_t(i)].min[a];
            hi.mutable_at(i, a) = boxes[std::size_t(i)].max[a];
          }
          v.mutable_at(i) = values[std::size_t(i)];
        }
        return pyb::make_tuple(lo, hi, v);
      },
      pyb::arg("region") = pyb::none(),
      R"doc(The leaves as arrays (min_keys (M, 3) int32, max_keys (M, 3) int32, log_odds (M,) float32):
inclusive cell boxes on the lattice (cell k spans [k, k+1) * resolution metres). `region`, two
inclusive key corners, keeps the leaves meeting it (an R-tree query).)doc");
  cls.def(
      "cast_rays",
      [](const PyMap& self, const DoubleArray& origins, const DoubleArray& directions, double max_range) {
        const std::size_t n = rowsOf(directions, 3, "directions");
        const std::size_t no = rowsOf(origins, 3, "origins");
        if (no != 1 && no != n) throw pyb::value_error("origins: one origin, or one per direction");
        pyb::array_t<bool> hit(static_cast<pyb::ssize_t>(n));
        pyb::array_t<double> dist(static_cast<pyb::ssize_t>(n));
        pyb::array_t<std::int32_t> cell({static_cast<pyb::ssize_t>(n), pyb::ssize_t{3}});
        bool* h = hit.mutable_data();
        double* d = dist.mutable_data();
        std::int32_t* c = cell.mutable_data();
        const double *o = origins.data(), *dir = directions.data();
        self.read([&](const CRTreeOccupancyGridMap& map) {
          for (std::size_t i = 0; i < n; ++i) {
            const double* oi = o + 3 * (no == 1 ? 0 : i);
            const auto r = map.map().castRay(Eigen::Vector3d(oi[0], oi[1], oi[2]),
                                             Eigen::Vector3d(dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]), max_range);
            h[i] = r.hit;
            d[i] = r.hit ? r.distance : std::numeric_limits<double>::infinity();
            for (int a = 0; a < 3; ++a) c[3 * i + a] = r.hit ? r.cell[a] : 0;
          }
        });
        return pyb::make_tuple(hit, dist, cell);
      },
      pyb::arg("origins"), pyb::arg("directions"), pyb::arg("max_range"),
      "The first occupied cell along each ray: (hit (N,) bool, distance [m] (inf if none), cell keys (N, 3)).");
  cls.def(
      "nearest_occupied",
      [](const PyMap& self, const DoubleArray& points, double max_distance) {
        return perPoint<double>(self, points, [max_distance](const OccupancyMap& map, const Eigen::Vector3d& p) {
          const auto r = map.nearestOccupied(p, max_distance);
          return r.found ? r.distance : std::numeric_limits<double>::infinity();
        });
      },
      pyb::arg("points"), pyb::arg("max_distance"),
      "Distance [m] from each point to the nearest occupied leaf within max_distance (inf if none).");
  cls.def(
      "slice",
      [](const PyMap& self, double z, bool probability) {
        const cv::Mat s = self.read([&](const CRTreeOccupancyGridMap& map) {
          return probability ? image::rasterizeSliceProbabilityZ(map.map(), z) : image::rasterizeSliceZ(map.map(), z);
        });
        return matArray(s);
      },
      pyb::arg("z"), pyb::arg("probability") = false,
      R"doc(The layer of cells at height z over the map's x/y bounds, row 0 the highest y: uint8
(H, W) with occupied 0, free 255, unknown 128; probability=True gives BGR (H, W, 3), grey
255 (1 - P), unknown light blue.)doc");
}

}  // namespace rtog::python
