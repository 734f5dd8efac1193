#pragma once
// Surface normals as PCL's NormalEstimation computes them: the least-squares plane through the
// points within a radius (the eigenvector of the smallest eigenvalue of their covariance), turned
// towards the viewpoint; curvature = l0 / (l0 + l1 + l2). Fewer than 3 neighbours: NaN.
#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct NormalOptions {
  float radius_m = 0.015f;  ///< neighbourhood radius (PCL fixture and the 3d_rec_framework: 1.5 cm)
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  float focal_px = 525.0f;  ///< organized path only: pixels per metre at 1 m, to size the pixel window
  int max_window_px = 8;    ///< organized path only: largest half-window searched
};

/// Fills cloud.normals and cloud.curvature (neighbours from a grid of radius-wide cubes; any cloud).
void estimate_normals(PointCloud& cloud, const NormalOptions& options = {});

/// The same for an organized cloud, with neighbours taken from the image window around each pixel
/// (those within the radius in 3-D): no tree to build, and the window shrinks with distance.
void estimate_normals_organized(PointCloud& cloud, const NormalOptions& options = {});

}  // namespace viewpose
