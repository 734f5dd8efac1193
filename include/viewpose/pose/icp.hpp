#pragma once
// Point-to-plane ICP: source points (a scene cluster, camera frame) pulled onto a target surface
// (the object's model cloud with normals, object frame). Coarse to fine: correspondences are first
// accepted up to the largest distance of the schedule, then the smaller ones, so that the few
// centimetres a centroid-and-roll guess is off still converge, and the final fit ignores outliers.
#include <algorithm>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/nearest_grid.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

struct IcpOptions {
  std::vector<float> max_correspondence_m = {0.04f, 0.02f, 0.01f};  ///< one stage each
  int max_iterations_per_stage = 15;
  double convergence_translation_m = 1e-4;  ///< the last stage ends when a step moves less than this...
  double convergence_rotation_rad = 1e-4;   ///< ...and turns less than this (earlier stages: ten times),
  double convergence_relative_rmse = 1e-3;  ///< ...or the residual stays within this share of the last
  std::size_t min_correspondences = 12;
  /// At most this many source points take part, evenly spread over the source (0: all). A few
  /// hundred points pin six parameters down as well as thousands; the time is linear in them.
  std::size_t max_source_points = 400;
  /// Correspondences are looked up in the target's nearest-point grid of this cell size (constant
  /// time; the point found is within half a cell diagonal of the nearest, which a point-to-plane
  /// residual hardly feels, as it ignores slips along the surface). 0: exact k-d tree search.
  float grid_cell_m = 0.003f;
  /// The largest correspondence distance of the schedule: how far around the model the grid reaches.
  float reach_m() const {
    float reach = 0;
    for (float d : max_correspondence_m) reach = std::max(reach, d);
    return reach;
  }
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

/// A model surface ready for ICP: points, normals, their k-d tree, and a nearest-point grid whose
/// cells fill as ICP asks for them. Safe to share between threads.
struct IcpTarget {
  IcpTarget(std::vector<Eigen::Vector3f> points, std::vector<Eigen::Vector3f> normals);
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  KdTree tree;
  /// The grid of `cell_m` cells reaching `margin_m` beyond the points, made on the first call with
  /// cell_m > 0, whose sizes stay, and its `cells` if given (NearestGrid::cells() of the same grid,
  /// as a view database stores them). Null for cell_m 0, or where the grid would hold more than
  /// NearestGrid::kMaxCells (a scan metres across): look-ups then search the k-d tree.
  const NearestGrid* grid(float cell_m, float margin_m, std::span<const std::uint32_t> cells = {}) const;
  /// Each point beside its normal, in one cache line: ICP reads both for every correspondence, at
  /// random places in the model, and two lines a look-up were a third of its time.
  struct alignas(32) Surfel {
    Eigen::Vector3f point;
    float pad0 = 0;
    Eigen::Vector3f normal;
    float pad1 = 0;
  };
  const std::vector<Surfel>& surfels() const { return surfels_; }

 private:
  std::vector<Surfel> surfels_;
  mutable std::once_flag grid_once_;
  mutable std::unique_ptr<NearestGrid> grid_;
};

IcpResult icp_point_to_plane(std::span<const Eigen::Vector3f> source, const IcpTarget& target,
                             const Transform& T_target_source_initial, const IcpOptions& options = {});

/// ICP's fitness at a pose, without a step: the share of `source` (the points ICP would take,
/// options.max_source_points of them evenly spread) within `max_distance_m` of the target, looked
/// up as ICP looks it up (options.grid_cell_m).
double icp_fitness(std::span<const Eigen::Vector3f> source, const IcpTarget& target, const Transform& T_target_source,
                   float max_distance_m, const IcpOptions& options = {});

}  // namespace viewpose
