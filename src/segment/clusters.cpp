#include "viewpose/segment/clusters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/cell_grid.hpp"

namespace viewpose {

namespace {

void keep_by_size(std::vector<Cluster>& clusters, const ClusterOptions& o) {
  std::erase_if(clusters, [&](const Cluster& c) { return c.size() < o.min_points || c.size() > o.max_points; });
  for (auto& c : clusters)
    if (!std::is_sorted(c.begin(), c.end())) std::sort(c.begin(), c.end());
  std::stable_sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) { return a.size() > b.size(); });
}

}  // namespace

std::vector<Cluster> euclidean_clusters(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                                        const ClusterOptions& o) {
  if (!(o.tolerance_m > 0)) throw Error(fmt::format("clusters: tolerance {} must be positive", o.tolerance_m));
  // Points binned into cubes of side tolerance / sqrt(3): any two points in one cube are within the
  // tolerance, so each cube is joined whole, and only cubes up to two apart need their points
  // compared, once, until the two are joined. Exactly the transitive closure of "closer than the
  // tolerance", without a radius search per point.
  if (indices.empty()) return {};  // (bin_points reads an empty list as "every point")
  const float t2 = o.tolerance_m * o.tolerance_m;
  const CellGrid grid = bin_points(cloud.points, indices, o.tolerance_m / std::sqrt(3.0f), 2);
  const std::vector<KeyedIndex>& keyed = grid.items;  // cube, position in `indices`
  const std::vector<std::uint64_t>& cubes = grid.cells;
  const std::vector<std::size_t>& first = grid.first;
  constexpr std::int64_t kMask = CellGrid::kMask;
  const auto key = CellGrid::key;
  std::vector<std::uint32_t> parent(cubes.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto find = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  // The points in cube order, so that a cube's points are one run in memory.
  std::vector<Eigen::Vector3f> sorted(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) sorted[k] = cloud.points[indices[keyed[k].second]];
  const auto linked = [&](std::size_t a, std::size_t b) {
    for (std::size_t i = first[a]; i < first[a + 1]; ++i)
      for (std::size_t j = first[b]; j < first[b + 1]; ++j)
        if ((sorted[i] - sorted[j]).squaredNorm() <= t2) return true;
    return false;
  };
  // The later columns (x, y) within two cubes, and the same column: keys only grow from cube to cube,
  // so each column's position in `cubes` is a pointer that only moves forward.
  std::vector<std::pair<int, int>> columns;
  for (int dx = 0; dx <= 2; ++dx)
    for (int dy = -2; dy <= 2; ++dy)
      if (dx > 0 || dy >= 0) columns.emplace_back(dx, dy);
  // The pairs of cubes that may hold linked points, found in one pass. Touching cubes are tried
  // first: they are nearly always linked by their first few pairs. Then cubes further apart, most
  // of which are joined by then and need no comparison (taken in key order instead, every pair of
  // points of two cubes across a gap was compared before their clusters met).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> touching, apart;
  std::vector<std::size_t> pointer(columns.size(), 0);
  for (std::size_t a = 0; a < cubes.size(); ++a) {
    const auto [x, y, z] = CellGrid::coordinates(cubes[a]);
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const auto [dx, dy] = columns[c];
      const bool same_column = dx == 0 && dy == 0;
      const std::uint64_t lo = key(x + dx, y + dy, same_column ? z + 1 : z - 2), hi = key(x + dx, y + dy, z + 2);
      std::size_t& b = pointer[c];
      while (b < cubes.size() && cubes[b] < lo) ++b;
      for (std::size_t j = b; j < cubes.size() && cubes[j] <= hi; ++j) {
        const std::int64_t dz = static_cast<std::int64_t>(cubes[j] & kMask) - z;
        // Cubes whose nearest corners are farther apart than the tolerance cannot be linked.
        const std::int64_t gap = CellGrid::squared_gap(dx, dy, dz);
        if (gap > 3) continue;
        (gap == 0 ? touching : apart).emplace_back(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(j));
      }
    }
  }
  for (const auto* pairs : {&touching, &apart}) {
    for (const auto& [a, j] : *pairs) {
      const std::uint32_t ra = find(a), rb = find(j);
      if (ra != rb && linked(a, j)) parent[std::max(ra, rb)] = std::min(ra, rb);
    }
  }
  // Clusters in the order of their first point, as a region growing from each unvisited point would give.
  std::vector<std::uint32_t> smallest(cubes.size(), UINT32_MAX);
  for (std::size_t a = 0; a < cubes.size(); ++a) {
    const std::uint32_t r = find(static_cast<std::uint32_t>(a));
    for (std::size_t i = first[a]; i < first[a + 1]; ++i) smallest[r] = std::min(smallest[r], keyed[i].second);
  }
  std::vector<std::uint32_t> roots;
  for (std::uint32_t a = 0; a < cubes.size(); ++a) {
    if (find(a) == a) roots.push_back(a);
  }
  std::sort(roots.begin(), roots.end(), [&](std::uint32_t l, std::uint32_t r) { return smallest[l] < smallest[r]; });
  std::vector<std::uint32_t> slot(cubes.size(), 0);
  for (std::uint32_t k = 0; k < roots.size(); ++k) slot[roots[k]] = k;
  // Each point's cluster, then the points in the order given: a cluster's points come out in the
  // order of `indices`, as they would from a region growing, without sorting each cluster.
  std::vector<std::uint32_t> label(indices.size(), UINT32_MAX);
  for (std::size_t a = 0; a < cubes.size(); ++a) {
    const std::uint32_t l = slot[find(static_cast<std::uint32_t>(a))];
    for (std::size_t i = first[a]; i < first[a + 1]; ++i) label[keyed[i].second] = l;
  }
  std::vector<Cluster> clusters(roots.size());
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (label[k] != UINT32_MAX) clusters[label[k]].push_back(indices[k]);
  keep_by_size(clusters, o);
  return clusters;
}

std::vector<Cluster> organized_clusters(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                                        const ClusterOptions& o) {
  if (!cloud.organized()) throw Error("clusters: the organized version needs an organized cloud (height > 1)");
  if (!(o.tolerance_m > 0) || o.window_px < 1) throw Error("clusters: tolerance and window must be positive");
  const int W = cloud.width, H = cloud.height;
  // 0 = not taking part, 1 = waiting, 2 = assigned.
  std::vector<char> state(cloud.size(), 0);
  for (std::uint32_t i : indices) {
    if (cloud.points[i].allFinite()) state[i] = 1;
  }
  const float t2 = o.tolerance_m * o.tolerance_m;
  std::vector<Cluster> clusters;
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed : indices) {
    if (state[seed] != 1) continue;
    state[seed] = 2;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint32_t i = queue[q];
      const int u = static_cast<int>(i % static_cast<std::uint32_t>(W)), v = static_cast<int>(i / static_cast<std::uint32_t>(W));
      for (int dv = -o.window_px; dv <= o.window_px; ++dv) {
        const int vv = v + dv;
        if (vv < 0 || vv >= H) continue;
        for (int du = -o.window_px; du <= o.window_px; ++du) {
          const int uu = u + du;
          if (uu < 0 || uu >= W) continue;
          const auto j = static_cast<std::uint32_t>(vv * W + uu);
          if (state[j] == 1 && (cloud.points[j] - cloud.points[i]).squaredNorm() <= t2) {
            state[j] = 2;
            queue.push_back(j);
          }
        }
      }
    }
    clusters.push_back(queue);
  }
  keep_by_size(clusters, o);
  return clusters;
}

}  // namespace viewpose
