#pragma once
// No object stands inside a table. A pose may explain what the camera sees of an object and put
// the rest of the model where nothing is seen: behind something nearer, which verification takes
// for occlusion. When that something is a large plane the segmentation removed (the table the
// object stands on, a wall behind it), the model's hidden part lies inside it: the pose is not a
// way the object can be. (Real YCB-V 0014, with only the pitcher in the database: the pitcher
// fitted to the master chef can, its handle and spout in the table, every test of verification
// passed.)
#include <span>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/segment/planes.hpp"

namespace viewpose {

/// The share of `model_points` (object frame) that, posed at `T_camera_object`, lie more than
/// `margin_m` behind one of `planes` (n.p + d = 0 in the camera frame, unit n facing the camera,
/// as the segmentation removes them) where that plane was seen straight above them: their foot on
/// the plane lies in the plane's patch (Plane::patch, where the segmentation found it), and the
/// depth measured there lies on the plane, within `margin_m`. Only planes the model also lies in
/// front of, by more than `margin_m`, count: a model wholly behind one is under a table or a
/// shelf's board, seen past its edge. Of the planes, the largest share; 0 without planes, patches
/// or points. Nothing is prepared per frame: each point is projected once per plane.
/// The patch, not the unbounded plane: an object taller than a riser beside it (a box's top, a
/// second table) crosses the riser's plane, and where its lower points' feet fall the camera sees
/// the object's own front at the riser's height, on the plane but not on the riser. (Excluding
/// instead the measured points on the model's own surface, even within 5 mm, also excluded the
/// phantoms' feet: they lie along the surface the phantom was fitted to.)
double share_inside_planes(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K,
                           std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m);

/// How deep a pose's model reaches behind the removed plane it stands on.
struct PlaneSink {
  int plane = -1;     ///< index into the planes; -1: the model reaches behind none
  float depth_m = 0;  ///< how far behind that plane `share` of the model points lie (at least)
};

/// The plane `model_points` (object frame), posed at `T_camera_object`, sink deepest into, and how
/// deep: the depth behind the plane that a `share` of the points reach or pass (0 where fewer do).
/// The points counted are those of share_inside_planes, with `margin_m` as there: behind the plane
/// where the camera saw it straight above them (the depth measured there within `margin_m` of it),
/// and only planes the model also lies in front of by more than `margin_m` (it stands on them). A
/// pose sunk into a table by a few millimetres is the table's band removed with the object's foot;
/// one sunk by a centimetre or more is another object's height (a can 13 cm tall taken for one of
/// 14, its top on the top), which lifted out of the table no longer fits.
PlaneSink sink_into_planes(std::span<const Plane> planes, const DepthImage& depth, const CameraIntrinsics& K,
                           std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m,
                           double share);

}  // namespace viewpose
