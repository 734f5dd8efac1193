#pragma once
// The Viewpoint Feature Histogram (Rusu et al. 2010) as PCL's VFHEstimation computes it
// (../shared/reference/pcl-spec.md, sections 1-2): 308 bins in PCL's order,
//   0-44 f1 (atan2 angle), 45-89 f2 (v.n), 90-134 f3 (u.d), 135-179 f4 (shape distribution),
//   180-307 viewpoint component,
// computed between the cluster's centroid (with the mean normal) and every point.
#include <array>
#include <span>

#include <Eigen/Core>

namespace viewpose {

using Vfh = std::array<float, 308>;

struct VfhOptions {
  bool normalize_bins = true;       ///< histograms sum to about 100 (PCL default; the thesis's choice)
  bool normalize_distances = true;  ///< f4 bins relative to the largest centroid distance (PCL's 3d_rec_framework)
  bool size_component = false;      ///< fill the f4 bins (off in PCL's recognition framework)
  /// Reproduce PCL exactly, quirks included: f2 and f3 (in [-1, 1]) binned as if they spanned
  /// [-pi, pi], so they fill only bins 15-29 of their 45; the mean normal left unnormalized; and the
  /// homogeneous w = 1 of PCL's centroid leaking into the viewpoint direction and the distance
  /// normalization. Off: every feature spans its full bin range and the vectors are plain 3-D.
  bool pcl_compatible = true;
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();  ///< the sensor, in the cloud's frame
};

/// The VFH of points with unit normals (points whose normal is not finite are skipped). The
/// centroid is the mean of the points, as PCL's compute3DCentroid.
Vfh compute_vfh(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals,
                const VfhOptions& options = {});

/// PCL's computePairFeatures: the Darboux-frame angles between (p1, n1) and (p2, n2) and their
/// distance. Returns false, with all four zero, when the points coincide or the frame degenerates.
bool pair_features(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2,
                   const Eigen::Vector3f& n2, float& f1, float& f2, float& f3, float& f4);

}  // namespace viewpose
