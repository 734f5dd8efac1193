#include "viewpose/segment/clusters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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
  // The pairs of cubes that may hold linked points: for each later column (x + dx, y + dy) within
  // two cubes, and the same column, one pass over the cubes in key order, in which the first cube
  // of the neighbour's range is a pointer that only moves forward. A neighbour's key is the cube's
  // plus a constant (bin_points keeps every cube two clear of the key's ends, so no field
  // overflows into the next). Touching cubes are joined as they are found: they are nearly always
  // linked by their first few pairs. Cubes further apart are kept for a last pass, once every
  // touching pair is joined, when most of them are joined already and need no comparison; a pair
  // already joined when found is not kept, as joined cubes never part. (On a room's frame,
  // BM_ClustersOfRoomFrame: every pair kept in lists and joined after, megabytes written and read
  // back, took 28.8 ms; joined as found, 23.3; in these passes instead of one pass over the cubes
  // with a pointer per column, whose loops' lengths changed from column to column, 20.1.)
  // Whatever the order of the joins, each cube's root is the smallest cube of its cluster, so the
  // clusters are the same.
  const auto join = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint32_t ra = find(a), rb = find(b);
    if (ra != rb && linked(a, b)) parent[std::max(ra, rb)] = std::min(ra, rb);
  };
  // The keys again, with one larger than any after them: it ends every scan without a bound check.
  std::vector<std::uint64_t> keys(cubes.begin(), cubes.end());
  keys.push_back(std::numeric_limits<std::uint64_t>::max());
  const std::size_t n_cubes = cubes.size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> apart;
  for (int dx = 0; dx <= 2; ++dx) {
    for (int dy = -2; dy <= 2; ++dy) {
      if (dx == 0 && dy < 0) continue;  // earlier columns: their pairs are found from the other cube
      const bool same_column = dx == 0 && dy == 0;
      const std::uint64_t offset = CellGrid::step(dx, dy, 0);
      const std::uint64_t from = same_column ? 1 : static_cast<std::uint64_t>(-2);  // z + 1 or z - 2, to z + 2
      std::size_t b = 0;
      for (std::size_t a = 0; a < n_cubes; ++a) {
        const std::uint64_t column = keys[a] + offset;
        const std::uint64_t lo = column + from, hi = column + 2;
        while (keys[b] < lo) ++b;
        for (std::size_t j = b; keys[j] <= hi; ++j) {
          const auto ua = static_cast<std::uint32_t>(a), uj = static_cast<std::uint32_t>(j);
          // Touching: no axis more than one cube apart. (Cubes two apart on every axis still lie
          // within the tolerance at their nearest corners: sqrt(3) sides.)
          const auto dz = static_cast<std::int64_t>(keys[j] - column);  // -2..2, the step wrapped back
          const bool touching = CellGrid::squared_gap(dx, dy, dz) == 0;
          if (touching) join(ua, uj);
          else if (find(ua) != find(uj)) apart.emplace_back(ua, uj);
        }
      }
    }
  }
  for (const auto& [a, j] : apart) join(a, j);
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
