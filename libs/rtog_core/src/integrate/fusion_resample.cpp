// Placing the other map of a fusion by a rigid pose, with the exact overlap of each placed cuboid
// and each cell of this lattice. Coordinates are lattice coordinates (a cell is a unit cube);
// distances are measured in src cells so that a cuboid's overlaps sum to its cell count.
#include "integrate/fusion_resample.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace rtog {

namespace {

// Within this of a whole number of cells, an end of an aligned interval is that number: the pose's
// float rounding (0.3 / 0.1 = 2.9999999999999996) must not leave slivers of 1e-16 in a neighbour.
constexpr double kSnapCells = 1e-9;

double snap(double x) {
  const double r = std::round(x);
  return std::fabs(x - r) < kSnapCells ? r : x;
}

/// [from, to] cells of a lattice coordinate interval [x0, x1), clamped to the keys before the
/// conversion to integers (a far pose gives coordinates of 1e19); false if none is left.
bool cellRange(double x0, double x1, std::int64_t& from, std::int64_t& to, bool& beyond) {
  constexpr double kMin = kKeyMin, kMax = kKeyMax;
  const double f = std::floor(x0), t = std::ceil(x1) - 1.0;
  beyond = beyond || !(f >= kMin) || !(t <= kMax);
  const double cf = std::max(f, kMin), ct = std::min(t, kMax);
  if (!(cf <= ct)) return false;
  from = static_cast<std::int64_t>(cf), to = static_cast<std::int64_t>(ct);
  return true;
}

Key keyOf(std::int64_t x, std::int64_t y, std::int64_t z) {
  return Key{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), static_cast<std::int32_t>(z)};
}

/// Length of [x0, x1] inside cell c.
double overlap1(double x0, double x1, std::int64_t c) {
  return std::min(x1, double(c) + 1.0) - std::max(x0, double(c));
}

using Poly2 = std::vector<Eigen::Vector2d>;

/// Sutherland-Hodgman: the part of `in` where sign * (p[axis] - c) >= 0.
void clip2(const Poly2& in, int axis, double c, double sign, Poly2& out) {
  out.clear();
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector2d& p = in[i];
    const Eigen::Vector2d& q = in[(i + 1) % in.size()];
    const double dp = sign * (p[axis] - c), dq = sign * (q[axis] - c);
    if (dp >= 0) out.push_back(p);
    if ((dp > 0 && dq < 0) || (dp < 0 && dq > 0)) {
      Eigen::Vector2d m = p + (q - p) * (dp / (dp - dq));
      m[axis] = c;
      out.push_back(m);
    }
  }
}

double area2(const Poly2& p) {
  double s = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& a = p[i];
    const Eigen::Vector2d& b = p[(i + 1) % p.size()];
    s += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::fabs(s);
}

/// Increasing with the angle of (dx, dy) as atan2 is, in [0, 4), without a transcendental call.
double pseudoAngle(double dx, double dy) {
  const double s = std::fabs(dx) + std::fabs(dy);
  if (!(s > 0)) return 0.0;
  const double p = dy / s;
  return dx < 0 ? 2.0 - p : dy < 0 ? 4.0 + p : p;
}

/// A convex polyhedron as its faces, each a convex polygon, in fixed storage (a cube cut by six
/// planes has at most 12 faces of at most 10 vertices; the cut's points may repeat a vertex).
struct Polyhedron {
  static constexpr int kFaces = 16, kVerts = 48;
  struct Face {
    int n = 0;
    Eigen::Vector3d v[kVerts];
  };
  Face buf[2][kFaces];
  int cur = 0, count = 0;  // the faces are buf[cur][0, count)
  Eigen::Vector3d cap[kVerts];
  std::pair<double, int> order[kVerts];

