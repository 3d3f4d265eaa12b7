#include "rtog/core/key.hpp"

#include <sstream>

namespace rtog {

std::string toString(const Key& k) {
  std::ostringstream s;
  s << '(' << k.x << ',' << k.y << ',' << k.z << ')';
  return s.str();
}

std::string toString(const Box& b) { return "[" + toString(b.min) + ".." + toString(b.max) + "]"; }

Key Lattice::key(const Eigen::Vector3d& p) const {
  Key k;
  if (!tryKey(p, k)) {
    std::ostringstream s;
    s << "rtog: point (" << p.x() << ", " << p.y() << ", " << p.z() << ") is not finite or lies outside the key range (+-"
      << (double(kKeyMax) + 1.0) * resolution_ << " m at resolution " << resolution_ << ")";
    throw std::out_of_range(s.str());
  }
  return k;
}

}  // namespace rtog
