#include "viewpose/segment/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/radix_sort.hpp"

namespace viewpose {

PointCloud voxel_downsample(const PointCloud& cloud, float leaf_m) {
  if (!(leaf_m > 0)) throw Error(fmt::format("voxel grid: leaf size {} must be positive", leaf_m));
  cloud.check_consistent();
  // Voxel coordinates packed into 21 bits each (about +-3 km at 3 mm), sorted to gather each voxel.
  constexpr std::int64_t kOffset = 1 << 20;
  std::vector<KeyedIndex> keys;
  keys.reserve(cloud.size());
  const float inv = 1.0f / leaf_m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    std::uint64_t key = 0;
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      const std::int64_t c = static_cast<std::int64_t>(std::floor(p[k] * inv)) + kOffset;
      inside = inside && c >= 0 && c < (std::int64_t{1} << 21);
      key = (key << 21) | static_cast<std::uint64_t>(c & ((1 << 21) - 1));
    }
    if (inside) keys.emplace_back(key, static_cast<std::uint32_t>(i));
  }
  radix_sort(keys);
  PointCloud out;
  const bool normals = cloud.has_normals(), labels = !cloud.labels.empty(), colours = !cloud.rgba.empty();
  for (std::size_t a = 0; a < keys.size();) {
    std::size_t b = a;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), nsum = Eigen::Vector3d::Zero();
    for (; b < keys.size() && keys[b].first == keys[a].first; ++b) {
      sum += cloud.points[keys[b].second].cast<double>();
      if (normals && cloud.normals[keys[b].second].allFinite()) nsum += cloud.normals[keys[b].second].cast<double>();
    }
    out.points.push_back((sum / static_cast<double>(b - a)).cast<float>());
    if (normals) out.normals.push_back(nsum.norm() > 0 ? Eigen::Vector3f(nsum.normalized().cast<float>()) : Eigen::Vector3f::Constant(NAN));
    if (labels) out.labels.push_back(cloud.labels[keys[a].second]);
    if (colours) out.rgba.push_back(cloud.rgba[keys[a].second]);
    a = b;
  }
  out.width = static_cast<int>(out.points.size());
  out.height = 1;
  return out;
}

}  // namespace viewpose
