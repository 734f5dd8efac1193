#include "viewpose/pose/points_on_model.hpp"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace viewpose {
namespace {

// A square plate 10 x 10 cm in the object's xy plane, a point every 2 mm, its normals along +z.
IcpTarget plate() {
  std::vector<Eigen::Vector3f> points, normals;
  for (int i = -25; i <= 25; ++i)
    for (int j = -25; j <= 25; ++j) {
      points.emplace_back(0.002f * static_cast<float>(i), 0.002f * static_cast<float>(j), 0.0f);
      normals.emplace_back(0.0f, 0.0f, 1.0f);
    }
  return IcpTarget(std::move(points), std::move(normals));
}

// The plate 1 m in front of the camera, turned a little so that no axis lines up with the grid's.
Transform plate_pose() {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())).toRotationMatrix();
  return make_transform(R, Eigen::Vector3d(0.01, -0.02, 1.0));
}

// A point of the plate's frame in the camera's.
Eigen::Vector3f in_camera(const Transform& T_camera_object, float x, float y, float z) {
  return (T_camera_object * Eigen::Vector3d(x, y, z)).cast<float>();
}

TEST(PointsOnModel, EachPointIsFarNearOrOnAsTheExactNearestModelPointSays) {
  const IcpTarget model = plate();
  const Transform T = plate_pose();
  const VerifyOptions verify;
  const IcpOptions icp;
  const float reach = 0.02f;
  // Points around the plate, out to 5 cm beyond it each way (the grid's margin is ICP's 4 cm).
  std::mt19937 random(7);
  std::uniform_real_distribution<float> xy(-0.1f, 0.1f), z(-0.05f, 0.05f);
  std::vector<Eigen::Vector3f> points;
  std::vector<NearModel> expected;
  while (points.size() < 4000) {
    const Eigen::Vector3f q(xy(random), xy(random), z(random));
    const Eigen::Vector3f p = in_camera(T, q.x(), q.y(), q.z());
    float d2 = std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& m : model.points) d2 = std::min(d2, (m - q).squaredNorm());
    const float d = std::sqrt(d2), tolerance = std::min(reach, depth_tolerance(p.z(), verify));
    if (std::abs(d - reach) < 1e-4f || std::abs(d - tolerance) < 1e-4f) continue;  // (no rounding's call)
    points.push_back(p);
    expected.push_back(d > reach ? NearModel::far : d > tolerance ? NearModel::near : NearModel::on);
  }
  const std::vector<NearModel> got = near_model(points, model, T, reach, verify, icp);
  ASSERT_EQ(got.size(), points.size());
  std::size_t counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(got[i], expected[i]) << "point " << i;
    ++counts[static_cast<int>(expected[i])];
  }
  // Every kind is tested, many times over.
  for (const std::size_t n : counts) EXPECT_GT(n, 200u);
  // A reach beyond the grid's margin is answered by the tree, as exactly.
  const float wide = 0.06f;
  const std::vector<NearModel> wider = near_model(points, model, T, wide, verify, icp);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (expected[i] == NearModel::far) continue;
    EXPECT_EQ(wider[i], expected[i] == NearModel::on ? NearModel::on : NearModel::near);
  }
}

TEST(PointsOnModel, NoReachAndPointsWithoutDepthAreFar) {
  const IcpTarget model = plate();
  const Transform T = plate_pose();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> points = {in_camera(T, 0, 0, 0), Eigen::Vector3f(nan, nan, nan)};
  const std::vector<NearModel> got = near_model(points, model, T, 0.02f, {}, {});
  EXPECT_EQ(got[0], NearModel::on);
  EXPECT_EQ(got[1], NearModel::far);
  for (const NearModel n : near_model(points, model, T, 0.0f, {}, {})) EXPECT_EQ(n, NearModel::far);
}

TEST(PointsOnModel, ThePieceGrownIsTheOneTheModelLiesOnNotTheLargest) {
  // A part of the plate seen (its left end, on the model), and beside its right end, 3 cm to the
  // side of the part, a neighbour's surface 1.5 cm behind the plate: within the reach, beyond the
  // tolerance, four times as many points, and a piece of its own. Farther off, a wall.
  const IcpTarget model = plate();
  const Transform T = plate_pose();
  const VerifyOptions verify;
  ASSERT_LT(depth_tolerance(1.1f, verify), 0.015f);
  PointCloud region;
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 10; ++j) region.points.push_back(in_camera(T, -0.05f + 0.002f * static_cast<float>(i), 0.002f * static_cast<float>(j), 0));
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 15; ++j) region.points.push_back(in_camera(T, 0.01f + 0.001f * static_cast<float>(i), 0.001f * static_cast<float>(j), -0.015f));
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) region.points.push_back(in_camera(T, -0.05f + 0.0025f * static_cast<float>(i), -0.05f + 0.0025f * static_cast<float>(j), -0.06f));
  region.width = static_cast<int>(region.points.size());
  const ClusterOptions clusters;
  const PointCloud piece = piece_on_model(region, model, T, 0.02f, verify, {}, clusters);
  ASSERT_EQ(piece.size(), 150u);
  for (std::size_t k = 0; k < piece.size(); ++k) EXPECT_EQ(piece.points[k], region.points[k]);
  // Without the part, the neighbour's surface is all there is within reach: that piece.
  PointCloud beside;
  beside.points.assign(region.points.begin() + 150, region.points.end());
  beside.width = static_cast<int>(beside.points.size());
  EXPECT_EQ(piece_on_model(beside, model, T, 0.02f, verify, {}, clusters).size(), 600u);
  // Pieces smaller than the clusters' least: none.
  ClusterOptions fewer = clusters;
  fewer.min_points = 1000;
  EXPECT_EQ(piece_on_model(region, model, T, 0.02f, verify, {}, fewer).size(), 0u);
}

}  // namespace
}  // namespace viewpose