  void cube(const std::array<Eigen::Vector3d, 8>& v) {
    static constexpr int kCube[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                        {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    Face* faces = buf[cur];
    count = 6;
    for (int f = 0; f < 6; ++f) {
      faces[f].n = 4;
      for (int i = 0; i < 4; ++i) faces[f].v[i] = v[std::size_t(kCube[f][i])];
    }
  }

  /// Keeps the part where sign * (p[axis] - c) >= 0, closing the cut by a cap face.
  void clip(int axis, double c, double sign) {
    const Face* faces = buf[cur];
    Face* next = buf[cur ^ 1];
    int n = 0, ncap = 0;
    for (int f = 0; f < count; ++f) {
      const Face& face = faces[f];
      Face& out = next[n];
      out.n = 0;
      for (int i = 0, j = 1; i < face.n; ++i, j = (j + 1 == face.n ? 0 : j + 1)) {
        const Eigen::Vector3d& p = face.v[i];
        const Eigen::Vector3d& q = face.v[j];
        const double dp = sign * (p[axis] - c), dq = sign * (q[axis] - c);
        if (dp >= 0 && out.n < kVerts) out.v[out.n++] = p;
        if (dp == 0 && ncap < kVerts) cap[ncap++] = p;
        if ((dp > 0 && dq < 0) || (dp < 0 && dq > 0)) {
          Eigen::Vector3d m = p + (q - p) * (dp / (dp - dq));
          m[axis] = c;
          if (out.n < kVerts) out.v[out.n++] = m;
          if (ncap < kVerts) cap[ncap++] = m;
        }
      }
      if (out.n >= 3) ++n;
    }
    if (ncap >= 3 && n < kFaces) {
      // The cut is convex: its points in order of angle about their mean, in the plane's axes.
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      double ma = 0, mb = 0;
      for (int i = 0; i < ncap; ++i) ma += cap[i][a], mb += cap[i][b];
      ma /= ncap, mb /= ncap;
      for (int i = 0; i < ncap; ++i) order[i] = {pseudoAngle(cap[i][a] - ma, cap[i][b] - mb), i};
      std::sort(order, order + ncap);
      Face& out = next[n++];
      out.n = ncap;
      for (int i = 0; i < ncap; ++i) out.v[i] = cap[order[i].second];
    }
    count = n;
    cur ^= 1;
  }

  /// Sum of the pyramids from an inner point to the faces.
  double volume() const {
    const Face* faces = buf[cur];
    Eigen::Vector3d inner = Eigen::Vector3d::Zero();
    int points = 0;
    for (int f = 0; f < count; ++f)
      for (int i = 0; i < faces[f].n; ++i) inner += faces[f].v[i], ++points;
    if (points == 0) return 0.0;
    inner /= double(points);
    double v = 0;
    for (int f = 0; f < count; ++f) {
      const Face& face = faces[f];
      Eigen::Vector3d area = Eigen::Vector3d::Zero();
      for (int i = 1; i + 1 < face.n; ++i) area += (face.v[i] - face.v[0]).cross(face.v[i + 1] - face.v[0]);
      v += std::fabs(area.dot(face.v[0] - inner));
    }
    return v / 6.0;
  }
};

}  // namespace

std::optional<std::array<std::int64_t, 3>> wholeCellShift(const Lattice& dst, const Lattice& src,
                                                          const Eigen::Isometry3d& pose) {
  if (dst.resolution() != src.resolution() || !pose.linear().isIdentity(0.0)) return std::nullopt;
  std::array<std::int64_t, 3> shift{};
  for (int a = 0; a < 3; ++a) {
    const double c = pose.translation()[a] / dst.resolution();
    if (!(std::fabs(c) < 1e9) || c != std::round(c) || std::round(c) * dst.resolution() != pose.translation()[a])
      return std::nullopt;
    shift[std::size_t(a)] = static_cast<std::int64_t>(std::round(c));
  }
  return shift;
}

Placement::Placement(const Lattice& dst, const Lattice& src, const Eigen::Isometry3d& pose) {
  r_ = pose.linear();
  bool perm = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double s = std::round(r_(i, j));
      if (std::fabs(r_(i, j) - s) <= 1e-12)
        r_(i, j) = s;
      else
        perm = false;
    }
  scale_ = src.resolution() / dst.resolution();
  t_ = pose.translation() / dst.resolution();
  // x = scale r u + t, so u = r^T (x - t) / scale.
  back_ = r_.transpose() / scale_;
  back_t_ = -(back_ * t_);
  kind_ = perm ? Kind::Axes : Kind::General;
  for (int a = 0; a < 3; ++a) {
    axis_of_[a] = -1;
    for (int b = 0; b < 3; ++b) {
      if (std::fabs(r_(a, b)) != 1.0) continue;
      // Aligned only if the rest of row a and column b is exactly (snapped) zero.
      bool alone = true;
      for (int o = 0; o < 3; ++o) alone = alone && (o == b || r_(a, o) == 0.0) && (o == a || r_(o, b) == 0.0);
      if (alone) axis_of_[a] = b;
    }
    if (!perm && axis_of_[a] >= 0) kind_ = Kind::OneAxis, kept_ = a;
  }
}

