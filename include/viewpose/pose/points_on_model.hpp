#pragma once
// Which of a region's points a posed model accounts for, and the piece of the region it lies on.
// A pose found on part of an object (a mug's wall, cut from its handle where the object touches
// unknown things) reaches into the rest of the region: the points near the model are grown into a
// region of their own and searched again. Near is not on: the reach takes in the neighbour's
// points beside the model too, and of the pieces within reach the model is taken to lie on the one
// holding most points within verification's depth tolerance.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/pose/icp.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/segment/clusters.hpp"

namespace viewpose {

enum class NearModel : std::uint8_t {
  far,   ///< farther than the reach from the model's surface
  near,  ///< within the reach
  on,    ///< within verification's depth tolerance at the point's depth (at most the reach)
};

/// Each point (camera frame) against the model posed at T_camera_object, by its exact nearest model
/// point. The model's nearest-point grid (IcpTarget::grid, made with `icp`'s cell and reach where
/// ICP has not made it already) answers most points; the k-d tree those its slack leaves undecided.
/// A reach of 0 or less (or NaN): every point is far; so is every point without depth.
std::vector<NearModel> near_model(std::span<const Eigen::Vector3f> points, const IcpTarget& model,
                                  const Transform& T_camera_object, float reach_m, const VerifyOptions& verify,
                                  const IcpOptions& icp);

/// Whether each point (camera frame) lies on the model posed at T_camera_object: within
/// verification's depth tolerance at its depth of the nearest model point (what a detection
/// explains of its region). near_model with a reach of the tolerance, at a look-up's cost: the grid
/// decides every point it can place within the tolerance or beyond it by more than its slack, the
/// k-d tree the rest. Points without depth are not on it.
std::vector<char> on_model(std::span<const Eigen::Vector3f> points, const IcpTarget& model, const Transform& T_camera_object,
                           const VerifyOptions& verify, const IcpOptions& icp);

/// The points within reach_m of the posed model, split into Euclidean pieces (`clusters`: pieces of
/// fewer than min_points or more than max_points are none), and of them the piece holding most
/// points on the model (ties: the larger), with the points' labels. Empty where there is no piece.
PointCloud piece_on_model(const PointCloud& points, const IcpTarget& model, const Transform& T_camera_object,
                          float reach_m, const VerifyOptions& verify, const IcpOptions& icp,
                          const ClusterOptions& clusters);

}  // namespace viewpose
