#pragma once
// A depth image in metres: depth along the camera's z axis (not the ray length), row-major, NaN where
// the sensor measured nothing.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth_m;  ///< width * height values, row-major

  DepthImage() = default;
  /// A width x height image with no measurements (all NaN).
  DepthImage(int w, int h);

  float& at(int u, int v) { return depth_m[static_cast<std::size_t>(v) * width + u]; }
  float at(int u, int v) const { return depth_m[static_cast<std::size_t>(v) * width + u]; }
  /// Pixels with a finite depth greater than zero.
  std::size_t count_valid() const;
};

/// Depth from a camera driver's integer units (row-major, 0 = no measurement): unit v is
/// v * metres_per_unit metres (an Xtion or Kinect in millimetres: 0.001). Throws viewpose::Error when
/// the buffer is not width x height or the scale is not a positive fraction of a metre.
DepthImage depth_from_units(std::span<const std::uint16_t> units, int width, int height, double metres_per_unit);

/// The median of the valid depths (metres); NaN when there is none.
double median_depth_m(const DepthImage& depth);

/// What structured-light and time-of-flight depth cameras measure, about 0.3 to 5 m: a median
/// depth outside it says the depth (or cloud) was read in the wrong unit.
inline constexpr double kDepthCameraNearM = 0.3, kDepthCameraFarM = 5.0;
inline bool within_depth_camera_range(double z_m) { return z_m >= kDepthCameraNearM && z_m <= kDepthCameraFarM; }

/// The organized cloud (width x height, NaN for missing pixels) that `depth` measures through `K`.
/// Throws viewpose::Error when the image size and the intrinsics' size disagree.
PointCloud depth_to_cloud(const DepthImage& depth, const CameraIntrinsics& K);

}  // namespace viewpose
