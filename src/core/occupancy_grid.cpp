#include "viewpose/core/occupancy_grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace viewpose {

OccupancyGrid::OccupancyGrid(std::span<const Eigen::Vector3f> points, float cell_m) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // No finite point, a bad cell size, or points spread so far that their extent overflows: no grid
  // (every level 0), never a grid whose cells cannot be indexed.
  if (!(lo.x() <= hi.x()) || !(cell_m > 0) || !std::isfinite(cell_m) || !(hi - lo).allFinite()) return;
  // A margin of more than a cell each side, so that the neighbours of every occupied cell are in the grid.
  const float widest = (hi - lo).maxCoeff();
  cell_ = std::max(cell_m, widest / static_cast<float>(kMaxCellsPerSide - 3));
  inv_cell_ = 1.0f / cell_;
  origin_ = lo - Eigen::Vector3f::Constant(1.5f * cell_);  // 1.5: rounding never puts a point in the first cell
  const Eigen::Vector3f size = (hi - origin_) * inv_cell_;
  nx_ = static_cast<std::uint32_t>(size.x()) + 2;
  ny_ = static_cast<std::uint32_t>(size.y()) + 2;
  nz_ = static_cast<std::uint32_t>(size.z()) + 2;
  extent_ = Eigen::Vector3f(static_cast<float>(nx_), static_cast<float>(ny_), static_cast<float>(nz_));
  cells_.assign(static_cast<std::size_t>(nx_) * ny_ * nz_, 0);
  const auto index = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return (static_cast<std::size_t>(z) * ny_ + y) * nx_ + x;
  };
  // The occupied cells first, then their neighbours. The margin keeps those inside the grid, but
  // far from the origin float rounding can eat it, so the neighbours are clamped to the grid.
  std::vector<std::array<std::uint32_t, 3>> occupied;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3f c = ((p - origin_) * inv_cell_).cwiseMax(0.0f);
    const std::array<std::uint32_t, 3> xyz = {std::min(static_cast<std::uint32_t>(c.x()), nx_ - 1),
                                             std::min(static_cast<std::uint32_t>(c.y()), ny_ - 1),
                                             std::min(static_cast<std::uint32_t>(c.z()), nz_ - 1)};
    std::uint8_t& cell = cells_[index(xyz[0], xyz[1], xyz[2])];
    if (cell == 2) continue;
    cell = 2;
    occupied.push_back(xyz);
  }
  for (const auto& [x, y, z] : occupied) {
    for (std::uint32_t zz = z > 0 ? z - 1 : 0; zz <= std::min(z + 1, nz_ - 1); ++zz)
      for (std::uint32_t yy = y > 0 ? y - 1 : 0; yy <= std::min(y + 1, ny_ - 1); ++yy)
        for (std::uint32_t xx = x > 0 ? x - 1 : 0; xx <= std::min(x + 1, nx_ - 1); ++xx) {
          std::uint8_t& cell = cells_[index(xx, yy, zz)];
          cell = std::max<std::uint8_t>(cell, 1);
        }
  }
}

}  // namespace viewpose
