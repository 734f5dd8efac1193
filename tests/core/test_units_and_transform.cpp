#include <numbers>

#include "test_support.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/core/units.hpp"

namespace viewpose {
namespace {

BoundingBox box_of_size(float s) {
  BoundingBox b;
  b.extend({0, 0, 0});
  b.extend({s, s / 2, s / 3});
  return b;
}

TEST(Units, GuessReadsObjectsAndScenesInEitherUnit) {
  EXPECT_EQ(guess_length_unit(box_of_size(0.15f)).unit, LengthUnit::Metres);     // a bottle in metres
  EXPECT_EQ(guess_length_unit(box_of_size(4.0f)).unit, LengthUnit::Metres);      // a room-sized frame
  EXPECT_EQ(guess_length_unit(box_of_size(150.0f)).unit, LengthUnit::Millimetres);  // a bottle in mm
  EXPECT_EQ(guess_length_unit(box_of_size(1500.0f)).unit, LengthUnit::Millimetres);
  EXPECT_EQ(guess_length_unit(BoundingBox{}).unit, LengthUnit::Metres);
}

TEST(Units, MismatchWarningNamesTheOtherUnit) {
  EXPECT_NE(unit_mismatch_warning(box_of_size(150.0f), LengthUnit::Metres).find("millimetres"), std::string::npos);
  EXPECT_NE(unit_mismatch_warning(box_of_size(0.15f), LengthUnit::Millimetres).find("metres"), std::string::npos);
  EXPECT_TRUE(unit_mismatch_warning(box_of_size(0.15f), LengthUnit::Metres).empty());
  EXPECT_TRUE(unit_mismatch_warning(box_of_size(150.0f), LengthUnit::Millimetres).empty());
  // The warning names the flag that fixes it, and every unit that makes an object of 1 cm to 1.5 m:
  // 150 units (a bottle in mm) only millimetres; 40 units (a jug in cm, or a 4 cm box in mm) either.
  EXPECT_NE(unit_mismatch_warning(box_of_size(150.0f), LengthUnit::Metres).find("it looks like millimetres (--unit mm)"),
            std::string::npos);
  EXPECT_EQ(unit_mismatch_warning(box_of_size(150.0f), LengthUnit::Metres).find("centimetres"), std::string::npos);
  EXPECT_NE(unit_mismatch_warning(box_of_size(40.0f), LengthUnit::Metres)
                .find("it looks like millimetres (--unit mm) or centimetres (--unit cm)"),
            std::string::npos);
  EXPECT_NE(unit_mismatch_warning(box_of_size(0.15f), LengthUnit::Millimetres).find("(--unit m)"), std::string::npos);
  EXPECT_TRUE(unit_mismatch_warning(box_of_size(40.0f), LengthUnit::Centimetres).empty());
}

TEST(Units, ParseAndScale) {
  EXPECT_EQ(parse_length_unit("mm"), LengthUnit::Millimetres);
  EXPECT_EQ(parse_length_unit("m"), LengthUnit::Metres);
  EXPECT_DOUBLE_EQ(metres_per_unit(LengthUnit::Millimetres), 0.001);
  EXPECT_EQ(parse_length_unit("cm"), LengthUnit::Centimetres);
  EXPECT_DOUBLE_EQ(metres_per_unit(LengthUnit::Centimetres), 0.01);
  EXPECT_EQ(to_string(LengthUnit::Centimetres), "cm");
  test::expect_error([] { parse_length_unit("inch"); }, "inch");
}

Transform rz(double deg, const Eigen::Vector3d& t) {
  return make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix(), t);
}

TEST(Transform, FramesComposeRightToLeft) {
  const Transform T_world_camera = rz(90, {1, 0, 0});
  const Transform T_camera_object = rz(0, {0, 0, 2});
  const Eigen::Vector3d p_object(0.1, 0, 0);
  const Eigen::Vector3d p_world = (T_world_camera * T_camera_object) * p_object;
  // Object point (0.1, 0, 0) is (0.1, 0, 2) in the camera; a 90 degree turn and a shift give (1, 0.1, 2).
  EXPECT_TRUE(p_world.isApprox(Eigen::Vector3d(1, 0.1, 2), 1e-12));
  EXPECT_TRUE((T_world_camera.inverse() * p_world).isApprox(T_camera_object * p_object, 1e-12));
}

TEST(Transform, RotationDifferenceAndCheck) {
  EXPECT_NEAR(rotation_difference_deg(rz(30, Eigen::Vector3d::Zero()).linear(), Eigen::Matrix3d::Identity()), 30.0, 1e-9);
  EXPECT_NEAR(rotation_difference_deg(rz(-170, Eigen::Vector3d::Zero()).linear(), rz(170, Eigen::Vector3d::Zero()).linear()), 20.0, 1e-9);
  EXPECT_TRUE(is_rotation(rz(42, Eigen::Vector3d::Zero()).linear()));
  EXPECT_FALSE(is_rotation(2.0 * Eigen::Matrix3d::Identity()));
  EXPECT_FALSE(is_rotation(Eigen::Vector3d(1, 1, -1).asDiagonal().toDenseMatrix()));  // a reflection
}

// Rotations as files hold them: LM-O's ground truth is off orthonormal by up to 2e-3 (rounding to
// a few digits); a reflection, a scale or a shear is no rounding.
TEST(Transform, NearRotationsAreTakenAndOthersRefused) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const NearRotation exact = nearest_rotation(R);
  EXPECT_EQ(exact.kind, NearRotation::Kind::Rotation);
  EXPECT_LT(exact.deviation, 1e-12);
  EXPECT_TRUE(exact.R.isApprox(R, 1e-12));
  EXPECT_TRUE(exact.R == R);  // bit for bit: results read back and written again do not change

