#include "viewpose/segment/planes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>

#include <Eigen/Eigenvalues>


namespace viewpose {

namespace {

std::vector<std::uint32_t> inliers_of(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices,
                                      const Eigen::Vector4f& plane, float threshold) {
  std::vector<std::uint32_t> in;
  for (std::uint32_t i : indices) {
    if (std::abs(plane.head<3>().dot(points[i]) + plane[3]) <= threshold) in.push_back(i);
  }
  return in;
}

// Least-squares plane and in-plane spread of a set of points.
Eigen::Vector4f refit(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> in, float& extent) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::uint32_t i : in) mean += points[i].cast<double>();
  mean /= static_cast<double>(in.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::uint32_t i : in) {
    const Eigen::Vector3d d = points[i].cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.dot(-mean) < 0) n = -n;  // face the sensor at the origin
  // Spread along the two in-plane axes, ignoring the 2 % extremes on either side; the smaller one.
  extent = std::numeric_limits<float>::infinity();
  for (int axis : {1, 2}) {
    std::vector<double> s;
    s.reserve(in.size());
    for (std::uint32_t i : in) s.push_back((points[i].cast<double>() - mean).dot(eig.eigenvectors().col(axis)));
    std::sort(s.begin(), s.end());
    extent = std::min(extent, static_cast<float>(s[s.size() * 98 / 100] - s[s.size() * 2 / 100]));
  }
  return {static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()), static_cast<float>(-n.dot(mean))};
}

}  // namespace

Plane fit_plane(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, const PlaneOptions& o) {
  Plane best;
  if (indices.size() < 3) return best;
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<std::size_t> pick(0, indices.size() - 1);
  // Hypotheses are scored on a fixed random subsample (a few thousand points estimate the inlier
  // share to within a percent); only the winner is counted on every point.
  constexpr std::size_t kScoreSample = 4000;
  std::vector<std::uint32_t> sample;
  if (indices.size() <= kScoreSample) {
    sample.assign(indices.begin(), indices.end());
  } else {
    for (std::size_t k = 0; k < kScoreSample; ++k) sample.push_back(indices[pick(rng)]);
  }
  std::size_t best_count = 0;
  double needed = o.max_iterations;
  for (int it = 0; it < o.max_iterations && it < needed; ++it) {
    const Eigen::Vector3f a = points[indices[pick(rng)]], b = points[indices[pick(rng)]], c = points[indices[pick(rng)]];
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (!(n.norm() > 1e-9f)) continue;  // collinear or repeated sample
    n.normalize();
    const Eigen::Vector4f plane(n.x(), n.y(), n.z(), -n.dot(a));
    std::size_t count = 0;
    for (std::uint32_t i : sample) count += std::abs(n.dot(points[i]) + plane[3]) <= o.distance_threshold_m ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best.coefficients = plane;
      // Samples still needed for 99 % confidence of an all-inlier sample (PCL's RANSAC rule).
      const double w = static_cast<double>(count) / static_cast<double>(sample.size());
      const double p_fail = 1.0 - w * w * w;
      needed = p_fail <= 0 ? 0 : std::log(0.01) / std::log(std::max(p_fail, 1e-12));
    }
  }
  if (best_count < 3) return best;
  best.inliers = inliers_of(points, indices, best.coefficients, o.distance_threshold_m);
  best.coefficients = refit(points, best.inliers, best.extent_m);
  best.inliers = inliers_of(points, indices, best.coefficients, o.distance_threshold_m);
  return best;
}

namespace {

std::vector<std::uint32_t> minus(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
  std::vector<std::uint32_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

// The inliers of the largest connected patch of a plane: the inliers binned into square cells
// of the plane's own 2-D coordinates, cells joined to their 8 neighbours. Linear time.
std::vector<std::uint32_t> largest_patch(std::span<const Eigen::Vector3f> points, const Plane& plane, float cell) {
  const Eigen::Vector3f n = plane.coefficients.head<3>();
  const Eigen::Vector3f a = (std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY()).cross(n).normalized();
  const Eigen::Vector3f b = n.cross(a);
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
  const auto key = [](std::int64_t x, std::int64_t y) {
    return (static_cast<std::uint64_t>(x + (1 << 30)) << 32) | static_cast<std::uint64_t>(y + (1 << 30));
  };
  for (std::uint32_t i : plane.inliers) {
    cells[key(static_cast<std::int64_t>(std::floor(a.dot(points[i]) / cell)),
              static_cast<std::int64_t>(std::floor(b.dot(points[i]) / cell)))].push_back(i);
  }
  std::unordered_map<std::uint64_t, char> seen;
  std::vector<std::uint32_t> best, current;
  std::vector<std::uint64_t> queue;
  for (const auto& [start, unused] : cells) {
    if (seen[start]) continue;
    seen[start] = 1;
    queue.assign(1, start);
    current.clear();
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint64_t c = queue[q];
      const auto& members = cells[c];
      current.insert(current.end(), members.begin(), members.end());
      const std::int64_t x = static_cast<std::int64_t>(c >> 32) - (1 << 30), y = static_cast<std::int64_t>(c & 0xffffffffu) - (1 << 30);
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy) {
          const std::uint64_t k = key(x + dx, y + dy);
          if (cells.count(k) && !seen[k]) {
            seen[k] = 1;
            queue.push_back(k);
          }
        }
    }
    if (current.size() > best.size()) best.swap(current);
  }
  std::sort(best.begin(), best.end());
  return best;
}

}  // namespace

PlaneRemoval remove_large_planes(const PointCloud& cloud, const PlaneOptions& o) {
  PlaneRemoval out;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.points[i].allFinite()) out.remaining.push_back(static_cast<std::uint32_t>(i));
  }
  // Planes are searched for among `pool`; a plane that is not large is left in the cloud but
  // taken out of the pool, so that a smaller wall behind it can still be found.
  std::vector<std::uint32_t> pool = out.remaining;
  PlaneOptions round = o;
  // Cells of the inlier band's width: neighbouring cells link points up to about 2.8 cells apart.
  const float patch_cell = o.distance_threshold_m;
  for (int attempt = 0; attempt < 2 * o.max_planes && static_cast<int>(out.removed.size()) < o.max_planes &&
                        pool.size() >= o.min_inliers;
       ++attempt) {
    round.seed = o.seed + static_cast<std::uint64_t>(attempt);
    Plane plane = fit_plane(cloud.points, pool, round);
    if (plane.inliers.size() < o.min_inliers) break;
    // Large means one connected patch spans min_extent in both directions: a table or a wall does;
    // coplanar faces of boxes (apart, or in a row) and object faces do not.
    const std::vector<std::uint32_t> patch = largest_patch(cloud.points, plane, patch_cell);
    float patch_extent = 0;
    refit(cloud.points, patch, patch_extent);
    pool = minus(pool, plane.inliers);
    if (patch.size() < o.min_inliers || patch_extent < o.min_extent_m) continue;
    plane.extent_m = patch_extent;
    out.remaining = minus(out.remaining, plane.inliers);
    out.removed.push_back(std::move(plane));
  }
  return out;
}

}  // namespace viewpose
