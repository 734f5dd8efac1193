#pragma once
// Which way is up, from the scene: the plane a detected object rests on. A symmetric object's
// reported pose is chosen among its look-alikes by a reference "up" (canonical_pose); the camera's
// own axes give one only for a camera held level or tilted down. The table the object stands on
// gives it for any camera, rolled (a wrist camera) or upside down.
#include <optional>
#include <span>

#include "viewpose/core/transform.hpp"

namespace viewpose {

/// Of `planes` (n.p + d = 0 in the camera frame, unit n facing the camera, as the segmentation
/// removes them), those the object at `T_camera_object` rests on: its lowest point (of
/// `model_points`, object frame) lies on the plane within `touch_m` on either side, so nothing of
/// it is below the plane and it touches it. Of several (a box against a wall, on a table), the one
/// whose normal is nearest the camera's default up, (0, -1, -1) / sqrt 2 (the table, for a camera
/// held anywhere near level). Its unit normal, or nothing where the object rests on none of them
/// (held in the air, lying on something that is not a removed plane).
std::optional<Eigen::Vector3d> resting_plane_up(std::span<const Eigen::Vector4f> planes, std::span<const Eigen::Vector3f> model_points,
                                                const Transform& T_camera_object, float touch_m);

}  // namespace viewpose
