#include "viewpose/describe/normals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"

namespace viewpose {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Plane through the neighbours of point i; writes its normal and curvature.
template <typename Neighbours>
void fit_normal(const PointCloud& cloud, std::size_t i, const Neighbours& neighbours, std::size_t count,
                const Eigen::Vector3f& viewpoint, Eigen::Vector3f& normal, float& curvature) {
  if (count < 3) {
    normal = Eigen::Vector3f::Constant(kNaN);
    curvature = kNaN;
    return;
  }
  // Mean-centred covariance in double: small neighbourhoods far from the origin stay accurate.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < count; ++k) mean += cloud.points[neighbours(k)].template cast<double>();
  mean /= static_cast<double>(count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d d = cloud.points[neighbours(k)].template cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);  // eigenvalues in increasing order
  const Eigen::Vector3d l = eig.eigenvalues();
  Eigen::Vector3f n = eig.eigenvectors().col(0).cast<float>();
  if (n.dot(viewpoint - cloud.points[i]) < 0) n = -n;
  normal = n;
  const double sum = l.sum();
  curvature = sum > 0 ? static_cast<float>(std::max(0.0, l[0]) / sum) : 0.0f;
}

}  // namespace

void estimate_normals(PointCloud& cloud, const NormalOptions& options) {
  if (!(options.radius_m > 0)) throw Error(fmt::format("normals: radius {} must be positive", options.radius_m));
  const KdTree tree(cloud.points);
  cloud.normals.assign(cloud.size(), Eigen::Vector3f::Constant(kNaN));
  cloud.curvature.assign(cloud.size(), kNaN);
  const auto n = static_cast<std::ptrdiff_t>(cloud.size());
#pragma omp parallel
  {
    std::vector<std::uint32_t> neighbours;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t s = 0; s < n; ++s) {
      const auto i = static_cast<std::size_t>(s);
      if (!cloud.points[i].allFinite()) continue;
      tree.radius_search(cloud.points[i], options.radius_m, neighbours);
      fit_normal(cloud, i, [&](std::size_t k) { return neighbours[k]; }, neighbours.size(), options.viewpoint,
                 cloud.normals[i], cloud.curvature[i]);
    }
  }
}

void estimate_normals_organized(PointCloud& cloud, const NormalOptions& options) {
  if (!cloud.organized()) throw Error("normals: the organized path needs an organized cloud (height > 1)");
  if (!(options.radius_m > 0 && options.focal_px > 0)) throw Error("normals: radius and focal length must be positive");
  cloud.normals.assign(cloud.size(), Eigen::Vector3f::Constant(kNaN));
  cloud.curvature.assign(cloud.size(), kNaN);
  const int W = cloud.width, H = cloud.height;
  const float r2 = options.radius_m * options.radius_m;
#pragma omp parallel
  {
    std::vector<std::uint32_t> neighbours;
#pragma omp for schedule(dynamic, 16)
    for (int v = 0; v < H; ++v) {
      for (int u = 0; u < W; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(W) + static_cast<std::size_t>(u);
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite() || !(p.z() > 0)) continue;
        // The radius covers about focal * radius / z pixels at depth z.
        const int half = std::clamp(static_cast<int>(std::ceil(options.focal_px * options.radius_m / p.z())), 1, options.max_window_px);
        neighbours.clear();
        for (int dv = -half; dv <= half; ++dv) {
          const int vv = v + dv;
          if (vv < 0 || vv >= H) continue;
          for (int du = -half; du <= half; ++du) {
            const int uu = u + du;
            if (uu < 0 || uu >= W) continue;
            const std::size_t j = static_cast<std::size_t>(vv) * static_cast<std::size_t>(W) + static_cast<std::size_t>(uu);
            if ((cloud.points[j] - p).squaredNorm() <= r2) neighbours.push_back(static_cast<std::uint32_t>(j));  // NaN fails
          }
        }
        fit_normal(cloud, i, [&](std::size_t k) { return neighbours[k]; }, neighbours.size(), options.viewpoint,
                   cloud.normals[i], cloud.curvature[i]);
      }
    }
  }
}

}  // namespace viewpose
