#include "rtog/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

namespace rtog::sim {

const char* toString(BoxKind k) {
  switch (k) {
    case BoxKind::Floor: return "floor";
    case BoxKind::Ceiling: return "ceiling";
    case BoxKind::Wall: return "wall";
    case BoxKind::Pillar: return "pillar";
    case BoxKind::Cabinet: return "cabinet";
    case BoxKind::TableTop: return "table_top";
    case BoxKind::TableLeg: return "table_leg";
    case BoxKind::Crate: return "crate";
  }
  return "?";
}

std::optional<double> intersectRayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const SolidBox& b) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.min[a] || o[a] > b.max[a]) return std::nullopt;
      continue;
    }
    const double inv = 1.0 / d[a];
    double tn = (b.min[a] - o[a]) * inv, tf = (b.max[a] - o[a]) * inv;
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
    if (t0 > t1) return std::nullopt;
  }
  return t0;
}

void WorldParams::validate() const {
  auto fail = [](const char* what) { throw std::invalid_argument(std::string("rtog::sim::WorldParams: ") + what); };
  if (rooms_x < 1 || rooms_y < 1) fail("rooms_x and rooms_y must be >= 1");
  if (!(room_min > 2.0 * door_width + 2.0 * wall_thickness) || !(room_max >= room_min)) fail("room size range");
  if (!(height_min > door_height + 0.2) || !(height_max >= height_min)) fail("height range");
  if (!(wall_thickness > 0) || !(slab_thickness > 0) || !(door_width > 0) || !(door_height > 0)) fail("thicknesses");
  if (pillars_max < 0 || furniture_min < 0 || furniture_max < furniture_min) fail("counts");
  if (!(clearance >= 0) || !(pose_spacing > 0)) fail("clearance / pose_spacing");
}

namespace {

SolidBox makeBox(double x0, double y0, double z0, double x1, double y1, double z1, BoxKind k) {
  SolidBox b;
  b.min = Eigen::Vector3d(std::min(x0, x1), std::min(y0, y1), std::min(z0, z1));
  b.max = Eigen::Vector3d(std::max(x0, x1), std::max(y0, y1), std::max(z0, z1));
  b.kind = k;
  return b;
}

// Distance from a 2D point to a 2D rectangle (0 inside).
double pointRectDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const double dx = std::max({lo.x() - p.x(), 0.0, p.x() - hi.x()});
  const double dy = std::max({lo.y() - p.y(), 0.0, p.y() - hi.y()});
  return std::hypot(dx, dy);
}

}  // namespace

