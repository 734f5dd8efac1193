// Symmetries found on shapes whose symmetries are known by construction, and canonical poses.
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Geometry>

#include "test_support.hpp"
#include "viewpose/core/symmetry.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {
namespace {

Transform turn(const Eigen::Vector3d& axis, double deg, const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
  return make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix(), t);
}

// Largest distance a symmetry moves a mesh vertex off the surface.
double worst_displacement(const TriangleMesh& mesh, const Transform& S) {
  double worst = 0;
  for (std::size_t i = 0; i < mesh.vertices.size(); i += std::max<std::size_t>(1, mesh.vertices.size() / 200))
    worst = std::max(worst, distance_to_surface(mesh, S * mesh.vertices[i].cast<double>()));
  return worst;
}

TEST(Symmetry, ABoxWithThreeDifferentSidesHasItsThreeHalfTurns) {
  const TriangleMesh box = make_box_mesh({0.06f, 0.095f, 0.2f});
  const Symmetries s = find_symmetries(box);
  EXPECT_TRUE(s.continuous.empty());
  ASSERT_EQ(s.discrete.size(), 3u);
  for (const Transform& S : s.discrete) {
    EXPECT_NEAR(Eigen::AngleAxisd(S.linear()).angle(), std::numbers::pi, 1e-3);
    EXPECT_LT(worst_displacement(box, S), 1e-4);
  }
}

TEST(Symmetry, ASquareSectionAddsQuarterTurns) {
  const TriangleMesh box = make_box_mesh({0.05f, 0.05f, 0.2f});
  const Symmetries s = find_symmetries(box);
  EXPECT_TRUE(s.continuous.empty());
  EXPECT_EQ(s.discrete.size(), 7u);  // the dihedral group of the square, less the identity
}

TEST(Symmetry, ACanTurnsFreelyAboutItsAxisAndFlipsEndForEnd) {
  const TriangleMesh can = make_can();
  const Symmetries s = find_symmetries(can);
  ASSERT_EQ(s.continuous.size(), 1u);
  EXPECT_GT(std::abs(s.continuous[0].axis.dot(Eigen::Vector3d::UnitZ())), 0.999);
  // The axis passes through the can's middle: x = y = 0.
  const Eigen::Vector3d o = s.continuous[0].offset_m;
  const Eigen::Vector3d off_axis = o - o.dot(s.continuous[0].axis) * s.continuous[0].axis;
  EXPECT_LT(off_axis.norm(), 0.001);
  ASSERT_EQ(s.discrete.size(), 1u);  // upside down
  EXPECT_LT(worst_displacement(can, s.discrete[0]), 0.002);
}

TEST(Symmetry, AJugAndAMugWithHandlesHaveNone) {
  EXPECT_TRUE(find_symmetries(make_jug()).empty());
  EXPECT_TRUE(find_symmetries(make_mug()).empty());
}

