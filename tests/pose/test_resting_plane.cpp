// The plane an object rests on, against planes placed by construction around a box.
#include <cmath>
#include <limits>
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/pose/resting_plane.hpp"

namespace viewpose {
namespace {

// A 10 x 10 x 20 cm box (object frame centred, z its long side) standing 1 m in front of a camera
// looking level: the table 0.3 m below the camera (y down in the image), the box's base on it.
constexpr float kTableY = 0.3f;
const Eigen::Vector4f kTable(0, -1, 0, kTableY);  // n faces the camera: n.0 + d = 0.3 > 0
const std::vector<Eigen::Vector3f> kBox = make_box_mesh({0.1f, 0.1f, 0.2f}).vertices;
const std::vector<Eigen::Vector3d> kZ = {Eigen::Vector3d::UnitZ()};  // the box's standing axis

// Standing (object z up: -y in the camera), its base `gap` metres above the table.
Transform standing(float gap) {
  Eigen::Matrix3d R_camera_object;
  R_camera_object.col(0) = Eigen::Vector3d::UnitX();
  R_camera_object.col(1) = Eigen::Vector3d::UnitZ();
  R_camera_object.col(2) = -Eigen::Vector3d::UnitY();
  return make_transform(R_camera_object, {0.0, kTableY - 0.1 - gap, 1.0});
}

TEST(RestingPlane, ABoxStandingOnTheTableGetsItsUp) {
  const std::vector<Eigen::Vector4f> planes = {kTable};
  const auto up = resting_plane_up(planes, kBox, standing(0.0f), kZ, 0.008f);
  ASSERT_TRUE(up.has_value());
  EXPECT_NEAR((*up - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-6);
  // Within the tolerance above or into it (the plane's, the pose's and the sensor's errors).
  EXPECT_TRUE(resting_plane_up(planes, kBox, standing(0.006f), kZ, 0.008f).has_value());
  EXPECT_TRUE(resting_plane_up(planes, kBox, standing(-0.006f), kZ, 0.008f).has_value());
}

TEST(RestingPlane, ABoxHeldAboveOrSunkIntoThePlaneRestsOnNothing) {
  const std::vector<Eigen::Vector4f> planes = {kTable};
  EXPECT_FALSE(resting_plane_up(planes, kBox, standing(0.05f), kZ, 0.008f).has_value()) << "held 5 cm above";
  EXPECT_FALSE(resting_plane_up(planes, kBox, standing(-0.03f), kZ, 0.008f).has_value()) << "3 cm into the table";
  // Lying on its side it rests on the table, but with its z level: the table says nothing of which
  // way z points. Given its x as a standing axis too (a cube's symmetries give that), it does.
  const Transform lying = standing(0.0f) * make_transform(Eigen::AngleAxisd(std::acos(-1.0) / 2, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                                                         {0.05, 0.0, -0.05});
  EXPECT_FALSE(resting_plane_up(planes, kBox, lying, kZ, 0.008f).has_value());
  const std::vector<Eigen::Vector3d> z_and_x = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()};
  const auto up = resting_plane_up(planes, kBox, lying, z_and_x, 0.008f);
  ASSERT_TRUE(up.has_value());
  EXPECT_GT(up->dot(Eigen::Vector3d(0, -1, 0)), 0.999);
}

TEST(RestingPlane, AgainstAWallOnATableTheTableIsUpAndTheWallAloneIsNothing) {
  // A wall touching the box's side (x = 0.05, its normal toward the camera at x = 0), listed first;
  // a plane far behind; broken ones. The table is the up, whichever way the camera is rolled.
  const std::vector<Eigen::Vector4f> planes = {{-1, 0, 0, 0.05f}, {0, 0, -1, 3.0f}, kTable,
                                               {std::numeric_limits<float>::quiet_NaN(), 0, 0, 0}, {0, 0, 0, 0}};
  const auto up = resting_plane_up(planes, kBox, standing(0.0f), kZ, 0.008f);
  ASSERT_TRUE(up.has_value());
  EXPECT_GT(up->dot(Eigen::Vector3d(0, -1, 0)), 0.999);
  const Transform T_rolled_camera = make_transform(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector4f> rolled;  // the same planes seen by the camera turned half a turn about its z
  for (const Eigen::Vector4f& p : planes) rolled.push_back({-p.x(), -p.y(), p.z(), p.w()});
  const auto rolled_up = resting_plane_up(rolled, kBox, T_rolled_camera * standing(0.0f), kZ, 0.008f);
  ASSERT_TRUE(rolled_up.has_value());
  EXPECT_GT(rolled_up->dot(Eigen::Vector3d(0, 1, 0)), 0.999);
  // The wall alone: the box touches it, but its normal is square to the box's z.
  const std::vector<Eigen::Vector4f> wall = {planes[0]};
  EXPECT_FALSE(resting_plane_up(wall, kBox, standing(0.0f), kZ, 0.008f).has_value());
  EXPECT_FALSE(resting_plane_up({}, kBox, standing(0.0f), kZ, 0.008f).has_value());
  EXPECT_FALSE(resting_plane_up(planes, {}, standing(0.0f), kZ, 0.008f).has_value());
  EXPECT_FALSE(resting_plane_up(planes, kBox, standing(0.0f), {}, 0.008f).has_value());
}

}  // namespace
}  // namespace viewpose