World World::generate(const WorldParams& p, std::uint32_t seed) {
  p.validate();
  std::mt19937 rng(seed);
  auto uni = [&rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto coin = [&rng](double prob) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < prob; };

  const double t = p.wall_thickness, half = 0.5 * t;
  // Random sub-cell offsets keep faces off any lattice's cell boundaries.
  const double ox = uni(0.011, 0.089), oy = uni(0.011, 0.089), zf = uni(0.011, 0.089);
  const double H = uni(p.height_min, p.height_max);
  std::vector<double> X{ox}, Y{oy};  // wall centre lines
  for (int i = 0; i < p.rooms_x; ++i) X.push_back(X.back() + uni(p.room_min, p.room_max));
  for (int j = 0; j < p.rooms_y; ++j) Y.push_back(Y.back() + uni(p.room_min, p.room_max));
  const double x_lo = X.front() - half, x_hi = X.back() + half, y_lo = Y.front() - half, y_hi = Y.back() + half;
  const double z_top = zf + H;

  std::vector<SolidBox> boxes;
  boxes.push_back(makeBox(x_lo, y_lo, zf - p.slab_thickness, x_hi, y_hi, zf, BoxKind::Floor));
  boxes.push_back(makeBox(x_lo, y_lo, z_top, x_hi, y_hi, z_top + p.slab_thickness, BoxKind::Ceiling));
  // Exterior walls.
  boxes.push_back(makeBox(X.front() - half, y_lo, zf, X.front() + half, y_hi, z_top, BoxKind::Wall));
  boxes.push_back(makeBox(X.back() - half, y_lo, zf, X.back() + half, y_hi, z_top, BoxKind::Wall));
  boxes.push_back(makeBox(x_lo, Y.front() - half, zf, x_hi, Y.front() + half, z_top, BoxKind::Wall));
  boxes.push_back(makeBox(x_lo, Y.back() - half, zf, x_hi, Y.back() + half, z_top, BoxKind::Wall));

  const double dw = p.door_width, margin = 0.3 + half + 0.5 * dw;
  // A wall segment along `axis` (0: runs along x at y = c; 1: runs along y at x = c) from a to
  // b, with an optional door centred at d.
  auto wallSegment = [&](int axis, double c, double a, double b, std::optional<double> door) {
    auto piece = [&](double s0, double s1, double z0, double z1) {
      if (s1 - s0 <= 1e-9) return;
      if (axis == 0)
        boxes.push_back(makeBox(s0, c - half, z0, s1, c + half, z1, BoxKind::Wall));
      else
        boxes.push_back(makeBox(c - half, s0, z0, c + half, s1, z1, BoxKind::Wall));
    };
    if (!door) {
      piece(a, b, zf, z_top);
      return;
    }
    piece(a, *door - 0.5 * dw, zf, z_top);
    piece(*door + 0.5 * dw, b, zf, z_top);
    piece(*door - 0.5 * dw, *door + 0.5 * dw, zf + p.door_height, z_top);  // lintel
  };

  // Interior walls between columns (x = X[i]): a door in every row (the path goes through).
  // door_x[i][j]: door y of the wall x = X[i] in row j.
  std::vector<std::vector<double>> door_x(X.size(), std::vector<double>(Y.size(), 0.0));
  for (int i = 1; i < p.rooms_x; ++i)
    for (int j = 0; j < p.rooms_y; ++j) {
      const double d = uni(Y[j] + margin, Y[j + 1] - margin);
      door_x[i][j] = d;
      wallSegment(1, X[i], Y[j], Y[j + 1], d);
    }
  // Interior walls between rows (y = Y[j]): the snake path turns at the last column of even
  // rows and the first column of odd rows; other doors at random.
  std::vector<std::vector<double>> door_y(Y.size(), std::vector<double>(X.size(), 0.0));
  for (int j = 1; j < p.rooms_y; ++j) {
    const int turn = ((j - 1) % 2 == 0) ? p.rooms_x - 1 : 0;
    for (int i = 0; i < p.rooms_x; ++i) {
      const bool has_door = i == turn || coin(p.extra_door_probability);
      const double d = uni(X[i] + margin, X[i + 1] - margin);
      door_y[j][i] = d;
      wallSegment(0, Y[j], X[i], X[i + 1], has_door ? std::optional<double>(d) : std::nullopt);
    }
  }

  // The path: a snake through the rooms' centres and the doors.
  std::vector<Eigen::Vector2d> wp;
  auto centre = [&](int i, int j) { return Eigen::Vector2d(0.5 * (X[i] + X[i + 1]), 0.5 * (Y[j] + Y[j + 1])); };
  const double through = 0.8;  // approach a door straight from this far
  for (int j = 0; j < p.rooms_y; ++j) {
    const bool ltr = j % 2 == 0;
    for (int s = 0; s < p.rooms_x; ++s) {
      const int i = ltr ? s : p.rooms_x - 1 - s;
      wp.push_back(centre(i, j));
      if (s + 1 < p.rooms_x) {
        const int wall = ltr ? i + 1 : i;
        const double d = door_x[wall][j], dir = ltr ? 1.0 : -1.0;
        wp.emplace_back(X[wall] - dir * through, d);
        wp.emplace_back(X[wall] + dir * through, d);
      } else if (j + 1 < p.rooms_y) {
        const double d = door_y[j + 1][i];
        wp.emplace_back(d, Y[j + 1] - through);
        wp.emplace_back(d, Y[j + 1] + through);
      }
    }
  }
  std::vector<Pose> poses;
  for (std::size_t k = 0; k + 1 < wp.size(); ++k) {
    const Eigen::Vector2d a = wp[k], b = wp[k + 1], ab = b - a;
    const double len = ab.norm();
    if (len < 1e-9) continue;
    const double yaw = std::atan2(ab.y(), ab.x());
    const int n = std::max(1, static_cast<int>(std::ceil(len / p.pose_spacing)));
    for (int s = 0; s < n; ++s) {
      const Eigen::Vector2d q = a + ab * (static_cast<double>(s) / n);
      poses.push_back(Pose{Eigen::Vector3d(q.x(), q.y(), zf), yaw});
    }
  }
  poses.push_back(Pose{Eigen::Vector3d(wp.back().x(), wp.back().y(), zf), poses.empty() ? 0.0 : poses.back().yaw});

  // Path samples for the clearance test.
  std::vector<Eigen::Vector2d> path_pts;
  for (std::size_t k = 0; k + 1 < wp.size(); ++k) {
    const double len = (wp[k + 1] - wp[k]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.05)));
    for (int s = 0; s <= n; ++s) path_pts.push_back(wp[k] + (wp[k + 1] - wp[k]) * (static_cast<double>(s) / n));
  }
  auto clearOfPath = [&](double x0, double y0, double x1, double y1) {
    const Eigen::Vector2d lo(x0, y0), hi(x1, y1);
    for (const auto& q : path_pts)
      if (pointRectDistance(q, lo, hi) < p.clearance) return false;
    return true;
  };

  // Pillars and furniture, room by room.
  const double gap = 0.05;  // furniture against a wall stands this far off it
  for (int j = 0; j < p.rooms_y; ++j)
    for (int i = 0; i < p.rooms_x; ++i) {
      const double rx0 = X[i] + half, rx1 = X[i + 1] - half, ry0 = Y[j] + half, ry1 = Y[j + 1] - half;
      const int n_pillars = std::uniform_int_distribution<int>(0, p.pillars_max)(rng);
      for (int n = 0, tries = 0; n < n_pillars && tries < 50; ++tries) {
        const double s = uni(0.3, 0.5);
        const double x = uni(rx0 + 0.6, rx1 - 0.6 - s), y = uni(ry0 + 0.6, ry1 - 0.6 - s);
        if (!clearOfPath(x, y, x + s, y + s)) continue;
        boxes.push_back(makeBox(x, y, zf, x + s, y + s, z_top, BoxKind::Pillar));
        ++n;
      }
      const int n_furn = std::uniform_int_distribution<int>(p.furniture_min, p.furniture_max)(rng);
      for (int n = 0, tries = 0; n < n_furn && tries < 100; ++tries) {
        const int kind = std::uniform_int_distribution<int>(0, 2)(rng);
        if (kind == 0) {  // cabinet against a wall
          const double w = uni(0.6, 1.6), dpt = uni(0.35, 0.6), h = uni(1.5, 2.2);
          const int side = std::uniform_int_distribution<int>(0, 3)(rng);
          double x0, y0, x1, y1;
          if (side < 2) {
            const double x = uni(rx0 + 0.1, rx1 - 0.1 - w);
            x0 = x, x1 = x + w;
            y0 = side == 0 ? ry0 + gap : ry1 - gap - dpt;
            y1 = y0 + dpt;
          } else {
            const double y = uni(ry0 + 0.1, ry1 - 0.1 - w);
            y0 = y, y1 = y + w;
            x0 = side == 2 ? rx0 + gap : rx1 - gap - dpt;
            x1 = x0 + dpt;
          }
          if (!clearOfPath(x0, y0, x1, y1)) continue;
          boxes.push_back(makeBox(x0, y0, zf, x1, y1, zf + h, BoxKind::Cabinet));
        } else if (kind == 1) {  // table: top slab on four legs
          const double w = uni(0.8, 1.6), dpt = uni(0.6, 1.0), h = uni(0.70, 0.78), top = 0.04, leg = 0.05;
          const double x0 = uni(rx0 + 0.3, rx1 - 0.3 - w), y0 = uni(ry0 + 0.3, ry1 - 0.3 - dpt);
          const double x1 = x0 + w, y1 = y0 + dpt;
          if (!clearOfPath(x0, y0, x1, y1)) continue;
          boxes.push_back(makeBox(x0, y0, zf + h - top, x1, y1, zf + h, BoxKind::TableTop));
          const double in = 0.04;
          for (const auto& c : {Eigen::Vector2d(x0 + in, y0 + in), Eigen::Vector2d(x1 - in - leg, y0 + in),
                                Eigen::Vector2d(x0 + in, y1 - in - leg), Eigen::Vector2d(x1 - in - leg, y1 - in - leg)})
            boxes.push_back(makeBox(c.x(), c.y(), zf, c.x() + leg, c.y() + leg, zf + h - top, BoxKind::TableLeg));
        } else {  // crate on the floor
          const double w = uni(0.3, 0.8), dpt = uni(0.3, 0.8), h = uni(0.3, 0.9);
          const double x0 = uni(rx0 + 0.2, rx1 - 0.2 - w), y0 = uni(ry0 + 0.2, ry1 - 0.2 - dpt);
          if (!clearOfPath(x0, y0, x0 + w, y0 + dpt)) continue;
          boxes.push_back(makeBox(x0, y0, zf, x0 + w, y0 + dpt, zf + h, BoxKind::Crate));
        }
        ++n;
      }
    }

  World w(std::move(boxes), std::move(poses));
  w.floor_z_ = zf;
  return w;
}

