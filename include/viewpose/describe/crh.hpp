#pragma once
// The Camera Roll Histogram (Aldoma et al. 2011) as PCL's CRHEstimation computes it, and the roll
// angles PCL's CRHAlignment finds between two of them (pcl-spec.md, sections 3-4). A view and a
// scene cluster with the same VFH can still differ by a turn about the viewing ray; the CRH of
// each, correlated, gives that turn.
#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/transform.hpp"

namespace viewpose {

/// The 90-bin roll histogram's spectrum: [0] = 1, then the real and imaginary parts of harmonics
/// 1..44, and [89] the real Nyquist term.
using Crh = std::array<float, 90>;

/// CRH of normals seen from the origin, for a cluster whose centroid is `centroid`.
Crh compute_crh(std::span<const Eigen::Vector3f> normals, const Eigen::Vector3f& centroid);

struct RollOptions {
  int max_peaks = 5;               ///< PCL: 5
  float quantile = 0.2f;           ///< share of the correlation's lags scanned, best first (PCL: 0.2)
  float accept_threshold = 0.8f;   ///< a peak must reach this share of the best (PCL: 0.8)
};

/// Roll angles in degrees (multiples of 2) that turn `view` onto `scene`, best first, as PCL's
/// CRHAlignment::computeRollAngle(view, scene).
std::vector<float> crh_roll_angles(const Crh& view, const Crh& scene, const RollOptions& options = {});

/// The rotation that turns the ray through `centroid` onto the +z axis (PCL's CRH frame).
Eigen::Matrix3d ray_to_z(const Eigen::Vector3d& centroid);

/// PCL's CRHAlignment::align for one roll angle: the transform that carries the view's camera
/// frame into the scene camera's, moving the view's centroid onto the scene's and turning it by
/// `roll_deg` about the viewing ray. T_camera_object = result * T_view_object.
Transform crh_alignment(const Eigen::Vector3d& view_centroid, const Eigen::Vector3d& scene_centroid, double roll_deg);

}  // namespace viewpose
