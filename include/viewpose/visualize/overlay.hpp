#pragma once
// A picture of detections: the depth frame in grey, each detected model drawn over it in its own
// colour where it is visible at its estimated pose, and its axes (x red, y green, z blue).
#include <span>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/visualize/image.hpp"

namespace viewpose {

struct OverlayItem {
  const TriangleMesh* mesh = nullptr;
  Transform T_camera_object = Transform::Identity();
  double axis_length_m = 0.05;
};

RgbImage draw_overlay(const DepthImage& depth, const CameraIntrinsics& K, std::span<const OverlayItem> items);

}  // namespace viewpose