TEST(Symmetry, ASphereTurnsEveryWay) {
  const Symmetries s = find_symmetries(make_sphere(0.05, 30));
  EXPECT_EQ(s.continuous.size(), 3u);
  // Any pose of it is reported as the reference: x along the camera's x, z up and toward the
  // camera, turned about its centre (which stays where it was).
  const Transform T = turn({1, 2, 0.5}, 70, {0.1, -0.05, 0.9});
  const Transform c = canonical_pose(T, s);
  const double h = std::sqrt(0.5);
  EXPECT_LT((c.linear().col(0) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-9);
  EXPECT_LT((c.linear().col(2) - Eigen::Vector3d(0, -h, -h)).norm(), 1e-9);
  EXPECT_LT((c * s.continuous[0].offset_m - T * s.continuous[0].offset_m).norm(), 1e-9);
}

TEST(Symmetry, EquivalentPosesGiveTheSameCanonicalPose) {
  const Transform T = turn({1, 2, 0.5}, 70, {0.1, -0.05, 0.9});
  // Box: each of its half turns.
  const TriangleMesh box = make_box_mesh({0.06f, 0.095f, 0.2f});
  const Symmetries box_s = find_symmetries(box);
  const Transform c = canonical_pose(T, box_s);
  for (const Transform& S : box_s.discrete) {
    const Transform other = canonical_pose(T * S, box_s);
    EXPECT_LT((other.matrix() - c.matrix()).norm(), 1e-6);
  }
  // Can: any turn about its axis, and upside down.
  const Symmetries can_s = find_symmetries(make_can());
  const Transform cc = canonical_pose(T, can_s);
  for (const Transform& S : symmetry_transforms(can_s, 10)) {
    const Transform other = canonical_pose(T * S, can_s);
    EXPECT_LT((other.linear() - cc.linear()).norm(), 1e-3);
    EXPECT_LT((other.translation() - cc.translation()).norm(), 1e-4);
  }
  // The canonical pose is one of the equivalent ones: it moves the can's surface onto itself.
  const TriangleMesh can = make_can();
  EXPECT_LT(worst_displacement(can, T.inverse() * cc), 0.002);
  // Without symmetries nothing changes.
  EXPECT_LT((canonical_pose(T, Symmetries{}).matrix() - T.matrix()).norm(), 1e-12);
}

TEST(Symmetry, ObjectsStandingAsModelledAreReportedUprightForAnyCameraTilt) {
  // A can and a box standing on a table (world z up, as their meshes are drawn), seen by a camera
  // looking level, down at 30 and 60 degrees, and straight down; each pose given upside down (an
  // equivalent pose). The canonical pose stands it up again: its z along the world's up.
  const TriangleMesh can = make_can(), box = make_box_mesh({0.06f, 0.095f, 0.2f});
  const Symmetries can_s = find_symmetries(can), box_s = find_symmetries(box);
  for (const double tilt_deg : {0.0, 30.0, 60.0, 90.0}) {
    const double t = tilt_deg * std::numbers::pi / 180.0;
    Eigen::Matrix3d R_world_camera;  // columns: the camera's x (right), y (down in the image), z (forward)
    R_world_camera.col(0) = Eigen::Vector3d::UnitX();
    R_world_camera.col(1) = Eigen::Vector3d(0, -std::sin(t), -std::cos(t));
    R_world_camera.col(2) = Eigen::Vector3d(0, std::cos(t), -std::sin(t));
    const Eigen::Vector3d up_in_camera = R_world_camera.transpose() * Eigen::Vector3d::UnitZ();
    for (const double yaw_deg : {0.0, 50.0, 140.0, 235.0}) {
      const Eigen::Matrix3d R_world_object = Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const Transform upright = make_transform(R_world_camera.transpose() * R_world_object, {0.02, 0.05, 0.8});
      const Transform upside_down = upright * turn({1, 0, 0}, 180);
      for (const auto& [name, s] : {std::pair{"can", &can_s}, std::pair{"box", &box_s}}) {
        const Transform c = canonical_pose(upside_down, *s);
        EXPECT_GT(c.linear().col(2).dot(up_in_camera), 0.999) << name << ", camera " << tilt_deg << " degrees down, yaw " << yaw_deg;
      }
    }
  }
}

TEST(Symmetry, GivenTheScenesUpObjectsAreReportedUprightForAnyCameraRollOrTilt) {
  // The same with the up the scene gives (the table's normal in the camera frame): a camera rolled
  // a quarter turn, half a turn (upside down: the fixed reference then stands them on their heads)
  // and three quarters, looking down or up. The canonical pose stands each up along it.
  const TriangleMesh can = make_can(), box = make_box_mesh({0.06f, 0.095f, 0.2f});
  const Symmetries can_s = find_symmetries(can), box_s = find_symmetries(box);
  std::size_t upside_down_by_fixed_reference = 0;
  for (const double tilt_deg : {-30.0, 0.0, 45.0, 90.0}) {
    for (const double roll_deg : {0.0, 90.0, 180.0, 270.0, 33.0}) {
      const double t = tilt_deg * std::numbers::pi / 180.0;
      Eigen::Matrix3d R_world_camera;
      R_world_camera.col(0) = Eigen::Vector3d::UnitX();
      R_world_camera.col(1) = Eigen::Vector3d(0, -std::sin(t), -std::cos(t));
      R_world_camera.col(2) = Eigen::Vector3d(0, std::cos(t), -std::sin(t));
      R_world_camera = R_world_camera * turn({0, 0, 1}, roll_deg).linear();  // rolled about its own z
      const Eigen::Vector3d up_in_camera = R_world_camera.transpose() * Eigen::Vector3d::UnitZ();
      // (Not 0: a box square to the heading, the camera straight down and rolled a quarter turn, is a
      // tie between its half turns, which either answer meets.)
      for (const double yaw_deg : {10.0, 50.0, 140.0, 235.0}) {
        const Eigen::Matrix3d R_world_object = Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        const Transform upright = make_transform(R_world_camera.transpose() * R_world_object, {0.02, 0.05, 0.8});
        for (const Transform& given : {upright, upright * turn({1, 0, 0}, 180), upright * turn({0, 1, 0}, 180)}) {
          for (const auto& [name, s] : {std::pair{"can", &can_s}, std::pair{"box", &box_s}}) {
            const Transform c = canonical_pose(given, *s, up_in_camera);
            // Every equivalent pose gives the same one.
            EXPECT_LT(rotation_difference_deg(c.linear(), canonical_pose(upright, *s, up_in_camera).linear()), 0.01) << name << " tilt " << tilt_deg << " roll " << roll_deg << " yaw " << yaw_deg;
            EXPECT_GT(c.linear().col(2).dot(up_in_camera), 0.999) << name << ", tilt " << tilt_deg << ", roll " << roll_deg << ", yaw " << yaw_deg;
            // Still one of the given pose's equivalents: the same surface.
            EXPECT_LT(worst_displacement(name == std::string("can") ? can : box, given.inverse() * c), 0.002) << name;
            upside_down_by_fixed_reference += canonical_pose(given, *s).linear().col(2).dot(up_in_camera) < 0 ? 1 : 0;
          }
        }
      }
    }
  }
  EXPECT_GT(upside_down_by_fixed_reference, 50u) << "the fixed reference alone fails these cameras";
}

TEST(Symmetry, RollingTheCameraDoesNotChangeTheCanonicalPoseInTheWorld) {
  // A can and a box standing still, a camera looking down 40 degrees rolled through a whole turn a
  // degree at a time: the pose reported, taken back to the world, stays the same (a reference
  // whose heading followed the camera's own axes would turn it with the roll, or flip it where its
  // rule switches).
  const TriangleMesh can = make_can(), box = make_box_mesh({0.06f, 0.095f, 0.2f});
  const Symmetries can_s = find_symmetries(can), box_s = find_symmetries(box);
  const double t = 40.0 * std::numbers::pi / 180.0;
  Eigen::Matrix3d R_world_level;
  R_world_level.col(0) = Eigen::Vector3d::UnitX();
  R_world_level.col(1) = Eigen::Vector3d(0, -std::sin(t), -std::cos(t));
  R_world_level.col(2) = Eigen::Vector3d(0, std::cos(t), -std::sin(t));
  const Transform T_world_object = make_transform(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {0.1, 0.8, 0.0});
  const Transform T_world_eye = make_transform(R_world_level, {0.0, 0.0, 0.6});
  for (const auto& [name, s] : {std::pair{"can", &can_s}, std::pair{"box", &box_s}}) {
    Transform first = Transform::Identity();
    for (int roll = 0; roll < 360; ++roll) {
      const Transform T_world_camera = T_world_eye * turn({0, 0, 1}, roll);
      const Transform T_camera_object = T_world_camera.inverse() * T_world_object * turn({1, 0, 0}, 180);  // given upside down
      const Eigen::Vector3d up_in_camera = T_world_camera.linear().transpose() * Eigen::Vector3d::UnitZ();
      const Transform in_world = T_world_camera * canonical_pose(T_camera_object, *s, up_in_camera);
      if (roll == 0) first = in_world;
      EXPECT_LT(rotation_difference_deg(in_world.linear(), first.linear()), 0.01) << name << ", roll " << roll;
    }
    EXPECT_GT(first.linear().col(2).z(), 0.999) << name << " standing";
  }
}

TEST(Symmetry, TheDefaultUpGivesTheFixedReferencesPoseBitForBit) {
  const TriangleMesh can = make_can();
  const Symmetries s = find_symmetries(can);
  const double h = std::sqrt(0.5);
  for (const double deg : {0.0, 37.0, 121.0, 250.0}) {
    const Transform T = make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(), {0.1, -0.05, 0.9});
    EXPECT_TRUE(canonical_pose(T, s).matrix() == canonical_pose(T, s, Eigen::Vector3d(0, -h, -h)).matrix()) << deg;
  }
}

}  // namespace
}  // namespace viewpose
