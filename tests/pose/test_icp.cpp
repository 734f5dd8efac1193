#include <algorithm>
#include <cmath>
#include <random>

#include "test_support.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/pose/icp.hpp"

namespace viewpose {
namespace {

// A 12 x 8 x 5 cm box's surface sampled every 2.5 mm, with outward normals: an asymmetric target.
void box_surface(std::vector<Eigen::Vector3f>& points, std::vector<Eigen::Vector3f>& normals) {
  const Eigen::Vector3f half(0.06f, 0.04f, 0.025f);
  const float step = 0.0025f;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      for (float s = -half[a]; s <= half[a]; s += step)
        for (float t = -half[b]; t <= half[b]; t += step) {
          Eigen::Vector3f p, n = Eigen::Vector3f::Zero();
          p[axis] = sign * half[axis];
          p[a] = s;
          p[b] = t;
          n[axis] = sign;
          points.push_back(p);
          normals.push_back(n);
        }
    }
}

TEST(Icp, ATargetTooLargeForAGridIsSearchedInItsTree) {
  // A box and a point 3 km away: a 3 mm grid over both would be 10^18 cells. None is made, and ICP
  // still recovers a pose from the k-d tree.
  std::vector<Eigen::Vector3f> points, normals;
  box_surface(points, normals);
  points.emplace_back(3000.0f, 0.0f, 0.0f);
  normals.emplace_back(1.0f, 0.0f, 0.0f);
  const IcpTarget target(points, normals);
  EXPECT_EQ(target.grid(0.003f, 0.04f), nullptr);
  EXPECT_EQ(target.grid(0.0f, 0.04f), nullptr);
  std::vector<Eigen::Vector3f> source;
  for (std::size_t i = 0; i + 1 < points.size(); ++i)
    if (normals[i].z() > 0) source.push_back(points[i] + Eigen::Vector3f(0.003f, 0.0f, 0.002f));
  const IcpResult r = icp_point_to_plane(source, target, Transform::Identity());
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.T_target_source.translation().z(), -0.002, 0.0005);
}

TEST(Icp, GridAndTreeCorrespondencesBothRecoverAKnownPose) {
  std::vector<Eigen::Vector3f> points, normals;
  box_surface(points, normals);
  const IcpTarget target(points, normals);
  // The source: the three faces a camera would see, moved by a known pose, with 1 mm noise.
  const Transform T_target_source_true =
      make_transform(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix(), {0.01, -0.02, 0.015});
  std::mt19937_64 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.001f);
  std::vector<Eigen::Vector3f> source;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (normals[i].x() < 0 || normals[i].y() < 0 || normals[i].z() < 0) continue;
    source.push_back((T_target_source_true.inverse() * points[i].cast<double>()).cast<float>() +
                     Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  }
  // Start 2 cm and 8 degrees off.
  const Transform start = make_transform(Eigen::AngleAxisd(0.14, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix(),
                                         {0.02, 0.0, 0.0}) * T_target_source_true;
  for (float cell : {0.003f, 0.0f}) {
    SCOPED_TRACE(cell > 0 ? "grid" : "k-d tree");
    IcpOptions o;
    o.grid_cell_m = cell;
    const IcpResult r = icp_point_to_plane(source, target, start, o);
    ASSERT_TRUE(r.converged);
    EXPECT_GT(r.fitness, 0.95);
    EXPECT_LT((r.T_target_source.translation() - T_target_source_true.translation()).norm(), 0.001);
    EXPECT_LT(rotation_difference_deg(r.T_target_source.linear(), T_target_source_true.linear()), 0.3);
  }
}

