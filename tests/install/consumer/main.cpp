#include <rtog/core/occupancy_map.hpp>

int main() {
  rtog::OccupancyMap map;
  const std::vector<Eigen::Vector3f> pts = {{1.0f, 0.0f, 0.0f}};
  map.insertPointCloud(Eigen::Vector3d::Zero(), pts);
  return map.state(map.lattice().key(Eigen::Vector3d(1.0, 0.0, 0.0))) == rtog::CellState::Occupied ? 0 : 1;
}
