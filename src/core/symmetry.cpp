#include "viewpose/core/symmetry.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "viewpose/core/kdtree.hpp"

namespace viewpose {

namespace {

// Points spread evenly over the surface (by area), each with its triangle.
struct SurfaceSamples {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint32_t> triangle;
};

SurfaceSamples sample_surface(const TriangleMesh& mesh, std::size_t count, std::mt19937_64& rng) {
  SurfaceSamples s;
  std::vector<double> cumulative;
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          c = mesh.vertices[t[2]].cast<double>();
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative.push_back(total);
  }
  if (!(total > 0)) return s;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t k = 0; k < count; ++k) {
    const auto it = std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total);
    const auto index = static_cast<std::uint32_t>(std::min<std::ptrdiff_t>(it - cumulative.begin(), static_cast<std::ptrdiff_t>(cumulative.size()) - 1));
    const auto& t = mesh.triangles[index];
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1) {
      r1 = 1 - r1;
      r2 = 1 - r2;
    }
    const Eigen::Vector3f p = mesh.vertices[t[0]] + static_cast<float>(r1) * (mesh.vertices[t[1]] - mesh.vertices[t[0]]) +
                              static_cast<float>(r2) * (mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    s.points.push_back(p);
    s.triangle.push_back(index);
  }
  return s;
}

class SurfaceDistance {
 public:
  SurfaceDistance(const TriangleMesh& mesh, SurfaceSamples dense) : mesh_(mesh), dense_(std::move(dense)), tree_(dense_.points) {}

  // An upper bound of the distance from q to the surface, tight where q lies on it: the nearer of the
  // nearest sample and that sample's triangle.
  double operator()(const Eigen::Vector3d& q) const {
    std::uint32_t k = 0;
    float d2 = 0;
    if (!tree_.nearest(q.cast<float>(), k, d2)) return INFINITY;
    const auto& t = mesh_.triangles[dense_.triangle[k]];
    const Eigen::Vector3d on = closest_point_on_triangle(q, mesh_.vertices[t[0]].cast<double>(), mesh_.vertices[t[1]].cast<double>(),
                                                         mesh_.vertices[t[2]].cast<double>());
    return std::min(std::sqrt(static_cast<double>(d2)), (on - q).norm());
  }

 private:
  const TriangleMesh& mesh_;
  SurfaceSamples dense_;
  KdTree tree_;
};

Transform rotation_about(const Eigen::Vector3d& axis, const Eigen::Vector3d& point, double angle_rad) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  return make_transform(R, point - R * point);
}

// Two symmetries closer than 10 degrees are one (n-fold symmetries are at least 60 degrees apart);
// products of slightly inexact generators would otherwise breed near copies.
bool same_motion(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() < 10.0 * M_PI / 180.0;
}

}  // namespace

Symmetries find_symmetries(const TriangleMesh& mesh, const SymmetryOptions& o) {
  Symmetries out;
  if (mesh.triangles.empty()) return out;
  std::mt19937_64 rng(o.seed);
  SurfaceSamples dense = sample_surface(mesh, o.dense_samples, rng);
  const SurfaceSamples probe = sample_surface(mesh, o.samples, rng);
  if (dense.points.empty() || probe.points.empty()) return out;
  const double tolerance = o.tolerance_fraction * mesh_diameter(mesh);

  // Centre of the surface, exact (area-weighted triangle centroids), and its principal axes.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double area = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          c = mesh.vertices[t[2]].cast<double>();
    const double w = 0.5 * (b - a).cross(c - a).norm();
    centre += w * (a + b + c) / 3.0;
    area += w;
  }
  centre /= area;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : dense.points) {
    const Eigen::Vector3d q = p.cast<double>() - centre;
    cov += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  // Candidate axes: the model's own x, y, z first (CAD models are usually drawn square to their
  // symmetries, and principal axes are arbitrary where two moments are equal), then the principal
  // axes that are not within 2 degrees of those.
  std::vector<Eigen::Vector3d> axes;
  for (const Eigen::Vector3d& a : {Eigen::Vector3d(Eigen::Vector3d::UnitX()), Eigen::Vector3d(Eigen::Vector3d::UnitY()),
                                   Eigen::Vector3d(Eigen::Vector3d::UnitZ()), Eigen::Vector3d(eig.eigenvectors().col(2)),
                                   Eigen::Vector3d(eig.eigenvectors().col(1)), Eigen::Vector3d(eig.eigenvectors().col(0))}) {
    if (std::none_of(axes.begin(), axes.end(), [&](const Eigen::Vector3d& b) { return std::abs(a.dot(b)) > std::cos(2.0 * M_PI / 180.0); })) {
      axes.push_back(a.normalized());
    }
  }

  const SurfaceDistance distance(mesh, std::move(dense));
  const auto holds = [&](const Transform& S) {
    std::vector<double> d;
    d.reserve(probe.points.size());
    for (const auto& p : probe.points) d.push_back(distance(S * p.cast<double>()));
    const std::size_t k = d.size() * 99 / 100;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    return d[k] <= tolerance;
  };

  // Continuous: every one of a few unrelated angles holds.
  for (const Eigen::Vector3d& a : axes) {
    bool continuous = true;
    for (double deg : {23.0, 71.0, 137.0, 199.0}) continuous = continuous && holds(rotation_about(a, centre, deg * M_PI / 180.0));
    if (continuous) out.continuous.push_back({a, centre});
  }
  if (out.continuous.size() >= 2) {
    // Two axes of rotational symmetry: a sphere; any rotation about the centre.
    out.continuous = {{Eigen::Vector3d::UnitX(), centre}, {Eigen::Vector3d::UnitY(), centre}, {Eigen::Vector3d::UnitZ(), centre}};
    return out;
  }
  std::vector<Transform> generators;
  for (const Eigen::Vector3d& a : axes) {
    if (!out.continuous.empty()) {
      // Only a flip across the continuous axis adds anything; one is enough (the others are it
      // combined with a turn about the axis).
      if (std::abs(a.dot(out.continuous[0].axis)) > 0.01 || !generators.empty()) continue;
      const Transform flip = rotation_about(a, centre, M_PI);
      if (holds(flip)) generators.push_back(flip);
      continue;
    }
    for (int n : {6, 4, 3, 2}) {
      const Transform turn = rotation_about(a, centre, 2 * M_PI / n);
      if (holds(turn)) {
        generators.push_back(turn);
        break;
      }
    }
  }
  // The group the generators make (without the identity), capped at 48 (a cube's); each member is
  // checked in turn, so that a generator's small error cannot breed false members.
  std::vector<Transform> group = {Transform::Identity()};
  for (std::size_t i = 0; i < group.size() && group.size() < 48; ++i) {
    for (const Transform& g : generators) {
      const Transform next = group[i] * g;
      if (std::none_of(group.begin(), group.end(), [&](const Transform& h) { return same_motion(h, next); }) && holds(next)) {
        group.push_back(next);
      }
    }
  }
  out.discrete.assign(group.begin() + 1, group.end());
  return out;
}

