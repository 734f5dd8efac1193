#include "viewpose/pose/icp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace viewpose {

IcpTarget::IcpTarget(std::vector<Eigen::Vector3f> p, std::vector<Eigen::Vector3f> n)
    : points(std::move(p)), normals(std::move(n)), tree(points) {
  surfels_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    surfels_[i].point = points[i];
    surfels_[i].normal = i < normals.size() ? normals[i] : Eigen::Vector3f::Constant(NAN);
  }
}

const NearestGrid* IcpTarget::grid(float cell_m, float margin_m, std::span<const std::uint32_t> cells) const {
  if (!(cell_m > 0)) return nullptr;
  std::call_once(grid_once_, [&] {
    if (NearestGrid::cell_count(points, cell_m, margin_m) == std::numeric_limits<std::size_t>::max()) return;
    grid_ = cells.empty() ? std::make_unique<NearestGrid>(tree, points, cell_m, margin_m)
                          : std::make_unique<NearestGrid>(tree, points, cell_m, margin_m, cells);
  });
  return grid_.get();
}

namespace {

// An even subset: every k-th point, k chosen so that at most max_source_points remain (all of them
// when they are fewer, or max_source_points is 0).
std::span<const Eigen::Vector3f> even_subset(std::span<const Eigen::Vector3f> all, const IcpOptions& o,
                                             std::vector<Eigen::Vector3f>& subset) {
  if (o.max_source_points == 0 || all.size() <= o.max_source_points) return all;
  const double step = static_cast<double>(all.size()) / static_cast<double>(o.max_source_points);
  subset.reserve(o.max_source_points);
  for (std::size_t i = 0; i < o.max_source_points; ++i) subset.push_back(all[static_cast<std::size_t>(static_cast<double>(i) * step)]);
  return subset;
}

// Each source point moved by T, beside the target's point nearest it (with its normal): from the
// target's grid (IcpOptions::grid_cell_m) or its k-d tree. The look-ups of all points are made
// first, then the surfels read, then used: each pass's loads are independent of one another, and
// the processor overlaps them, where one loop that branched on each correspondence before the
// next look-up waited on each in turn (the look-ups were two thirds of ICP's time on real frames).
class Correspondences {
 public:
  struct Pair {
    Eigen::Vector3f p;          // the source point moved by T
    IcpTarget::Surfel q;        // the target's point nearest it; NaN when none was found
  };
  Correspondences(const IcpTarget& t, const IcpOptions& o)
      : target_(t), grid_(t.grid(o.grid_cell_m, o.reach_m())) {}

  std::span<const Pair> find(std::span<const Eigen::Vector3f> source, const Transform& T) {
    const Eigen::Matrix3f R = T.linear().cast<float>();
    const Eigen::Vector3f t = T.translation().cast<float>();
    pairs_.resize(source.size());
    index_.resize(source.size());
    const std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t i = 0; i < source.size(); ++i) {
      pairs_[i].p = R * source[i] + t;
      std::uint32_t k = none;
      float unused;
      const bool found = source[i].allFinite() && (grid_ ? grid_->held(pairs_[i].p, k) : target_.tree.nearest(pairs_[i].p, k, unused));
      index_[i] = found ? k : none;
    }
    const std::vector<IcpTarget::Surfel>& surfels = target_.surfels();
    for (std::size_t i = 0; i < source.size(); ++i) {
      if (index_[i] != none) pairs_[i].q = surfels[index_[i]];
      else pairs_[i].q.point = pairs_[i].q.normal = Eigen::Vector3f::Constant(NAN);
    }
    return pairs_;
  }

 private:
  const IcpTarget& target_;
  const NearestGrid* grid_;
  std::vector<Pair> pairs_;
  std::vector<std::uint32_t> index_;
};

}  // namespace

