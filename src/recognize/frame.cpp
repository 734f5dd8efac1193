#include "viewpose/recognize/frame.hpp"

#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

Frame frame_from_depth(DepthImage depth, const CameraIntrinsics& K) {
  Frame f;
  f.cloud = depth_to_cloud(depth, K);
  f.depth = std::move(depth);
  f.K = K;
  return f;
}

CameraIntrinsics intrinsics_from_organized_cloud(const PointCloud& cloud) {
  if (!cloud.organized()) throw Error("intrinsics: the cloud is not organized");
  // u = fx (x/z) + cx and v = fy (y/z) + cy: two independent line fits.
  Eigen::Matrix2d Au = Eigen::Matrix2d::Zero(), Av = Eigen::Matrix2d::Zero();
  Eigen::Vector2d bu = Eigen::Vector2d::Zero(), bv = Eigen::Vector2d::Zero();
  std::size_t n = 0;
  for (int v = 0; v < cloud.height; ++v) {
    for (int u = 0; u < cloud.width; ++u) {
      const Eigen::Vector3f& p = cloud.points[static_cast<std::size_t>(v) * static_cast<std::size_t>(cloud.width) + static_cast<std::size_t>(u)];
      if (!p.allFinite() || !(p.z() > 0)) continue;
      const Eigen::Vector2d a(p.x() / p.z(), 1.0), b(p.y() / p.z(), 1.0);
      Au += a * a.transpose();
      bu += a * u;
      Av += b * b.transpose();
      bv += b * v;
      ++n;
    }
  }
  if (n < 100) throw Error("intrinsics: fewer than 100 valid points to recover them from");
  const Eigen::Vector2d su = Au.ldlt().solve(bu), sv = Av.ldlt().solve(bv);
  CameraIntrinsics K{su[0], sv[0], su[1], sv[1], cloud.width, cloud.height};
  double ss = 0;
  for (int v = 0; v < cloud.height; ++v) {
    for (int u = 0; u < cloud.width; ++u) {
      const Eigen::Vector3f& p = cloud.points[static_cast<std::size_t>(v) * static_cast<std::size_t>(cloud.width) + static_cast<std::size_t>(u)];
      if (!p.allFinite() || !(p.z() > 0)) continue;
      const Eigen::Vector2d uv = K.project(p.cast<double>());
      ss += (uv - Eigen::Vector2d(u, v)).squaredNorm();
    }
  }
  const double rms = std::sqrt(ss / static_cast<double>(n));
  if (!(rms < 0.5) || !(K.fx > 0 && K.fy > 0)) {
    throw Error(fmt::format("intrinsics: the organized cloud is not one pinhole image (residual {:.2f} px); give them", rms));
  }
  return K;
}

Frame frame_from_cloud(const PointCloud& cloud, const std::optional<CameraIntrinsics>& K_given) {
  cloud.check_consistent();
  Frame f;
  if (cloud.organized()) {
    f.K = K_given ? *K_given : intrinsics_from_organized_cloud(cloud);
    f.K.width = cloud.width;
    f.K.height = cloud.height;
    f.cloud = PointCloud::from_points(cloud.points);
    f.cloud.width = cloud.width;
    f.cloud.height = cloud.height;
    f.depth = DepthImage(cloud.width, cloud.height);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (cloud.points[i].allFinite() && cloud.points[i].z() > 0) f.depth.depth_m[i] = cloud.points[i].z();
    }
    return f;
  }
  f.K = K_given ? *K_given : CameraIntrinsics::kinect_v1();
  if (f.K.width == 0) f.K = CameraIntrinsics{f.K.fx, f.K.fy, f.K.cx, f.K.cy, 640, 480};
  f.K.validate();
  DepthImage depth(f.K.width, f.K.height);
  for (const Eigen::Vector3f& p : cloud.points) {
    if (!p.allFinite() || !(p.z() > 0)) continue;
    const Eigen::Vector2d uv = f.K.project(p.cast<double>());
    const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= f.K.width || v >= f.K.height) continue;
    float& z = depth.at(u, v);
    if (!(z <= p.z())) z = p.z();  // nearest point wins (NaN compares false)
  }
  f.cloud = depth_to_cloud(depth, f.K);
  f.depth = std::move(depth);
  return f;
}

}  // namespace viewpose