std::array<double, 2> Placement::alignedInterval(int a, double u0, double u1) const {
  const double s = r_(a, axis_of_[a]);
  const double x0 = snap(s * u0 * scale_ + t_[a]), x1 = snap(s * u1 * scale_ + t_[a]);
  return {std::min(x0, x1), std::max(x0, x1)};
}

void Placement::overlaps(const Box& box, InsertStats& stats, const std::function<void(const Key&, double)>& emit) const {
  const Eigen::Vector3d lo(box.min.x, box.min.y, box.min.z);
  const Eigen::Vector3d hi(box.max.x + 1.0, box.max.y + 1.0, box.max.z + 1.0);
  Eigen::Vector3d a = Eigen::Vector3d::Constant(HUGE_VAL), b = Eigen::Vector3d::Constant(-HUGE_VAL);
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d u((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d x = r_ * u * scale_ + t_;
    a = a.cwiseMin(x), b = b.cwiseMax(x);
  }
  for (int i = 0; i < 3; ++i)
    if (axis_of_[i] >= 0) {
      const auto iv = alignedInterval(i, lo[axis_of_[i]], hi[axis_of_[i]]);
      a[i] = iv[0], b[i] = iv[1];
    }
  std::int64_t from[3], to[3];
  bool beyond = false, any = true;
  for (int i = 0; i < 3; ++i) any = cellRange(a[i], b[i], from[i], to[i], beyond) && any;
  if (beyond) ++stats.skipped_out_of_range;
  if (!any) return;
  switch (kind_) {
    case Kind::Axes: return axes(box, from, to, emit);
    case Kind::OneAxis: return oneAxis(box, from, to, emit);
    case Kind::General: return general(box, from, to, emit);
  }
}

void Placement::axes(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
                     const std::function<void(const Key&, double)>& emit) const {
  // Per axis, each cell's length inside the placed interval; a cell's volume is their product.
  std::vector<double> len[3];
  for (int i = 0; i < 3; ++i) {
    const int s = axis_of_[i];
    const auto iv = alignedInterval(i, box.min[s], double(box.max[s]) + 1.0);
    for (std::int64_t c = lo[i]; c <= hi[i]; ++c) len[i].push_back(overlap1(iv[0], iv[1], c));
  }
  const double cell = scale_ * scale_ * scale_;
  for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
      for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
        const double v = len[0][std::size_t(x - lo[0])] * len[1][std::size_t(y - lo[1])] * len[2][std::size_t(z - lo[2])];
        if (v > 0) emit(keyOf(x, y, z), v / cell);
      }
}

