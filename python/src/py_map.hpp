// The Python module's view of a map, and the NumPy conversions its bindings share.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::python {

namespace pyb = pybind11;

/// A map as Python holds it: the MRPT map type, so that the presets, sensor models and option
/// names are exactly the C++ ones, and a lock. Insertions take it alone, queries share it; both
/// run with the GIL released, so Python threads query one map in parallel and never see a
/// half-made insertion.
struct PyMap {
  std::shared_ptr<CRTreeOccupancyGridMap> map;
  mutable std::shared_mutex mutex;

  explicit PyMap(std::shared_ptr<CRTreeOccupancyGridMap> m) : map(std::move(m)) {}

  /// fn(map) without the GIL, alone.
  template <class Fn>
  auto write(Fn&& fn) {
    pyb::gil_scoped_release nogil;
    std::unique_lock<std::shared_mutex> lock(mutex);
    return fn(*map);
  }
  /// fn(map) without the GIL, beside other readers.
  template <class Fn>
  auto read(Fn&& fn) const {
    pyb::gil_scoped_release nogil;
    std::shared_lock<std::shared_mutex> lock(mutex);
    return fn(static_cast<const CRTreeOccupancyGridMap&>(*map));
  }
};

// ---- NumPy in (C-contiguous views; forcecast copies only what is not of the type already) ----
using FloatArray = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>;
using DoubleArray = pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast>;
using Int32Array = pyb::array_t<std::int32_t, pyb::array::c_style | pyb::array::forcecast>;
using ByteArray = pyb::array_t<std::uint8_t, pyb::array::c_style | pyb::array::forcecast>;

/// The rows of an (N, cols) array; throws ValueError naming `what` otherwise.
std::size_t rowsOf(const pyb::array& a, pyb::ssize_t cols, const char* what);
/// A point from a sequence of 3 numbers.
Eigen::Vector3d point3(const DoubleArray& a, const char* what);
/// A rigid pose from a 4x4 matrix (its last row 0 0 0 1, its rotation orthonormal).
Eigen::Isometry3d isometry(const DoubleArray& a, const char* what);
/// A robot pose as MRPT states it: (x, y, yaw) or (x, y, z, yaw, pitch, roll), or a 4x4 matrix.
mrpt::poses::CPose3D mrptPose(const DoubleArray& a, const char* what);
/// The pose with its covariance: None (certain), 3x3 over (x, y, yaw) or 6x6 over
/// (x, y, z, yaw, pitch, roll), MRPT's order.
mrpt::poses::CPose3DPDFGaussian mrptPosePdf(const mrpt::poses::CPose3D& mean, const pyb::object& cov);

/// A cv::Mat as a NumPy array without a copy: the array keeps the matrix alive.
pyb::array matArray(const cv::Mat& mat);

/// An insertion's figures as a dict (InsertStats' field names).
pyb::dict statsDict(const InsertStats& s);

void bindMap(pyb::module_& m);
void bindInsert(pyb::module_& m);
void bindQuery(pyb::module_& m);
void bindTools(pyb::module_& m);
void bindImage(pyb::module_& m);

}  // namespace rtog::python
