#pragma once
// Pinhole camera intrinsics. Pixel convention (OpenCV, BOP): the centre of pixel column u, row v is at
// image coordinates (u, v); x points right, y down, z forward, all in metres.
#include <Eigen/Core>

namespace viewpose {

struct CameraIntrinsics {
  double fx = 0, fy = 0;  ///< focal lengths in pixels
  double cx = 0, cy = 0;  ///< principal point in pixels
  int width = 0, height = 0;

  /// Image coordinates of a point in the camera frame (z > 0 expected).
  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const {
    return {fx * p_camera.x() / p_camera.z() + cx, fy * p_camera.y() / p_camera.z() + cy};
  }
  /// The point in the camera frame seen at image coordinates (u, v) with depth z (metres along +z).
  Eigen::Vector3d unproject(double u, double v, double z) const {
    return {(u - cx) * z / fx, (v - cy) * z / fy, z};
  }
  bool contains(double u, double v) const { return u > -0.5 && v > -0.5 && u < width - 0.5 && v < height - 0.5; }

  /// Throws viewpose::Error when the intrinsics cannot describe a real camera (non-positive or
  /// non-finite focal lengths, an absurd image size).
  void validate() const;

  /// The nominal Kinect v1 / Xtion VGA depth camera (fx = fy = 525, cx = 319.5, cy = 239.5).
  static CameraIntrinsics kinect_v1();
};

}  // namespace viewpose
