#include "viewpose/core/cell_grid.hpp"

#include <algorithm>
#include <cmath>

#include "viewpose/core/threads.hpp"

namespace viewpose {

namespace {

// Points per thread's turn: a thread the system has paused holds up the others by one chunk at most.
constexpr std::size_t kChunk = 8192;

// std::floor is a library call on baseline x86-64 (no SSE4.1 rounding instruction), three per point.
// Finite x only; beyond +-1e12 (far outside any grid) it is clamped, as a cast would be undefined.
std::int64_t floor_to_int(float x) {
  const auto t = static_cast<std::int64_t>(std::clamp(x, -1e12f, 1e12f));  // towards zero
  return t - (x < static_cast<float>(t) ? 1 : 0);
}

}  // namespace

CellGrid bin_points(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, float cell_m,
                    int margin_cells) {
  CellGrid grid;
  const float inv = 1.0f / cell_m;
  const std::size_t n = indices.empty() ? points.size() : indices.size();
  // A frame's points are binned on every thread (the voxel grid and the frame's clusters, before
  // any other stage of the frame can start). Inside a parallel region (a frame's clusters searched
  // side by side) the caller's thread bins alone. The sort between follows this decision: it is
  // given the points kept, fewer than these where pixels had no depth.
  const bool parallel = on_every_thread(n);
  // Each point's cell (kLeftOut where it has none: no key has the top bit), and the box the cells span.
  constexpr std::uint64_t kLeftOut = ~std::uint64_t{0};
  std::vector<std::uint64_t> key_of(n);
  std::int64_t lo[3] = {CellGrid::kMask, CellGrid::kMask, CellGrid::kMask}, hi[3] = {0, 0, 0};
#pragma omp parallel if (parallel)
  {
    std::int64_t my_lo[3] = {CellGrid::kMask, CellGrid::kMask, CellGrid::kMask}, my_hi[3] = {0, 0, 0};
#pragma omp for schedule(dynamic, kChunk) nowait
    for (std::size_t k = 0; k < n; ++k) {
      key_of[k] = kLeftOut;
      const Eigen::Vector3f& p = points[indices.empty() ? k : indices[k]];
      if (!p.allFinite()) continue;
      std::int64_t c[3];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        c[a] = floor_to_int(p[a] * inv) + CellGrid::kOffset;
        inside = inside && c[a] >= margin_cells && c[a] <= CellGrid::kMask - margin_cells;
      }
      if (!inside) continue;
      for (int a = 0; a < 3; ++a) my_lo[a] = std::min(my_lo[a], c[a]), my_hi[a] = std::max(my_hi[a], c[a]);
      key_of[k] = CellGrid::key(c[0], c[1], c[2]);
    }
#pragma omp critical(viewpose_bin_points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], my_lo[a]), hi[a] = std::max(hi[a], my_hi[a]);
  }
  std::vector<std::uint32_t> kept;
  kept.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (key_of[k] != kLeftOut) kept.push_back(static_cast<std::uint32_t>(k));
  }
  // Sorted by a dense key over that box, (x - lo) (ny nz) + (y - lo) nz + (z - lo): the same order
  // as the packed keys, but in a few bits, so the radix sort makes two passes instead of five or six
  // (the packed key's bits all change where a coordinate crosses a power of two, at 0 for example).
  const auto ny = static_cast<std::uint64_t>(hi[1] - lo[1] + 1), nz = static_cast<std::uint64_t>(hi[2] - lo[2] + 1);
  const std::size_t m = kept.size();
  grid.items.resize(m);
#pragma omp parallel for schedule(dynamic, kChunk) if (parallel)
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t k = kept[i];
    const auto [x, y, z] = CellGrid::coordinates(key_of[k]);
    grid.items[i] = {(static_cast<std::uint64_t>(x - lo[0]) * ny + static_cast<std::uint64_t>(y - lo[1])) * nz +
                         static_cast<std::uint64_t>(z - lo[2]),
                     k};
  }
  radix_sort(grid.items, parallel);
#pragma omp parallel for schedule(dynamic, kChunk) if (parallel)
  for (std::size_t i = 0; i < m; ++i) grid.items[i].first = key_of[grid.items[i].second];
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
