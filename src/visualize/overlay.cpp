#include "viewpose/visualize/overlay.hpp"

#include <algorithm>
#include <cmath>

#include "viewpose/render/rasterizer.hpp"

namespace viewpose {

RgbImage draw_overlay(const DepthImage& depth, const CameraIntrinsics& K, std::span<const OverlayItem> items) {
  // Grey by depth: near is bright.
  float lo = INFINITY, hi = -INFINITY;
  for (float z : depth.depth_m) {
    if (std::isfinite(z)) { lo = std::min(lo, z); hi = std::max(hi, z); }
  }
  RgbImage out(depth.width, depth.height, 0);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const float z = depth.at(u, v);
      if (!std::isfinite(z)) continue;
      const auto g = static_cast<std::uint8_t>(230.0f - 180.0f * (z - lo) / std::max(hi - lo, 1e-6f));
      out.set(u, v, g, g, g);
    }
  }
  // Each model where it is visible: rendered together with the others, then blended in.
  std::vector<MeshInstance> instances;
  for (const auto& item : items) instances.push_back({item.mesh, item.T_camera_object});
  const RenderedFrame models = render(instances, K);
  for (int v = 0; v < K.height && v < depth.height; ++v) {
    for (int u = 0; u < K.width && u < depth.width; ++u) {
      const std::int32_t id = models.instance[static_cast<std::size_t>(v) * static_cast<std::size_t>(K.width) + static_cast<std::size_t>(u)];
      if (id < 0) continue;
      const float zo = depth.at(u, v);
      if (std::isfinite(zo) && zo < models.depth.at(u, v) - 0.02f) continue;  // hidden behind something
      const auto c = palette(static_cast<std::size_t>(id));
      std::uint8_t* p = out.rgb.data() + 3 * (static_cast<std::size_t>(v) * static_cast<std::size_t>(out.width) + static_cast<std::size_t>(u));
      for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>((p[k] + 2 * c[static_cast<std::size_t>(k)]) / 3);
    }
  }
  for (const auto& item : items) {
    const Eigen::Vector3d o = item.T_camera_object.translation();
    if (!(o.z() > 0.05)) continue;
    static constexpr std::array<std::array<std::uint8_t, 3>, 3> axis_colour = {{{255, 40, 40}, {40, 230, 40}, {60, 100, 255}}};
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d end = item.T_camera_object * (item.axis_length_m * Eigen::Vector3d::Unit(a));
      if (end.z() > 0.05) draw_line(out, K.project(o), K.project(end), axis_colour[static_cast<std::size_t>(a)]);
    }
  }
  return out;
}

}  // namespace viewpose