World::World(std::vector<SolidBox> boxes, std::vector<Pose> trajectory)
    : boxes_(std::move(boxes)), trajectory_(std::move(trajectory)) {
  if (boxes_.empty()) throw std::invalid_argument("rtog::sim::World: no boxes");
  bmin_ = boxes_.front().min;
  bmax_ = boxes_.front().max;
  for (const auto& b : boxes_) {
    if (!(b.min.array() <= b.max.array()).all() || !b.min.allFinite() || !b.max.allFinite())
      throw std::invalid_argument("rtog::sim::World: box with min > max or non-finite corner");
    bmin_ = bmin_.cwiseMin(b.min);
    bmax_ = bmax_.cwiseMax(b.max);
  }
  floor_z_ = bmin_.z();
  for (const auto& b : boxes_)
    if (b.kind == BoxKind::Floor) floor_z_ = b.max.z();
  buildGrid();
}

void World::buildGrid() {
  const Eigen::Vector3d ext = bmax_ - bmin_;
  cell_ = 0.5;
  for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::ceil(ext[a] / cell_)));
  // Keep the grid modest for huge worlds.
  while (static_cast<double>(dims_[0]) * dims_[1] * dims_[2] > 4e6) {
    cell_ *= 2.0;
    for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::ceil(ext[a] / cell_)));
  }
  const std::size_t n = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
  auto range = [&](const SolidBox& b, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::clamp(static_cast<int>(std::floor((b.min[a] - bmin_[a]) / cell_)), 0, dims_[a] - 1);
      hi[a] = std::clamp(static_cast<int>(std::floor((b.max[a] - bmin_[a]) / cell_)), 0, dims_[a] - 1);
    }
  };
  std::vector<std::uint32_t> count(n + 1, 0);
  auto forCells = [&](const SolidBox& b, auto&& fn) {
    Eigen::Vector3i lo, hi;
    range(b, lo, hi);
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x)
          fn(static_cast<std::size_t>(x) + static_cast<std::size_t>(dims_[0]) *
                                               (static_cast<std::size_t>(y) + static_cast<std::size_t>(dims_[1]) * z));
  };
  for (const auto& b : boxes_) forCells(b, [&](std::size_t c) { ++count[c + 1]; });
  for (std::size_t c = 0; c < n; ++c) count[c + 1] += count[c];
  cell_start_ = count;
  cell_boxes_.assign(count[n], 0);
  std::vector<std::uint32_t> fill(count.begin(), count.end() - 1);
  for (std::size_t i = 0; i < boxes_.size(); ++i)
    forCells(boxes_[i], [&](std::size_t c) { cell_boxes_[fill[c]++] = static_cast<std::uint32_t>(i); });
}