  // Rounded to three decimals, as an annotation tool might: a rotation with rounding in it.
  const Eigen::Matrix3d rounded = (R * 1000.0).array().round() / 1000.0;
  const NearRotation near = nearest_rotation(rounded);
  ASSERT_EQ(near.kind, NearRotation::Kind::Rotation);
  EXPECT_GT(near.deviation, kSilentRotationRounding);
  EXPECT_LT(near.deviation, 2e-3);
  EXPECT_TRUE(is_rotation(near.R, 1e-12));
  EXPECT_LT(rotation_difference_deg(near.R, R), 0.1);
  // A perturbation of 2e-3 off orthonormal (LM-O's worst): still taken.
  Eigen::Matrix3d off = R;
  off(0, 1) += 2e-3;
  EXPECT_EQ(nearest_rotation(off).kind, NearRotation::Kind::Rotation);

  Eigen::Matrix3d mirrored = R;
  mirrored.col(2) *= -1;
  EXPECT_EQ(nearest_rotation(mirrored).kind, NearRotation::Kind::Reflection);
  EXPECT_EQ(nearest_rotation(1.05 * R).kind, NearRotation::Kind::NotRigid);
  EXPECT_NEAR(nearest_rotation(1.05 * R).deviation, 0.05, 1e-12);
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(0, 1) = 0.1;
  EXPECT_EQ(nearest_rotation(R * shear).kind, NearRotation::Kind::NotRigid);
  EXPECT_EQ(nearest_rotation(Eigen::Matrix3d::Zero()).kind, NearRotation::Kind::NotRigid);
  Eigen::Matrix3d nan = R;
  nan(1, 1) = std::nan("");
  EXPECT_EQ(nearest_rotation(nan).kind, NearRotation::Kind::NotRigid);
}

TEST(Transform, CloudsMovePointsAndTurnNormals) {
  PointCloud c = PointCloud::from_points({{1, 0, 0}, {0, 0, 0}});
  c.normals = {{1, 0, 0}, {0, 0, 1}};
  const PointCloud out = transformed(c, rz(90, {0, 0, 5}));
  EXPECT_TRUE(out.points[0].isApprox(Eigen::Vector3f(0, 1, 5), 1e-6f));
  EXPECT_TRUE(out.normals[0].isApprox(Eigen::Vector3f(0, 1, 0), 1e-6f));  // no translation on normals
  EXPECT_TRUE(out.normals[1].isApprox(Eigen::Vector3f(0, 0, 1), 1e-6f));
}

}  // namespace
}  // namespace viewpose
