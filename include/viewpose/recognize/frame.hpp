#pragma once
// One depth frame as recognition takes it: the organized cloud, its depth image and the
// intrinsics that relate them. Made from a depth image and intrinsics, or from a point cloud.
#include <optional>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct Frame {
  PointCloud cloud;  ///< organized, camera frame, metres
  DepthImage depth;  ///< the same measurements as depth along z
  CameraIntrinsics K;
};

Frame frame_from_depth(DepthImage depth, const CameraIntrinsics& K);

/// From a cloud in the camera frame. An organized cloud's intrinsics are recovered from its own
/// points (x/z and y/z are affine in the pixel coordinates) unless given; an unorganized cloud is
/// projected through `K` (the Kinect v1's when not given) into a depth image, nearest point first.
Frame frame_from_cloud(const PointCloud& cloud, const std::optional<CameraIntrinsics>& K = std::nullopt);

/// The pinhole intrinsics that best explain an organized cloud, by least squares. Throws
/// viewpose::Error when the cloud is not a projective image (RMS residual over half a pixel).
CameraIntrinsics intrinsics_from_organized_cloud(const PointCloud& cloud);

}  // namespace viewpose