std::optional<RayHit> World::castRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range) const {
  // Clip the ray to the bounds.
  SolidBox bounds;
  bounds.min = bmin_;
  bounds.max = bmax_;
  const auto t_in = intersectRayBox(o, d, bounds);
  if (!t_in || *t_in > max_range) return std::nullopt;
  double t_out = max_range;
  for (int a = 0; a < 3; ++a)
    if (d[a] != 0.0) t_out = std::min(t_out, ((d[a] > 0 ? bmax_[a] : bmin_[a]) - o[a]) / d[a]);

  const Eigen::Vector3d p = o + d * *t_in;
  int c[3], step[3];
  double t_next[3], t_delta[3];
  for (int a = 0; a < 3; ++a) {
    c[a] = std::clamp(static_cast<int>(std::floor((p[a] - bmin_[a]) / cell_)), 0, dims_[a] - 1);
    if (d[a] > 0) {
      step[a] = 1;
      t_delta[a] = cell_ / d[a];
      t_next[a] = (bmin_[a] + (c[a] + 1) * cell_ - o[a]) / d[a];
    } else if (d[a] < 0) {
      step[a] = -1;
      t_delta[a] = -cell_ / d[a];
      t_next[a] = (bmin_[a] + c[a] * cell_ - o[a]) / d[a];
    } else {
      step[a] = 0;
      t_delta[a] = t_next[a] = std::numeric_limits<double>::infinity();
    }
  }
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_box = 0;
  for (;;) {
    const std::size_t cell = static_cast<std::size_t>(c[0]) +
                             static_cast<std::size_t>(dims_[0]) *
                                 (static_cast<std::size_t>(c[1]) + static_cast<std::size_t>(dims_[1]) * c[2]);
    for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
      const std::uint32_t bi = cell_boxes_[k];
      const auto t = intersectRayBox(o, d, boxes_[bi]);
      if (t && (*t < best || (*t == best && bi < best_box))) {
        best = *t;
        best_box = bi;
      }
    }
    const int a = t_next[0] <= t_next[1] ? (t_next[0] <= t_next[2] ? 0 : 2) : (t_next[1] <= t_next[2] ? 1 : 2);
    // Any box met later starts after this cell's exit; stop when the best hit is before it.
    if (best <= t_next[a] || t_next[a] > t_out) break;
    c[a] += step[a];
    if (c[a] < 0 || c[a] >= dims_[a]) break;
    t_next[a] += t_delta[a];
  }
  if (best > max_range) return std::nullopt;
  return RayHit{best, best_box};
}

