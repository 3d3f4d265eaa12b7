// The `rtog._rtog` extension module: NumPy conversions and error translation, and the parts.
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>

#include <new>

#include "py_map.hpp"
#include "rtog/mrpt/error_line.h"

namespace rtog::python {

std::size_t rowsOf(const pyb::array& a, pyb::ssize_t cols, const char* what) {
  if (a.ndim() == 1 && a.shape(0) == cols) return 1;  // one row given as a vector
  if (a.ndim() != 2 || a.shape(1) != cols)
    throw pyb::value_error(std::string(what) + ": expected an array of shape (N, " + std::to_string(cols) + ")");
  return static_cast<std::size_t>(a.shape(0));
}

Eigen::Vector3d point3(const DoubleArray& a, const char* what) {
  if (a.size() != 3) throw pyb::value_error(std::string(what) + ": expected 3 numbers (x, y, z)");
  const double* p = a.data();
  return {p[0], p[1], p[2]};
}

Eigen::Isometry3d isometry(const DoubleArray& a, const char* what) {
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw pyb::value_error(std::string(what) + ": expected a 4x4 rigid transform");
  Eigen::Matrix4d t;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t(r, c) = a.at(r, c);
  const Eigen::Matrix3d rot = t.topLeftCorner<3, 3>();
  if (!t.allFinite() || !t.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 0.0) ||
      !(rot.transpose() * rot).isIdentity(1e-6) || rot.determinant() < 0)
    throw pyb::value_error(std::string(what) + ": not a rigid transform (rotation orthonormal, last row 0 0 0 1)");
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.matrix() = t;
  return iso;
}

mrpt::poses::CPose3D mrptPose(const DoubleArray& a, const char* what) {
  const double* p = a.data();
  for (pyb::ssize_t i = 0; i < a.size(); ++i)
    if (!std::isfinite(p[i])) throw pyb::value_error(std::string(what) + ": not finite");
  if (a.ndim() == 1 && a.size() == 3) return mrpt::poses::CPose3D(p[0], p[1], 0.0, p[2], 0.0, 0.0);
  if (a.ndim() == 1 && a.size() == 6) return mrpt::poses::CPose3D(p[0], p[1], p[2], p[3], p[4], p[5]);
  if (a.ndim() == 2) {
    const Eigen::Isometry3d iso = isometry(a, what);
    mrpt::math::CMatrixDouble44 h;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) h(r, c) = iso.matrix()(r, c);
    return mrpt::poses::CPose3D(h);
  }
  throw pyb::value_error(std::string(what) + ": expected (x, y, yaw), (x, y, z, yaw, pitch, roll) or a 4x4 matrix");
}

mrpt::poses::CPose3DPDFGaussian mrptPosePdf(const mrpt::poses::CPose3D& mean, const pyb::object& cov) {
  mrpt::poses::CPose3DPDFGaussian pdf;
  pdf.mean = mean;
  pdf.cov.setZero();
  if (cov.is_none()) return pdf;
  const DoubleArray c = DoubleArray::ensure(cov);
  if (!c || c.ndim() != 2 || c.shape(0) != c.shape(1) || (c.shape(0) != 3 && c.shape(0) != 6))
    throw pyb::value_error("pose_cov: expected a 3x3 (x, y, yaw) or 6x6 (x, y, z, yaw, pitch, roll) covariance");
  if (c.shape(0) == 6) {
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) pdf.cov(r, k) = c.at(r, k);
    return pdf;
  }
  // A planar covariance: as MRPT lifts a CPosePDFGaussian (rows x, y, yaw -> x, y, yaw).
  const int idx[3] = {0, 1, 3};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) pdf.cov(idx[r], idx[k]) = c.at(r, k);
  return pdf;
}

pyb::dict statsDict(const InsertStats& s) {
  pyb::dict d;
  d["rays_hit"] = s.rays_hit;
  d["rays_truncated"] = s.rays_truncated;
  d["skipped_non_finite"] = s.skipped_non_finite;
  d["skipped_zero_length"] = s.skipped_zero_length;
  d["skipped_out_of_range"] = s.skipped_out_of_range;
  d["skipped_too_long"] = s.skipped_too_long;
  d["skipped_over_budget"] = s.skipped_over_budget;
  d["cells_occupied"] = s.cells_occupied;
  d["cells_free"] = s.cells_free;
  d["cells_unchanged"] = s.cells_unchanged;
  d["leaves_created"] = s.leaves_created;
  d["leaves_merged"] = s.leaves_merged;
  d["leaves_split"] = s.leaves_split;
  return d;
}

}  // namespace rtog::python

PYBIND11_MODULE(_rtog, m) {
  namespace py = rtog::python;
  m.doc() =
      "rtog: a probabilistic occupancy map stored as an R-tree of cuboids (the C++ library's "
      "MRPT map type, rtog::CRTreeOccupancyGridMap), with NumPy arrays in and out.";
  // A C++ error reaches Python as one line (rtog::errorLine: MRPT's call stacks left out): bad
  // arguments as ValueError, anything else as RuntimeError; pybind11's own pass through.
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const pybind11::error_already_set&) {
      throw;
    } catch (const pybind11::builtin_exception&) {
      throw;
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, rtog::errorLine(e).c_str());
    } catch (const std::domain_error& e) {
      PyErr_SetString(PyExc_ValueError, rtog::errorLine(e).c_str());
    } catch (const std::length_error& e) {
      PyErr_SetString(PyExc_ValueError, rtog::errorLine(e).c_str());
    } catch (const std::out_of_range& e) {
      PyErr_SetString(PyExc_ValueError, rtog::errorLine(e).c_str());
    } catch (const std::exception& e) {
      PyErr_SetString(PyExc_RuntimeError, rtog::errorLine(e).c_str());
    }
  });
  m.attr("UNKNOWN") = static_cast<int>(rtog::CellState::Unknown);
  m.attr("FREE") = static_cast<int>(rtog::CellState::Free);
  m.attr("OCCUPIED") = static_cast<int>(rtog::CellState::Occupied);
  py::bindMap(m);
  py::bindInsert(m);
  py::bindQuery(m);
  py::bindTools(m);
  py::bindImage(m);
}
