#include "viewpose/pose/through_planes.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace viewpose {

namespace {

// Calls `behind(s)` for each of `model_points` posed at `T_camera_object` lying behind `removed`
// (s < -behind_m, s its signed distance, > 0 on the camera's side) where the camera saw that plane
// straight above it: its foot in the plane's patch, the depth measured there within `margin_m` of
// the plane. Returns how many lie in front of it by more than `margin_m`.
template <class Behind>
std::size_t visit_behind_plane(const Plane& removed, const DepthImage& depth, const CameraIntrinsics& K,
                               std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object,
                               float margin_m, float behind_m, Behind&& behind) {
  if (removed.patch.covered.empty()) return 0;
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  const Eigen::Vector4f& plane = removed.coefficients;
  const Eigen::Vector3f n = plane.head<3>();
  std::size_t in_front = 0;
  for (const Eigen::Vector3f& m : model_points) {
    if (!m.allFinite()) continue;
    const Eigen::Vector3f p = R * m + t;
    const float s = n.dot(p) + plane.w();
    if (s > margin_m) {
      ++in_front;
      continue;
    }
    if (!(s < -behind_m)) continue;
    const Eigen::Vector3f foot = p - s * n;
    if (!(foot.z() > 0) || !removed.patch.covers(foot)) continue;  // not where the plane was seen
    const Eigen::Vector2d uv = K.project(foot.cast<double>());
    const double u = std::round(uv.x()), v = std::round(uv.y());
    if (!(u >= 0 && u < K.width && v >= 0 && v < K.height)) continue;
    const float zo = depth.at(static_cast<int>(u), static_cast<int>(v));
    if (!(zo > 0) || !std::isfinite(zo)) continue;
    // The measured point there, on the plane?
    const Eigen::Vector3f seen = K.unproject(u, v, zo).cast<float>();
    if (std::abs(n.dot(seen) + plane.w()) <= margin_m) behind(s);
  }
  return in_front;
}

bool usable(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K, std::span<const Eigen::Vector3f> model_points) {
  return !planes.empty() && !model_points.empty() && depth.width == K.width && depth.height == K.height && K.fx > 0 && K.fy > 0;
}

}  // namespace

double share_inside_planes(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K,
                           std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m) {
  if (!usable(planes, depth, K, model_points)) return 0;
  const auto counted = static_cast<std::size_t>(std::count_if(model_points.begin(), model_points.end(), [](const Eigen::Vector3f& m) { return m.allFinite(); }));
  std::size_t worst = 0;
  for (const Plane& removed : planes) {
    std::size_t inside = 0;
    const std::size_t in_front = visit_behind_plane(removed, depth, K, model_points, T_camera_object, margin_m, margin_m, [&](float) { ++inside; });
    if (in_front > 0) worst = std::max(worst, inside);
  }
  return counted ? static_cast<double>(worst) / static_cast<double>(counted) : 0.0;
}

PlaneSink sink_into_planes(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K,
                           std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m,
                           double share) {
  PlaneSink deepest;
  if (!usable(planes, depth, K, model_points) || !(share > 0)) return deepest;
  const auto counted = static_cast<std::size_t>(std::count_if(model_points.begin(), model_points.end(), [](const Eigen::Vector3f& m) { return m.allFinite(); }));
  // The k-th deepest point sets the depth: k of them reach it.
  const auto k = static_cast<std::size_t>(std::ceil(share * static_cast<double>(counted)));
  std::vector<float> depths;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    depths.clear();
    const std::size_t in_front = visit_behind_plane(planes[i], depth, K, model_points, T_camera_object, margin_m, 0.0f, [&](float s) { depths.push_back(-s); });
    if (in_front == 0 || k == 0 || depths.size() < k) continue;
    std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(k - 1), depths.end(), std::greater<float>());
    const float reach = depths[k - 1];
    if (reach > deepest.depth_m) deepest = {static_cast<int>(i), reach};
  }
  return deepest;
}

}  // namespace viewpose
