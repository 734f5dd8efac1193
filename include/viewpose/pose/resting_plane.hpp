#pragma once
// Which way is up, from the scene: the plane a detected object stands on. A symmetric object's
// reported pose is chosen among its look-alikes by a reference "up" (canonical_pose); the camera's
// own axes give one only for a camera held level or tilted down. The table the object stands on
// gives it for any camera, rolled (a wrist camera) or upside down.
#include <optional>
#include <span>

#include "viewpose/core/transform.hpp"

namespace viewpose {

/// Of `planes` (n.p + d = 0 in the camera frame, unit n facing the camera, as the segmentation
/// removes them; taken as unbounded), the one the object at `T_camera_object` stands on, and its
/// unit normal. It stands on a plane when its lowest point above it (of `model_points`, object
/// frame) lies within `touch_m` of it, on either side (the plane's and the pose's errors), and one
/// of its `standing_axes` (object frame, unit: its z, and where its symmetries turn z elsewhere,
/// those too, so that every equivalent pose gets the same answer) lies within 30 degrees of the
/// normal, either way: a wall beside it or an object lying on its side says nothing of which way
/// its z should point. Of several, the one best aligned. Nothing where it stands on none.
std::optional<Eigen::Vector3d> resting_plane_up(std::span<const Eigen::Vector4f> planes, std::span<const Eigen::Vector3f> model_points,
                                                const Transform& T_camera_object, std::span<const Eigen::Vector3d> standing_axes,
                                                float touch_m);

}  // namespace viewpose
