#include "viewpose/pose/through_planes.hpp"

#include <algorithm>
#include <cmath>

namespace viewpose {

double share_inside_planes(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K,
                           std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m) {
  if (planes.empty() || model_points.empty() || depth.width != K.width || depth.height != K.height || !(K.fx > 0) || !(K.fy > 0)) return 0;
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  const auto counted = static_cast<std::size_t>(std::count_if(model_points.begin(), model_points.end(), [](const Eigen::Vector3f& m) { return m.allFinite(); }));
  std::size_t worst = 0;
  for (const Plane& removed : planes) {
    if (removed.patch.covered.empty()) continue;
    const Eigen::Vector4f& plane = removed.coefficients;
    const Eigen::Vector3f n = plane.head<3>();
    std::size_t inside = 0, in_front = 0;
    for (const Eigen::Vector3f& m : model_points) {
      if (!m.allFinite()) continue;
      const Eigen::Vector3f p = R * m + t;
      const float s = n.dot(p) + plane.w();  // > 0: the camera's side
      if (s > margin_m) {
        ++in_front;
        continue;
      }
      if (!(s < -margin_m)) continue;
      const Eigen::Vector3f foot = p - s * n;
      if (!(foot.z() > 0) || !removed.patch.covers(foot)) continue;  // not where the plane was seen
      const Eigen::Vector2d uv = K.project(foot.cast<double>());
      const double u = std::round(uv.x()), v = std::round(uv.y());
      if (!(u >= 0 && u < K.width && v >= 0 && v < K.height)) continue;
      const float zo = depth.at(static_cast<int>(u), static_cast<int>(v));
      if (!(zo > 0) || !std::isfinite(zo)) continue;
      // The measured point there, on the plane?
      const Eigen::Vector3f seen = K.unproject(u, v, zo).cast<float>();
      inside += std::abs(n.dot(seen) + plane.w()) <= margin_m;
    }
    if (in_front > 0) worst = std::max(worst, inside);
  }
  return counted ? static_cast<double>(worst) / static_cast<double>(counted) : 0.0;
}

}  // namespace viewpose
