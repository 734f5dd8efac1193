#include "viewpose/core/nearest_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

NearestGrid::NearestGrid(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m) : points_(points) {
  if (!(cell_m > 0) || !(margin_m >= 0)) throw Error(fmt::format("nearest grid: cell {} and margin {} must be positive", cell_m, margin_m));
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (!(lo.x() <= hi.x())) return;  // no finite point: every query finds nothing
  origin_ = lo - Eigen::Vector3f::Constant(margin_m);
  inv_cell_ = 1.0f / cell_m;
  const Eigen::Vector3f size = (hi - lo + Eigen::Vector3f::Constant(2 * margin_m)) * inv_cell_;
  const double cells = (std::floor(size.x()) + 1.0) * (std::floor(size.y()) + 1.0) * (std::floor(size.z()) + 1.0);
  if (cells > 2e8) throw Error(fmt::format("nearest grid: {:.0f} cells of {} m is too many; use larger cells", cells, cell_m));
  nx_ = static_cast<std::uint32_t>(size.x()) + 1;
  ny_ = static_cast<std::uint32_t>(size.y()) + 1;
  nz_ = static_cast<std::uint32_t>(size.z()) + 1;
  cells_.assign(static_cast<std::size_t>(nx_) * ny_ * nz_, kEmpty);
  const auto at = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * ny_ + static_cast<std::size_t>(y)) * nx_ + static_cast<std::size_t>(x); };
  const auto centre = [&](int x, int y, int z) {
    return Eigen::Vector3f(origin_.x() + (static_cast<float>(x) + 0.5f) * cell_m, origin_.y() + (static_cast<float>(y) + 0.5f) * cell_m,
                           origin_.z() + (static_cast<float>(z) + 0.5f) * cell_m);
  };
  // Each cell's squared distance from its centre to the point it holds.
  std::vector<float> held(cells_.size(), std::numeric_limits<float>::infinity());
  // Seeds: each point in its own cell, the one nearest the centre winning.
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!p.allFinite()) continue;
    const Eigen::Vector3f c = (p - origin_) * inv_cell_;
    const int x = std::min(static_cast<int>(c.x()), static_cast<int>(nx_) - 1), y = std::min(static_cast<int>(c.y()), static_cast<int>(ny_) - 1),
              z = std::min(static_cast<int>(c.z()), static_cast<int>(nz_) - 1);
    const std::size_t cell = at(x, y, z);
    const float d2 = (p - centre(x, y, z)).squaredNorm();
    if (d2 < held[cell]) {
      cells_[cell] = i;
      held[cell] = d2;
    }
  }
  // Vector propagation (Danielsson): a forward raster pass taking the best of the 13 neighbours
  // already visited, then a backward pass over the other 13; each cell ends with the point nearest
  // its centre among those its neighbours hold (nearly always the nearest of all).
  const int X = static_cast<int>(nx_), Y = static_cast<int>(ny_), Z = static_cast<int>(nz_);
  const auto improve = [&](int x, int y, int z, int dx, int dy, int dz) {
    const int xx = x + dx, yy = y + dy, zz = z + dz;
    if (xx < 0 || yy < 0 || zz < 0 || xx >= X || yy >= Y || zz >= Z) return;
    const std::uint32_t candidate = cells_[at(xx, yy, zz)];
    if (candidate == kEmpty) return;
    const std::size_t cell = at(x, y, z);
    if (cells_[cell] == candidate) return;
    const float d2 = (points[candidate] - centre(x, y, z)).squaredNorm();
    if (d2 < held[cell]) {
      cells_[cell] = candidate;
      held[cell] = d2;
    }
  };
  {
    for (int z = 0; z < Z; ++z)
      for (int y = 0; y < Y; ++y)
        for (int x = 0; x < X; ++x)
          for (int dz = -1; dz <= 0; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx)
                if (dz < 0 || dy < 0 || (dy == 0 && dx < 0)) improve(x, y, z, dx, dy, dz);
    for (int z = Z - 1; z >= 0; --z)
      for (int y = Y - 1; y >= 0; --y)
        for (int x = X - 1; x >= 0; --x)
          for (int dz = 0; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx)
                if (dz > 0 || dy > 0 || (dy == 0 && dx > 0)) improve(x, y, z, dx, dy, dz);
  }
}

}  // namespace viewpose