bool World::overlapsSolid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  int clo[3], chi[3];
  for (int a = 0; a < 3; ++a) {
    if (hi[a] <= bmin_[a] || lo[a] >= bmax_[a]) return false;
    clo[a] = std::clamp(static_cast<int>(std::floor((lo[a] - bmin_[a]) / cell_)), 0, dims_[a] - 1);
    chi[a] = std::clamp(static_cast<int>(std::floor((hi[a] - bmin_[a]) / cell_)), 0, dims_[a] - 1);
  }
  for (int z = clo[2]; z <= chi[2]; ++z)
    for (int y = clo[1]; y <= chi[1]; ++y)
      for (int x = clo[0]; x <= chi[0]; ++x) {
        const std::size_t cell = static_cast<std::size_t>(x) +
                                 static_cast<std::size_t>(dims_[0]) *
                                     (static_cast<std::size_t>(y) + static_cast<std::size_t>(dims_[1]) * z);
        for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
          const SolidBox& b = boxes_[cell_boxes_[k]];
          if ((lo.array() < b.max.array()).all() && (hi.array() > b.min.array()).all()) return true;
        }
      }
  return false;
}

bool World::cellOccupied(const Lattice& lat, const Key& k) const {
  const double r = lat.resolution();
  const Eigen::Vector3d lo(k.x * r, k.y * r, k.z * r);
  return overlapsSolid(lo, lo + Eigen::Vector3d::Constant(r));
}

bool World::containsPoint(const Eigen::Vector3d& p) const {
  for (const auto& b : boxes_)
    if ((p.array() >= b.min.array()).all() && (p.array() <= b.max.array()).all()) return true;
  return false;
}

std::string World::summary() const {
  std::size_t counts[8] = {};
  for (const auto& b : boxes_) ++counts[static_cast<int>(b.kind)];
  std::ostringstream os;
  os << boxes_.size() << " boxes (";
  for (int k = 0; k < 8; ++k)
    if (counts[k]) os << (k ? " " : "") << toString(static_cast<BoxKind>(k)) << "=" << counts[k];
  os << "), bounds [" << bmin_.x() << ", " << bmax_.x() << "] x [" << bmin_.y() << ", " << bmax_.y() << "] x ["
     << bmin_.z() << ", " << bmax_.z() << "] m, " << trajectory_.size() << " poses";
  return os.str();
}

}  // namespace rtog::sim
