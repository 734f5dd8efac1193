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
    for (std::size_t i = 0; i < source.size(); ++i) pairs_[i].p = R * source[i] + t;
    // Every cell asked for before any is read, and every surfel before any is copied: the
    // processor then waits on many misses at once instead of on each in turn (the same results).
    if (grid_) {
      for (std::size_t i = 0; i < source.size(); ++i) {
        if (source[i].allFinite()) grid_->prefetch(pairs_[i].p);
      }
    }
    const std::vector<IcpTarget::Surfel>& surfels = target_.surfels();
    for (std::size_t i = 0; i < source.size(); ++i) {
      std::uint32_t k = none;
      float unused;
      const bool found = source[i].allFinite() && (grid_ ? grid_->held(pairs_[i].p, k) : target_.tree.nearest(pairs_[i].p, k, unused));
      index_[i] = found ? k : none;
      if (found) __builtin_prefetch(&surfels[k]);
    }
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

// The sums of a Gauss-Newton step's normal equations: the upper triangle of J^T J (all the solve
// reads) and J^T r, over correspondences with J = (p x n, n). Held and added as plain scalars, each
// entry named: built as an Eigen vector, J was stored in two halves and read back whole, which the
// processor cannot forward from its stores, and that wait was a third of ICP's time (perf annotate
// on real frames); a loop over the entries was not unrolled, and a rank update's library call cost
// more still. Each entry is the same sum, in the same order, as the whole outer product's.
struct NormalEquations {
  double h00 = 0, h01 = 0, h02 = 0, h03 = 0, h04 = 0, h05 = 0, h11 = 0, h12 = 0, h13 = 0, h14 = 0, h15 = 0;
  double h22 = 0, h23 = 0, h24 = 0, h25 = 0, h33 = 0, h34 = 0, h35 = 0, h44 = 0, h45 = 0, h55 = 0;
  double g0 = 0, g1 = 0, g2 = 0, g3 = 0, g4 = 0, g5 = 0;
  // The whole matrix (the lower triangle mirrors the upper) and the right-hand side.
  void unpack(Eigen::Matrix<double, 6, 6>& JtJ, Eigen::Matrix<double, 6, 1>& Jtr) const {
    JtJ(0, 0) = h00, JtJ(0, 1) = h01, JtJ(0, 2) = h02, JtJ(0, 3) = h03, JtJ(0, 4) = h04, JtJ(0, 5) = h05;
    JtJ(1, 1) = h11, JtJ(1, 2) = h12, JtJ(1, 3) = h13, JtJ(1, 4) = h14, JtJ(1, 5) = h15;
    JtJ(2, 2) = h22, JtJ(2, 3) = h23, JtJ(2, 4) = h24, JtJ(2, 5) = h25;
    JtJ(3, 3) = h33, JtJ(3, 4) = h34, JtJ(3, 5) = h35;
    JtJ(4, 4) = h44, JtJ(4, 5) = h45;
    JtJ(5, 5) = h55;
    JtJ.triangularView<Eigen::StrictlyLower>() = JtJ.transpose();
    Jtr << g0, g1, g2, g3, g4, g5;
  }
};

inline void add_normal_equations(const Eigen::Vector3d& c, const Eigen::Vector3d& n, double r, NormalEquations& s) {
  const double j0 = c.x(), j1 = c.y(), j2 = c.z(), j3 = n.x(), j4 = n.y(), j5 = n.z();
  s.h00 += j0 * j0, s.h01 += j0 * j1, s.h02 += j0 * j2, s.h03 += j0 * j3, s.h04 += j0 * j4, s.h05 += j0 * j5;
  s.h11 += j1 * j1, s.h12 += j1 * j2, s.h13 += j1 * j3, s.h14 += j1 * j4, s.h15 += j1 * j5;
  s.h22 += j2 * j2, s.h23 += j2 * j3, s.h24 += j2 * j4, s.h25 += j2 * j5;
  s.h33 += j3 * j3, s.h34 += j3 * j4, s.h35 += j3 * j5;
  s.h44 += j4 * j4, s.h45 += j4 * j5;
  s.h55 += j5 * j5;
  s.g0 += j0 * r, s.g1 += j1 * r, s.g2 += j2 * r, s.g3 += j3 * r, s.g4 += j4 * r, s.g5 += j5 * r;
}

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
      NormalEquations sums;
      std::size_t count = 0;
      double sum_r2 = 0;
      for (const auto& [p, q] : correspondences.find(source, result.T_target_source)) {
        if (!((q.point - p).squaredNorm() <= max_d2)) continue;  // (NaN: none found)
        const Eigen::Vector3d n = q.normal.cast<double>();
        if (!n.allFinite()) continue;
        const Eigen::Vector3d pd = p.cast<double>();
        const double r = n.dot(pd - q.point.cast<double>());
        add_normal_equations(pd.cross(n), n, r, sums);
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
      Eigen::Matrix<double, 6, 6> JtJ;
      Eigen::Matrix<double, 6, 1> Jtr;
      sums.unpack(JtJ, Jtr);
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
