#include "viewpose/pose/verify.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

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
  // The model is drawn into a frame wider than the image by `border` pixels on every side, so that
  // whatever of it falls outside the image counts as unseen rather than not existing.
  constexpr int border = 64;
  CameraIntrinsics Kx = K;
  Kx.width += 2 * border;
  Kx.height += 2 * border;
  Kx.cx += border;
  Kx.cy += border;
  RenderedFrame model;
  if (shape.mesh && !shape.mesh->triangles.empty()) {
    const MeshInstance inst{shape.mesh, T_camera_object};
    model = render(std::span(&inst, 1), Kx);
  } else {
    model = render_points(shape.points, T_camera_object, Kx, shape.point_spacing_m);
  }
  const int W = K.width, H = K.height, m = o.edge_margin_px;
  // Model depth at image pixel (col, row), which may lie in the border.
  const auto z_model = [&](int col, int row) -> float {
    const int x = col + border, y = row + border;
    return (x < 0 || y < 0 || x >= Kx.width || y >= Kx.height) ? NAN : model.depth.at(x, y);
  };
  // Pixels the cluster covers, each of its points splatted over its voxel's footprint.
  std::vector<char> in_cluster(static_cast<std::size_t>(W) * static_cast<std::size_t>(H), 0);
  for (const Eigen::Vector3f& p : cluster_points) {
    if (!p.allFinite() || !(p.z() > 0)) continue;
    const Eigen::Vector2d uv = K.project(p.cast<double>());
    const int half = std::max(1, static_cast<int>(std::ceil(0.5 * K.fx * shape.point_spacing_m / p.z())));
    const int cu = static_cast<int>(std::lround(uv.x())), cv = static_cast<int>(std::lround(uv.y()));
    for (int y = std::max(0, cv - half); y <= std::min(H - 1, cv + half); ++y)
      for (int x = std::max(0, cu - half); x <= std::min(W - 1, cu + half); ++x)
        in_cluster[static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x)] = 1;
  }
  std::size_t supported = 0;
  for (int y = -border; y < H + border; ++y) {
    for (int x = -border; x < W + border; ++x) {
      const float zm = z_model(x, y);
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
      if (x < 0 || y < 0 || x >= W || y >= H) {
        ++v.unknown;  // outside the image: not seen
        continue;
      }
      const float zo = observed.at(x, y);
      const bool cluster_here = in_cluster[static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x)];
      if (!std::isfinite(zo)) ++v.unknown;
      else if (zo < zm - tol) {
        // Something in front hides the model here. If that something is the cluster the model is
        // meant to be, the pose puts the object behind its own surface (a can sunk into a keyboard
        // with its lid flush): evidence against, not occlusion.
        if (cluster_here && o.cluster_cannot_hide_model) ++v.hidden_by_cluster;
        else ++v.occluded;
      } else if (zo > zm + tol) ++v.conflicts;
      else {
        ++v.inliers;
        supported += cluster_here;
      }
    }
  }
  const std::size_t judged = v.inliers + v.conflicts + v.hidden_by_cluster;
  v.inlier_fraction = judged ? static_cast<double>(v.inliers) / static_cast<double>(judged) : 0.0;
  const std::size_t all = judged + v.occluded + v.unknown;
  v.visible_fraction = all ? static_cast<double>(v.inliers) / static_cast<double>(all) : 0.0;
  const std::size_t unhidden = judged + v.unknown;
  v.unmeasured_fraction = unhidden ? static_cast<double>(v.unknown) / static_cast<double>(unhidden) : 0.0;
  v.model_support = v.inliers ? static_cast<double>(supported) / static_cast<double>(v.inliers) : 0.0;
  v.conflict_fraction = judged ? static_cast<double>(v.conflicts + v.hidden_by_cluster) / static_cast<double>(judged) : 0.0;
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
               v.conflict_fraction <= o.max_conflict_fraction && v.cluster_explained >= o.min_cluster_explained &&
               v.model_support >= o.min_model_support && v.visible_fraction >= o.min_visible_fraction &&
               v.unmeasured_fraction <= o.max_unmeasured_fraction;
  return v;
}

}  // namespace viewpose
