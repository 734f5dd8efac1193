#include "viewpose/pose/verify.hpp"

#include <cmath>

#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"

namespace viewpose {

float depth_tolerance(float z_m, const VerifyOptions& o) {
  return o.base_tolerance_m + o.noise_factor * static_cast<float>(axial_noise_sigma(z_m, 0.0));
}

Verification verify_pose(const VerifyModel& shape, const Transform& T_camera_object, const DepthImage& observed,
                         const CameraIntrinsics& K, std::span<const Eigen::Vector3f> cluster_points,
                         const VerifyOptions& o) {
  Verification v;
  RenderedFrame model;
  if (shape.mesh && !shape.mesh->triangles.empty()) {
    const MeshInstance inst{shape.mesh, T_camera_object};
    model = render(std::span(&inst, 1), K);
  } else {
    model = render_points(shape.points, T_camera_object, K, shape.point_spacing_m);
  }
  const int W = K.width, H = K.height, m = o.edge_margin_px;
  const auto z_model = [&](int col, int row) -> float {
    return (col < 0 || row < 0 || col >= W || row >= H) ? NAN : model.depth.at(col, row);
  };
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const float zm = model.depth.at(x, y);
      if (!std::isfinite(zm)) continue;
      const float tol = depth_tolerance(zm, o);
      // Only pixels well inside the model's outline and away from its own depth steps are judged:
      // edges are where the sensor's lateral noise lives.
      bool interior = true;
      for (const auto& [du, dv] : {std::pair{m, 0}, std::pair{-m, 0}, std::pair{0, m}, std::pair{0, -m}}) {
        const float zn = z_model(x + du, y + dv);
        interior = interior && std::isfinite(zn) && std::abs(zn - zm) <= tol;
      }
      if (!interior) continue;
      const float zo = observed.at(x, y);
      if (!std::isfinite(zo)) ++v.unknown;
      else if (zo < zm - tol) ++v.occluded;
      else if (zo > zm + tol) ++v.conflicts;
      else ++v.inliers;
    }
  }
  const std::size_t judged = v.inliers + v.conflicts;
  v.inlier_fraction = judged ? static_cast<double>(v.inliers) / static_cast<double>(judged) : 0.0;
  v.conflict_fraction = judged ? static_cast<double>(v.conflicts) / static_cast<double>(judged) : 0.0;
  // The other way round: how much of the cluster lies on the model's surface (within a pixel).
  std::size_t explained = 0, counted = 0;
  for (const Eigen::Vector3f& p : cluster_points) {
    if (!p.allFinite() || !(p.z() > 0)) continue;
    ++counted;
    const Eigen::Vector2d uv = K.project(p.cast<double>());
    const int u = static_cast<int>(std::lround(uv.x())), w = static_cast<int>(std::lround(uv.y()));
    const float tol = depth_tolerance(p.z(), o);
    bool hit = false;
    for (int dv = -1; dv <= 1 && !hit; ++dv)
      for (int du = -1; du <= 1 && !hit; ++du) {
        const float zm = z_model(u + du, w + dv);
        hit = std::isfinite(zm) && std::abs(zm - p.z()) <= tol;
      }
    explained += hit ? 1 : 0;
  }
  v.cluster_explained = counted ? static_cast<double>(explained) / static_cast<double>(counted) : 0.0;
  v.score = v.inlier_fraction * v.cluster_explained;
  v.accepted = v.inliers >= o.min_inliers && v.inlier_fraction >= o.min_inlier_fraction &&
               v.conflict_fraction <= o.max_conflict_fraction && v.cluster_explained >= o.min_cluster_explained;
  return v;
}

}  // namespace viewpose
