#pragma once
// No object stands inside a table. A pose may explain what the camera sees of an object and put
// the rest of the model where nothing is seen: behind something nearer, which verification takes
// for occlusion. When that something is a large plane the segmentation removed (the table the
// object stands on, a wall behind it), the model's hidden part lies inside it: the pose is not a
// way the object can be. (Real YCB-V 0014, with only the pitcher in the database: the pitcher
// fitted to the master chef can, its handle and spout in the table, every test of verification
// passed.)
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/point_cloud.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/segment/planes.hpp"

namespace viewpose {

/// Where in the image each removed plane was seen, in cells of `cell_px` pixels: the planes'
/// inliers (indices into `frame`, as Segmentation::planes holds them) projected with K.
class ObservedPlanes {
 public:
  ObservedPlanes(std::span<const Plane> planes, const PointCloud& frame, const CameraIntrinsics& K, int cell_px = 4);

  /// The share of `model_points` (object frame) that, posed at `T_camera_object`, lie more than
  /// `margin_m` behind a plane where the camera saw that plane: straight above them (their foot on
  /// the plane falls in a cell where it was seen). Only planes the model also lies in front of, by
  /// more than `margin_m`, count: a model wholly behind one is under it (a table, a shelf's board),
  /// seen past its edge. Of the planes, the largest share; 0 without planes or points.
  double share_inside(std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m) const;

  bool empty() const { return planes_.empty(); }

 private:
  std::vector<Eigen::Vector4f> planes_;  // n.p + d = 0, n facing the camera
  CameraIntrinsics K_;
  int cell_px_, cols_ = 0, rows_ = 0;
  std::vector<std::uint8_t> seen_;  // per cell: the plane's index + 1 (0: none; the first plane's where two were)
};

}  // namespace viewpose
