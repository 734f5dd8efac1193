// estimate_normals against the textbook computation: every point's neighbours found by brute
// force, their covariance in double precision and a general 3x3 eigensolver. Covers the planar
// case (solved by Newton's method on the characteristic polynomial), curved and cornered surfaces,
// clouds far from the origin, and line-like neighbourhoods, where the smallest eigenvalue is not
// separated and the general solver takes over.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "viewpose/describe/normals.hpp"

namespace viewpose {
namespace {

struct Reference {
  Eigen::Vector3d normal = Eigen::Vector3d::Constant(std::nan(""));
  double curvature = std::nan("");
  double gap = 0;  // (l1 - l0) / (l0 + l1 + l2): how well the normal is defined
};

Reference brute_force(const PointCloud& cloud, std::size_t i, float radius, const Eigen::Vector3f& viewpoint) {
  const Eigen::Vector3f p = cloud.points[i];
  std::vector<Eigen::Vector3d> nb;
  for (const auto& q : cloud.points)
    if ((q - p).squaredNorm() <= radius * radius) nb.push_back(q.cast<double>());
  Reference r;
  if (nb.size() < 3) return r;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : nb) mean += q;
  mean /= static_cast<double>(nb.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : nb) cov += (q - mean) * (q - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d l = eig.eigenvalues();
  r.normal = eig.eigenvectors().col(0);
  if (r.normal.dot((viewpoint - p).cast<double>()) < 0) r.normal = -r.normal;
  r.curvature = l[0] / l.sum();
  r.gap = (l[1] - l[0]) / l.sum();
  return r;
}

// Samples of a surface given as a function of (u, v), with Gaussian noise along z.
template <typename Surface>
PointCloud sample(Surface surface, int n, float noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uv(-0.04f, 0.04f);
  std::normal_distribution<float> dz(0.0f, noise);
  PointCloud c;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3f p = surface(uv(rng), uv(rng));
    p.z() += dz(rng);
    c.points.push_back(p);
  }
  c.width = static_cast<int>(c.points.size());
  return c;
}

void expect_like_brute_force(PointCloud cloud, const char* what) {
  SCOPED_TRACE(what);
  const NormalOptions options;
  estimate_normals(cloud, options);
  int compared = 0, ill_defined = 0;
  double worst_deg = 0, worst_curvature = 0;
  for (std::size_t i = 0; i < cloud.size(); i += 3) {
    const Reference ref = brute_force(cloud, i, options.radius_m, options.viewpoint);
    ASSERT_EQ(ref.normal.allFinite(), cloud.normals[i].allFinite()) << "point " << i;
    if (!ref.normal.allFinite()) continue;
    const Eigen::Vector3d n = cloud.normals[i].cast<double>();
    ASSERT_NEAR(n.norm(), 1.0, 1e-5);
    worst_curvature = std::max(worst_curvature, std::abs(cloud.curvature[i] - ref.curvature));
    if (ref.gap < 1e-3) {  // the normal is any direction in a plane: both must lie in it
      ++ill_defined;
      continue;
    }
    worst_deg = std::max(worst_deg, std::acos(std::clamp(n.dot(ref.normal), -1.0, 1.0)) * 180 / std::numbers::pi);
    ++compared;
  }
  EXPECT_GT(compared, 100);
  EXPECT_LT(worst_deg, 0.02);
  EXPECT_LT(worst_curvature, 1e-5);
}

TEST(Normals, EqualABruteForceFitOnANoisyPlane) {
  expect_like_brute_force(sample([](float u, float v) { return Eigen::Vector3f(u, v, 0.8f + 0.3f * u); }, 3000, 0.001f, 1),
                          "plane");
}

TEST(Normals, EqualABruteForceFitOnASphereFarAway) {
  // A 3 cm sphere cap 3 m away: offsets of centimetres from coordinates of metres.
  expect_like_brute_force(sample([](float u, float v) {
                            const float r = 0.03f, s = std::min(u * u + v * v, r * r * 0.95f);
                            return Eigen::Vector3f(u, v, 3.0f - std::sqrt(r * r - s));
                          }, 3000, 0.0005f, 2),
                          "sphere");
}

TEST(Normals, EqualABruteForceFitOnABoxCorner) {
  // Three faces meet: at the edges and the corner the smallest eigenvalue is large.
  expect_like_brute_force(sample([](float u, float v) {
                            return Eigen::Vector3f(u, v, 1.0f + 0.5f * std::max({std::abs(u), std::abs(v), 0.0f}) + (u > 0 && v > 0 ? u : 0.0f));
                          }, 3000, 0.0003f, 3),
                          "corner");
}

TEST(Normals, LineLikeNeighbourhoodsGiveANormalAcrossTheLine) {
  // Points along a straight line: every direction across it fits, none along it may come out.
  std::mt19937 rng(4);
  std::normal_distribution<float> jitter(0.0f, 1e-6f);
  PointCloud c;
  const Eigen::Vector3f direction = Eigen::Vector3f(1, 2, 0.5f).normalized();
  for (int k = 0; k < 200; ++k)
    c.points.push_back(Eigen::Vector3f(0.1f, 0, 1) + direction * (0.0005f * static_cast<float>(k)) +
                       Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)));
  c.width = static_cast<int>(c.points.size());
  estimate_normals(c);
  for (std::size_t i = 0; i < c.size(); ++i) {
    ASSERT_TRUE(c.normals[i].allFinite()) << i;
    EXPECT_NEAR(c.normals[i].norm(), 1.0f, 1e-4f);
    EXPECT_LT(std::abs(c.normals[i].dot(direction)), 0.01f) << i;
  }
}

}  // namespace
}  // namespace viewpose
