#pragma once
// Viewpoints around an object for the view database: directions from the object's centre through
// the face centres of a subdivided icosahedron (20 x 4^s faces: 80 views at one subdivision, as in
// the thesis and PCL's tessellated sphere; 320 at two), each a camera at a given distance looking at
// the centre, upright with respect to the object's +z axis where possible.
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/transform.hpp"

namespace viewpose {

/// Unit vectors from the centre towards the cameras: the face centres of an icosahedron split
/// `subdivisions` times (each edge halved and pushed out onto the sphere), projected onto the sphere.
std::vector<Eigen::Vector3d> view_directions(int subdivisions);

/// T_camera_object of a camera at `eye` (object frame) looking at `target`, with image "up" (-y)
/// as close to `up` as the viewing direction allows (any other axis when they are parallel).
Transform look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                  const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

/// Camera poses T_camera_object for every view direction, `distance_m` from `centre`.
std::vector<Transform> view_sphere_poses(const Eigen::Vector3d& centre, double distance_m, int subdivisions);

}  // namespace viewpose
