#include "viewpose/core/depth_image.hpp"

#include <algorithm>

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

DepthImage::DepthImage(int w, int h)
    : width(w), height(h),
      depth_m(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), std::numeric_limits<float>::quiet_NaN()) {}

std::size_t DepthImage::count_valid() const {
  std::size_t n = 0;
  for (float z : depth_m) n += (std::isfinite(z) && z > 0.0f) ? 1 : 0;
  return n;
}

PointCloud depth_to_cloud(const DepthImage& depth, const CameraIntrinsics& K) {
  K.validate();
  if (depth.width != K.width || depth.height != K.height) {
    throw Error(fmt::format("depth image is {}x{} but the camera intrinsics are for {}x{}", depth.width,
                            depth.height, K.width, K.height));
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointCloud cloud;
  cloud.width = depth.width;
  cloud.height = depth.height;
  cloud.points.resize(depth.depth_m.size());
  // Precomputed per-column and per-row ray slopes: the unprojection is then two multiplies a pixel.
  std::vector<float> x_over_z(static_cast<std::size_t>(depth.width));
  for (int u = 0; u < depth.width; ++u) x_over_z[static_cast<std::size_t>(u)] = static_cast<float>((u - K.cx) / K.fx);
#pragma omp parallel for schedule(static)
  for (int v = 0; v < depth.height; ++v) {
    const float y_over_z = static_cast<float>((v - K.cy) / K.fy);
    for (int u = 0; u < depth.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * depth.width + u;
      const float z = depth.depth_m[i];
      cloud.points[i] = (std::isfinite(z) && z > 0.0f)
                            ? Eigen::Vector3f(x_over_z[static_cast<std::size_t>(u)] * z, y_over_z * z, z)
                            : Eigen::Vector3f(nan, nan, nan);
    }
  }
  return cloud;
}

DepthImage depth_from_units(std::span<const std::uint16_t> units, int width, int height, double metres_per_unit) {
  if (!(std::isfinite(metres_per_unit) && metres_per_unit > 0 && metres_per_unit < 1)) {
    throw Error(fmt::format("depth scale {} m per unit is not a positive fraction of a metre", metres_per_unit));
  }
  if (width <= 0 || height <= 0 || units.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error(fmt::format("depth: {} values are not an image of {} x {}", units.size(), width, height));
  }
  DepthImage depth(width, height);
  for (std::size_t i = 0; i < units.size(); ++i) {
    if (units[i] != 0) depth.depth_m[i] = static_cast<float>(units[i] * metres_per_unit);
  }
  return depth;
}

double median_depth_m(const DepthImage& depth) {
  std::vector<float> valid;
  valid.reserve(depth.depth_m.size() / 4);
  for (const float z : depth.depth_m) {
    if (std::isfinite(z) && z > 0) valid.push_back(z);
  }
  if (valid.empty()) return std::nan("");
  const auto mid = valid.begin() + static_cast<std::ptrdiff_t>(valid.size() / 2);
  std::nth_element(valid.begin(), mid, valid.end());
  return *mid;
}

}  // namespace viewpose