TEST(Icp, OneStepIsTheGaussNewtonStepOfTheTextbookNormalEquations) {
  // One step from a pose 1 cm and 6 degrees off, its correspondences the exact nearest (k-d tree):
  // the step must be the one the whole outer products J J^T and J r give, summed with Eigen and
  // solved here. (ICP sums them entry by entry, for speed; an entry wrong, or two swapped, moves it.)
  std::vector<Eigen::Vector3f> all_points, all_normals, points, normals;
  box_surface(all_points, all_normals);
  // The box's edges and corners are sampled once per face: one point each (with its first face's
  // normal), so that no two model points tie for nearest.
  for (std::size_t i = 0; i < all_points.size(); ++i) {
    const bool seen = std::any_of(points.begin(), points.end(), [&](const Eigen::Vector3f& q) { return (q - all_points[i]).norm() < 1e-5f; });
    if (!seen) points.push_back(all_points[i]), normals.push_back(all_normals[i]);
  }
  const IcpTarget target(points, normals);
  std::mt19937_64 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.001f);
  std::vector<Eigen::Vector3f> source;
  for (std::size_t i = 0; i < points.size(); i += 17) source.push_back(points[i] + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  ASSERT_LT(source.size(), 400u);  // every point takes part
  const Transform start = make_transform(Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix(), {0.01, -0.004, 0.006});
  IcpOptions o;
  o.grid_cell_m = 0;
  o.max_correspondence_m = {0.02f};
  o.max_iterations_per_stage = 1;
  const IcpResult r = icp_point_to_plane(source, target, start, o);
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
  const Eigen::Matrix3f R = start.linear().cast<float>();
  const Eigen::Vector3f t = start.translation().cast<float>();
  std::size_t used = 0;
  for (const Eigen::Vector3f& s : source) {
    const Eigen::Vector3f p = R * s + t;
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < points.size(); ++k) {
      if ((points[k] - p).squaredNorm() < (points[nearest] - p).squaredNorm()) nearest = k;
    }
    if ((points[nearest] - p).squaredNorm() > 0.02f * 0.02f) continue;
    const Eigen::Vector3d n = normals[nearest].cast<double>(), pd = p.cast<double>();
    Eigen::Matrix<double, 6, 1> J;
    J << pd.cross(n), n;
    const double residual = n.dot(pd - points[nearest].cast<double>());
    JtJ += J * J.transpose();
    Jtr += J * residual;
    ++used;
  }
  ASSERT_GT(used, 100u);
  const Eigen::Matrix<double, 6, 1> x = JtJ.ldlt().solve(-Jtr);
  Transform step = Transform::Identity();
  step.linear() = Eigen::AngleAxisd(x.head<3>().norm(), x.head<3>().normalized()).toRotationMatrix();
  step.translation() = x.tail<3>();
  const Transform expected = step * start;
  EXPECT_EQ(r.iterations, 1);
  EXPECT_LT((r.T_target_source.translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT((r.T_target_source.linear() - expected.linear()).norm(), 1e-9);
  // And the step did something: the pose moved by millimetres.
  EXPECT_GT((r.T_target_source.translation() - start.translation()).norm(), 1e-3);
}

TEST(Icp, FitnessAtAPoseIsTheShareWithinReach) {
  // The box's top face as the source, lifted off it by 6 mm: none within 5 mm, all within 7.5 mm
  // (the grid finds a point at most a cell diagonal farther than the nearest, so the tree is asked
  // too); with a quarter of it lifted by 3 cm, a quarter is out of reach; at the pose that puts it
  // back, all of it is on the surface.
  std::vector<Eigen::Vector3f> points, normals;
  box_surface(points, normals);
  const IcpTarget target(points, normals);
  std::vector<Eigen::Vector3f> top;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (normals[i].z() > 0.5f) top.push_back(points[i] + Eigen::Vector3f(0, 0, 0.006f));
  ASSERT_GT(top.size(), 400u);
  for (const float cell : {0.0f, 0.003f}) {
    SCOPED_TRACE(cell);
    IcpOptions o;
    o.grid_cell_m = cell;
    const Transform I = Transform::Identity();
    EXPECT_DOUBLE_EQ(icp_fitness(top, target, I, 0.005f, o), 0.0);
    EXPECT_DOUBLE_EQ(icp_fitness(top, target, I, 0.0075f + (cell > 0 ? 0.0052f : 0.0f), o), 1.0);
    EXPECT_DOUBLE_EQ(icp_fitness(top, target, make_transform(Eigen::Matrix3d::Identity(), {0, 0, -0.006}), 0.001f + (cell > 0 ? 0.0052f : 0.0f), o), 1.0);
    std::vector<Eigen::Vector3f> some = top;
    for (std::size_t i = 0; i < some.size(); i += 4) some[i].z() += 0.03f;
    o.max_source_points = 0;  // every point, so that the share is exact
    const double lifted = static_cast<double>((some.size() + 3) / 4) / static_cast<double>(some.size());
    EXPECT_NEAR(icp_fitness(some, target, make_transform(Eigen::Matrix3d::Identity(), {0, 0, -0.006}), 0.01f, o), 1.0 - lifted, 1e-12);
  }
}

TEST(Icp, LostHypothesesAreDroppedEarlyNotRefined) {
  std::vector<Eigen::Vector3f> points, normals;
  box_surface(points, normals);
  const IcpTarget target(points, normals);
  std::vector<Eigen::Vector3f> far_away(200, Eigen::Vector3f(1.0f, 1.0f, 1.0f));
  const IcpResult r = icp_point_to_plane(far_away, target, Transform::Identity());
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_EQ(r.iterations, 1);
}

}  // namespace
}  // namespace viewpose