std::vector<Transform> symmetry_transforms(const Symmetries& s, int continuous_steps) {
  std::vector<Transform> discrete = {Transform::Identity()};
  discrete.insert(discrete.end(), s.discrete.begin(), s.discrete.end());
  if (s.continuous.empty()) return discrete;
  const int steps = std::max(1, continuous_steps);
  std::vector<Transform> out;
  for (const ContinuousSymmetry& c : s.continuous) {
    for (int i = 0; i < steps; ++i) {
      const Transform C = rotation_about(c.axis, c.offset_m, 2.0 * M_PI * i / steps);
      for (const Transform& D : discrete) out.push_back(C * D);
    }
  }
  return out;
}

namespace {

// Among the poses T * S the symmetries make equivalent, the one whose rotation is nearest R_ref.
Transform nearest_equivalent(const Transform& T, const Symmetries& s, const Eigen::Matrix3d& R_ref) {
  if (s.empty()) return T;
  // In the maths below R is the rotation relative to the reference, R_ref^T R_camera_object.
  const Eigen::Matrix3d R = R_ref.transpose() * T.linear();
  if (s.continuous.size() >= 2) {
    // Any rotation about the centre: the one that leaves the object's axes on the reference's.
    const Eigen::Vector3d c = s.continuous[0].offset_m;
    return T * make_transform(R.transpose(), c - R.transpose() * c);
  }
  std::vector<Transform> discrete = {Transform::Identity()};
  discrete.insert(discrete.end(), s.discrete.begin(), s.discrete.end());
  Transform best = T;
  double best_trace = -INFINITY;
  for (const Transform& D : discrete) {
    Transform S = D;
    if (!s.continuous.empty()) {
      // The turn about the axis that brings R_camera_object * Rot(theta) * R_D nearest R_ref (the
      // relative R * Rot(theta) * R_D nearest the identity), in closed form: trace(A Rot(theta))
      // with A = R_D R is c cos + s sin + const.
      const Eigen::Vector3d a = s.continuous[0].axis.normalized();
      const Eigen::Matrix3d A = D.linear() * R;
      Eigen::Matrix3d ax;
      ax << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
      const double theta = std::atan2((A * ax).trace(), A.trace() - a.dot(A * a));
      S = rotation_about(a, s.continuous[0].offset_m, theta) * D;
    }
    const double trace = (R * S.linear()).trace();
    if (trace > best_trace + 1e-9) {
      best_trace = trace;
      best = T * S;
    }
  }
  return best;
}

}  // namespace

Transform canonical_pose(const Transform& T, const Symmetries& s) {
  // The object's x on the camera's x, its z up-and-toward the camera, half way between the
  // image's up (-y) and the camera (-z), its y completing the frame (canonical_pose's doc says why).
  const double h = std::sqrt(0.5);
  Eigen::Matrix3d R_ref;
  R_ref << 1, 0, 0,
           0, -h, -h,
           0, h, -h;
  return nearest_equivalent(T, s, R_ref);
}

Transform canonical_pose(const Transform& T, const Symmetries& s, const Eigen::Vector3d& up_camera) {
  if (!(up_camera.allFinite() && up_camera.norm() > 1e-6)) return canonical_pose(T, s);
  // The object's z on `up_camera`; its x on the horizontal heading of the camera's view (the
  // viewing direction made square to up, turned a quarter about up), which no roll of the camera
  // changes: a rolled camera sees the same pose. For a camera not rolled that is its own x, as in
  // the fixed reference. Looking (nearly) along up, where the view has no heading, the camera's x
  // made square to up.
  const Eigen::Vector3d z = up_camera.normalized();
  const Eigen::Vector3d level_view = Eigen::Vector3d::UnitZ() - z.z() * z;
  Eigen::Vector3d x = level_view.cross(z);
  if (level_view.norm() < 0.2) x = Eigen::Vector3d::UnitX() - z.x() * z;
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitY() - z.y() * z;
  x.normalize();
  Eigen::Matrix3d R_ref;
  R_ref.col(0) = x;
  R_ref.col(1) = z.cross(x);
  R_ref.col(2) = z;
  return nearest_equivalent(T, s, R_ref);
}

}  // namespace viewpose
