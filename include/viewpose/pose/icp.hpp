#pragma once
// Point-to-plane ICP: source points (a scene cluster, camera frame) pulled onto a target surface
// (the object's model cloud with normals, object frame). Coarse to fine: correspondences are first
// accepted up to the largest distance of the schedule, then the smaller ones, so that the few
// centimetres a centroid-and-roll guess is off still converge, and the final fit ignores outliers.
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

struct IcpOptions {
  std::vector<float> max_correspondence_m = {0.04f, 0.02f, 0.01f};  ///< one stage each
  int max_iterations_per_stage = 15;
  double convergence_translation_m = 1e-5;  ///< a stage ends when a step moves less than this...
  double convergence_rotation_rad = 1e-5;   ///< ...and turns less than this
  std::size_t min_correspondences = 12;
  /// At most this many source points take part, evenly spread over the source (0: all). A few
  /// hundred points pin six parameters down as well as thousands; the time is linear in them.
  std::size_t max_source_points = 400;
  /// After the first stage, give up (not converged) when fewer source points than this share found
  /// the target: a wrong hypothesis is dropped early instead of being refined to the end.
  double min_fitness_after_first_stage = 0.5;
};

struct IcpResult {
  Transform T_target_source = Transform::Identity();
  double fitness = 0;      ///< share of source points with a correspondence in the last stage
  double inlier_rmse = 0;  ///< RMS point-to-plane distance of those correspondences, metres
  int iterations = 0;
  bool converged = false;  ///< the last stage converged with enough correspondences
};

/// A model surface ready for ICP: points, normals and their k-d tree.
struct IcpTarget {
  IcpTarget(std::vector<Eigen::Vector3f> points, std::vector<Eigen::Vector3f> normals);
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  KdTree tree;
};

IcpResult icp_point_to_plane(std::span<const Eigen::Vector3f> source, const IcpTarget& target,
                             const Transform& T_target_source_initial, const IcpOptions& options = {});

}  // namespace viewpose
