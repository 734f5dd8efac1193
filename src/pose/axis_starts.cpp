#include "viewpose/pose/axis_starts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace viewpose {

namespace {

std::vector<Eigen::Vector3d> finite_points(std::span<const Eigen::Vector3f> points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) {
    if (p.allFinite()) out.push_back(p.cast<double>());
  }
  return out;
}

// The width of the middle `share` of the values: from the quantile (1 - share) / 2 to its mirror
// (selected, not sorted: this runs on every region of every frame).
double central_interval(std::vector<double>& values, double share) {
  const double tail = std::clamp((1.0 - share) / 2.0, 0.0, 0.5);
  const auto last = values.size() - 1;
  const auto lo = static_cast<std::size_t>(std::floor(tail * static_cast<double>(last)));
  const auto hi = last - lo;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(lo), values.end());
  const double low = values[lo];
  std::nth_element(values.begin() + static_cast<std::ptrdiff_t>(lo), values.begin() + static_cast<std::ptrdiff_t>(hi), values.end());
  return values[hi] - low;
}

// The least and greatest of each coordinate of the vectors added.
struct Span3 {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  void add(const Eigen::Vector3d& v) { lo = lo.cwiseMin(v), hi = hi.cwiseMax(v); }
};

}  // namespace

StripSize strip_size(std::span<const Eigen::Vector3f> points, double share) {
  const std::vector<Eigen::Vector3d> finite = finite_points(points);
  if (finite.size() < 2) return {};
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : finite) mean += p;
  mean /= static_cast<double>(finite.size());
  if (!(mean.norm() > 0)) return {};
  // Two directions square to the ray: the image's axes, near enough, at the region's distance.
  const Eigen::Vector3d ray = mean.normalized();
  const Eigen::Vector3d a = ray.unitOrthogonal(), b = ray.cross(a);
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  for (const auto& p : finite) {
    const Eigen::Vector2d q(a.dot(p - mean), b.dot(p - mean));
    covariance += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(covariance);
  std::vector<double> along(finite.size());
  StripSize size;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d u = solver.eigenvectors().col(k);
    const Eigen::Vector3d direction = u.x() * a + u.y() * b;
    for (std::size_t i = 0; i < finite.size(); ++i) along[i] = direction.dot(finite[i]);
    (k == 0 ? size.width_m : size.length_m) = central_interval(along, share);
    if (k == 0) size.across = direction;
  }
  return size;
}

std::vector<Transform> edge_on_poses(const PrincipalAxes& object, std::span<const Eigen::Vector3f> model_points,
                                     std::span<const Eigen::Vector3f> region_points, const Eigen::Vector3d& across, int turns) {
  std::vector<Transform> poses;
  const std::vector<Eigen::Vector3d> model = finite_points(model_points), seen = finite_points(region_points);
  if (model.empty() || seen.empty() || turns < 1 || !(across.norm() > 0)) return poses;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : seen) mean += p;
  mean /= static_cast<double>(seen.size());
  if (!(mean.norm() > 0)) return poses;
  const Eigen::Vector3d ray = mean.normalized();
  // A thin axis along the ray is no edge seen: nothing across the image to turn about.
  const Eigen::Vector3d thin = across.normalized();
  const Eigen::Vector3d side = thin - thin.dot(ray) * ray;
  if (!(side.norm() > 1e-6)) return poses;
  // The plane square to `across`: the ray's part in it first (the object's plane holds the ray).
  const Eigen::Vector3d in_plane = (ray - ray.dot(thin) * thin).normalized();
  // Where the region lies: across the image (its strip's two directions) and along the ray.
  Eigen::Matrix3d basis;
  basis.col(0) = side.normalized();
  basis.col(1) = ray.cross(basis.col(0));
  basis.col(2) = ray;
  Span3 region;
  for (const auto& p : seen) region.add(basis.transpose() * (p - mean));
  const double pi = std::acos(-1.0);
  for (const double sign : {1.0, -1.0}) {
    const Eigen::Vector3d normal = sign * thin;
    const Eigen::Vector3d other = normal.cross(in_plane);
    for (int k = 0; k < turns; ++k) {
      const double angle = 2.0 * pi * static_cast<double>(k) / static_cast<double>(turns);
      // Where the object's widest, middle and thinnest axes go (right-handed, as theirs are).
      Eigen::Matrix3d onto;
      onto.col(0) = std::cos(angle) * in_plane + std::sin(angle) * other;
      onto.col(2) = normal;
      onto.col(1) = onto.col(2).cross(onto.col(0));
      const Eigen::Matrix3d R_camera_object = onto * object.axes.transpose();
      // Seen edge-on, the whole object projects onto its strip: its outline's middle put at the
      // strip's across the image, and its near side at the region's along the ray.
      Span3 object_span;
      for (const auto& p : model) object_span.add(basis.transpose() * (R_camera_object * (p - object.mean)));
      const Eigen::Vector3d shift(0.5 * (region.lo.x() + region.hi.x() - object_span.lo.x() - object_span.hi.x()),
                                  0.5 * (region.lo.y() + region.hi.y() - object_span.lo.y() - object_span.hi.y()),
                                  region.lo.z() - object_span.lo.z());
      Transform T_camera_object = Transform::Identity();
      T_camera_object.linear() = R_camera_object;
      T_camera_object.translation() = mean + basis * shift - R_camera_object * object.mean;
      poses.push_back(T_camera_object);
    }
  }
  return poses;
}

}  // namespace viewpose