void Placement::oneAxis(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
                        const std::function<void(const Key&, double)>& emit) const {
  const int k = kept_, p = (k + 1) % 3, q = (k + 2) % 3;  // dst axes: kept, and the turned plane
  const int bk = axis_of_[k], bp = (bk + 1) % 3, bq = (bk + 2) % 3;
  const auto iv = alignedInterval(k, box.min[bk], double(box.max[bk]) + 1.0);
  const double rlo[2] = {double(box.min[bp]), double(box.min[bq])};
  const double rhi[2] = {box.max[bp] + 1.0, box.max[bq] + 1.0};
  const double full = 1.0 / (scale_ * scale_);  // a dst cell's area in src cells
  Poly2 poly, tmp;
  std::int64_t at[3];
  for (std::int64_t i = lo[p]; i <= hi[p]; ++i)
    for (std::int64_t j = lo[q]; j <= hi[q]; ++j) {
      // The dst cell's square in the turned plane, taken back into src coordinates.
      poly.clear();
      const double corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      bool inside = true;
      int below[2] = {0, 0}, above[2] = {0, 0};
      for (const auto& c : corners) {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        x[p] = double(i) + c[0], x[q] = double(j) + c[1];
        const Eigen::Vector3d u = back_ * x + back_t_;
        const Eigen::Vector2d v(u[bp], u[bq]);
        poly.push_back(v);
        for (int d = 0; d < 2; ++d) {
          inside = inside && v[d] >= rlo[d] && v[d] <= rhi[d];
          below[d] += v[d] <= rlo[d], above[d] += v[d] >= rhi[d];
        }
      }
      if (below[0] == 4 || below[1] == 4 || above[0] == 4 || above[1] == 4) continue;
      double area = full;
      if (!inside) {
        for (int d = 0; d < 2; ++d) clip2(poly, d, rlo[d], 1.0, tmp), clip2(tmp, d, rhi[d], -1.0, poly);
        area = std::min(area2(poly), full);
      }
      if (!(area > 0)) continue;
      at[p] = i, at[q] = j;
      for (std::int64_t l = lo[k]; l <= hi[k]; ++l) {
        const double len = overlap1(iv[0], iv[1], l);
        if (!(len > 0)) continue;
        at[k] = l;
        emit(keyOf(at[0], at[1], at[2]), area * len / scale_);
      }
    }
}

void Placement::general(const Box& box, const std::int64_t lo[3], const std::int64_t hi[3],
                        const std::function<void(const Key&, double)>& emit) const {
  const Eigen::Vector3d blo(box.min.x, box.min.y, box.min.z);
  const Eigen::Vector3d bhi(box.max.x + 1.0, box.max.y + 1.0, box.max.z + 1.0);
  const double full = 1.0 / (scale_ * scale_ * scale_);  // a dst cell's volume in src cells
  static thread_local Polyhedron poly;  // 37 KB: not on the stack, not per leaf
  std::array<Eigen::Vector3d, 8> v;
  for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
      for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
        bool inside = true;
        int below[3] = {0, 0, 0}, above[3] = {0, 0, 0};
        for (int c = 0; c < 8; ++c) {
          const Eigen::Vector3d cx(double(x) + (c & 1), double(y) + ((c >> 1) & 1), double(z) + ((c >> 2) & 1));
          v[std::size_t(c)] = back_ * cx + back_t_;
          for (int d = 0; d < 3; ++d) {
            const double u = v[std::size_t(c)][d];
            inside = inside && u >= blo[d] && u <= bhi[d];
            below[d] += u <= blo[d], above[d] += u >= bhi[d];
          }
        }
        bool apart = false;
        for (int d = 0; d < 3; ++d) apart = apart || below[d] == 8 || above[d] == 8;
        if (apart) continue;
        double vol = full;
        if (!inside) {
          // Only by the faces the cell crosses: most cells of a boundary cross one or two.
          poly.cube(v);
          for (int d = 0; d < 3; ++d) {
            if (below[d] > 0) poly.clip(d, blo[d], 1.0);
            if (above[d] > 0) poly.clip(d, bhi[d], -1.0);
          }
          vol = std::min(poly.volume(), full);
        }
        if (vol > 0) emit(keyOf(x, y, z), vol);
      }
}

}  // namespace rtog
