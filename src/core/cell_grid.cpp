#include "viewpose/core/cell_grid.hpp"

#include <cmath>

namespace viewpose {

CellGrid bin_points(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, float cell_m,
                    int margin_cells) {
  CellGrid grid;
  const float inv = 1.0f / cell_m;
  const std::size_t n = indices.empty() ? points.size() : indices.size();
  grid.items.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3f& p = points[indices.empty() ? k : indices[k]];
    if (!p.allFinite()) continue;
    std::int64_t c[3];
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      c[a] = static_cast<std::int64_t>(std::floor(p[a] * inv)) + CellGrid::kOffset;
      inside = inside && c[a] >= margin_cells && c[a] <= CellGrid::kMask - margin_cells;
    }
    if (inside) grid.items.emplace_back(CellGrid::key(c[0], c[1], c[2]), static_cast<std::uint32_t>(k));
  }
  radix_sort(grid.items);
  for (std::size_t k = 0; k < grid.items.size(); ++k) {
    if (k == 0 || grid.items[k].first != grid.items[k - 1].first) {
      grid.cells.push_back(grid.items[k].first);
      grid.first.push_back(k);
    }
  }
  grid.first.push_back(grid.items.size());
  return grid;
}

}  // namespace viewpose