double icp_fitness(std::span<const Eigen::Vector3f> all_source, const IcpTarget& target, const Transform& T_target_source,
                   float max_distance_m, const IcpOptions& o) {
  if (all_source.empty() || target.points.empty()) return 0;
  std::vector<Eigen::Vector3f> subset;
  const std::span<const Eigen::Vector3f> source = even_subset(all_source, o, subset);
  Correspondences correspondences(target, o);
  const float max_d2 = max_distance_m * max_distance_m;
  std::size_t count = 0;
  // As an ICP step counts its correspondences: a finite point whose nearest has a normal (a NaN
  // distance, where none was found, fails the test).
  for (const auto& [p, q] : correspondences.find(source, T_target_source)) count += (q.point - p).squaredNorm() <= max_d2 && q.normal.allFinite();
  return static_cast<double>(count) / static_cast<double>(source.size());
}

IcpResult icp_point_to_plane(std::span<const Eigen::Vector3f> all_source, const IcpTarget& target,
                             const Transform& T_initial, const IcpOptions& o) {
  IcpResult result;
  result.T_target_source = T_initial;
  if (all_source.empty() || target.points.empty()) return result;
  std::vector<Eigen::Vector3f> subset;
  const std::span<const Eigen::Vector3f> source = even_subset(all_source, o, subset);
  Correspondences correspondences(target, o);
  for (std::size_t stage = 0; stage < o.max_correspondence_m.size(); ++stage) {
    const float max_d = o.max_correspondence_m[stage];
    const float max_d2 = max_d * max_d;
    bool converged = false;
    double previous_rmse = -1;
    for (int it = 0; it < o.max_iterations_per_stage; ++it) {
      ++result.iterations;
      // Gauss-Newton on r = n . (T s - q), with T perturbed by a small twist (omega, v) on the left.
      Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
      std::size_t count = 0;
      double sum_r2 = 0;
      for (const auto& [p, q] : correspondences.find(source, result.T_target_source)) {
        if (!((q.point - p).squaredNorm() <= max_d2)) continue;  // (NaN: none found)
        const Eigen::Vector3d n = q.normal.cast<double>();
        if (!n.allFinite()) continue;
        const Eigen::Vector3d pd = p.cast<double>();
        const double r = n.dot(pd - q.point.cast<double>());
        Eigen::Matrix<double, 6, 1> J;
        J << pd.cross(n), n;
        // The whole outer product, inlined: the same sums as a rank update of the upper triangle,
        // whose library call cost more than the arithmetic.
        JtJ.noalias() += J * J.transpose();
        Jtr.noalias() += J * r;
        sum_r2 += r * r;
        ++count;
      }
      result.fitness = static_cast<double>(count) / static_cast<double>(source.size());
      result.inlier_rmse = count ? std::sqrt(sum_r2 / static_cast<double>(count)) : 0.0;
      if (count < o.min_correspondences) return result;  // lost: not converged
      // The same fit as the step before: the correspondences have settled (or flip between two
      // equally good sets, which a grid's cells can make them do); another step changes nothing.
      if (previous_rmse >= 0 && std::abs(result.inlier_rmse - previous_rmse) <= o.convergence_relative_rmse * previous_rmse) {
        converged = true;
        break;
      }
      previous_rmse = result.inlier_rmse;
      const Eigen::Matrix<double, 6, 1> x = JtJ.selfadjointView<Eigen::Upper>().ldlt().solve(-Jtr);
      if (!x.allFinite()) return result;
      const Eigen::Vector3d omega = x.head<3>(), v = x.tail<3>();
      Transform step = Transform::Identity();
      if (omega.norm() > 0) step.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
      step.translation() = v;
      result.T_target_source = step * result.T_target_source;
      // Earlier stages only bring the pose within reach of the next: they stop at ten times the step.
      const double coarse = stage + 1 < o.max_correspondence_m.size() ? 10.0 : 1.0;
      if (v.norm() < coarse * o.convergence_translation_m && omega.norm() < coarse * o.convergence_rotation_rad) {
        converged = true;
        break;
      }
    }
    result.converged = converged;
    if (stage == 0 && result.fitness < o.min_fitness_after_first_stage) {
      result.converged = false;
      return result;
    }
  }
  return result;
}

}  // namespace viewpose
