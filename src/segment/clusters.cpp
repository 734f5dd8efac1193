#include "viewpose/segment/clusters.hpp"

#include <algorithm>
#include <deque>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"

namespace viewpose {

namespace {

void keep_by_size(std::vector<Cluster>& clusters, const ClusterOptions& o) {
  std::erase_if(clusters, [&](const Cluster& c) { return c.size() < o.min_points || c.size() > o.max_points; });
  for (auto& c : clusters) std::sort(c.begin(), c.end());
  std::stable_sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) { return a.size() > b.size(); });
}

}  // namespace

std::vector<Cluster> euclidean_clusters(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                                        const ClusterOptions& o) {
  if (!(o.tolerance_m > 0)) throw Error(fmt::format("clusters: tolerance {} must be positive", o.tolerance_m));
  std::vector<Eigen::Vector3f> pts;
  pts.reserve(indices.size());
  for (std::uint32_t i : indices) pts.push_back(cloud.points[i]);
  const KdTree tree(pts);
  std::vector<char> done(pts.size(), 0);
  std::vector<Cluster> clusters;
  std::vector<std::uint32_t> neighbours, queue;
  for (std::size_t seed = 0; seed < pts.size(); ++seed) {
    if (done[seed] || !pts[seed].allFinite()) continue;
    queue.assign(1, static_cast<std::uint32_t>(seed));
    done[seed] = 1;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      tree.radius_search(pts[queue[q]], o.tolerance_m, neighbours);
      for (std::uint32_t n : neighbours) {
        if (!done[n]) {
          done[n] = 1;
          queue.push_back(n);
        }
      }
    }
    Cluster c;
    c.reserve(queue.size());
    for (std::uint32_t k : queue) c.push_back(indices[k]);
    clusters.push_back(std::move(c));
  }
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
