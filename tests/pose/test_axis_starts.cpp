// Starting poses from principal axes, against boxes placed by construction: a book seen face-on
// and edge-on, whose true pose must be among the starts.
#include <cmath>
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/pose/axis_starts.hpp"

namespace viewpose {
namespace {

// A 20 x 15 x 2 cm book (x its length, y its height, z its thickness), its points every 2 mm on
// each face, in a frame whose origin is off its centre (the starts must carry the centre, not the
// origin); `facing`: only the faces turned toward a camera at the origin once at T_camera_object.
const Eigen::Vector3d kSize(0.20, 0.15, 0.02), kCentre(0.03, -0.01, 0.05);

std::vector<Eigen::Vector3f> book(const Transform* T_camera_object = nullptr) {
  std::vector<Eigen::Vector3f> points;
  const double step = 0.002;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (const double side : {-0.5, 0.5}) {
      const Eigen::Vector3d normal = side * 2.0 * Eigen::Vector3d::Unit(axis);
      const Eigen::Vector3d face_centre = kCentre + side * kSize[axis] * Eigen::Vector3d::Unit(axis);
      if (T_camera_object && (T_camera_object->linear() * normal).dot(*T_camera_object * face_centre) >= 0) continue;
      for (double a = -kSize[u] / 2; a <= kSize[u] / 2 + 1e-9; a += step) {
        for (double b = -kSize[v] / 2; b <= kSize[v] / 2 + 1e-9; b += step) {
          Eigen::Vector3d p = face_centre;
          p[u] += a, p[v] += b;
          points.push_back((T_camera_object ? *T_camera_object * p : p).cast<float>());
        }
      }
    }
  }
  return points;
}

// The start nearest `truth` in rotation: its rotation and translation errors.
struct Nearest {
  double degrees = 1e9, metres = 1e9;
};
Nearest nearest_start(const std::vector<Transform>& starts, const Transform& truth) {
  Nearest n;
  for (const Transform& T : starts) {
    const double deg = rotation_difference_deg(T.linear(), truth.linear());
    if (deg < n.degrees) n = {deg, (T.translation() - truth.translation()).norm()};
  }
  return n;
}

// Turned about the camera's y by `yaw` and tilted down by `pitch` (degrees), its centre 1 m ahead
// (on the optical axis: seen edge-on, neither cover then faces the camera).
Transform pose(double yaw, double pitch) {
  const double rad = std::acos(-1.0) / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(pitch * rad, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(yaw * rad, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  return make_transform(R, Eigen::Vector3d(0.0, 0.0, 1.0) - R * kCentre);
}

TEST(AxisStarts, ABooksPrincipalAxesAreItsEdgesWidestFirst) {
  const std::vector<Eigen::Vector3f> points = book();
  const PrincipalAxes a = principal_axes(points);
  EXPECT_NEAR((a.mean - kCentre).norm(), 0.0, 1e-4);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(std::abs(a.axes.col(k).dot(Eigen::Vector3d::Unit(k))), 1.0, 1e-6) << "axis " << k;
    EXPECT_NEAR(a.extent[k], kSize[k], 1e-6) << "axis " << k;
  }
  EXPECT_NEAR(a.axes.determinant(), 1.0, 1e-9);
  // Fewer than two finite points: nothing to measure, and no NaN.
  const std::vector<Eigen::Vector3f> one = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f::Constant(NAN)};
  EXPECT_EQ(principal_axes(one).extent, Eigen::Vector3d::Zero());
  EXPECT_TRUE(principal_axes(one).axes.allFinite());
}

TEST(AxisStarts, TheStripABookShowsEdgeOnIsAsWideAsTheBookIsThickAndAcrossItsThinAxis) {
  // Its 2 x 15 cm edge square to the ray: a strip 2 cm wide and 15 long, whichever way it is rolled.
  for (const double roll : {0.0, 0.7, 1.9}) {
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(std::acos(-1.0) / 2, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    const Transform T = make_transform(R, Eigen::Vector3d(0.0, 0.0, 1.2) - R * kCentre);
    const StripSize s = strip_size(book(&T), 1.0);
    EXPECT_NEAR(s.width_m, 0.02, 0.002) << "roll " << roll;
    EXPECT_NEAR(s.length_m, 0.15, 0.005) << "roll " << roll;
    EXPECT_NEAR(std::abs(s.across.dot(R.col(2))), 1.0, 1e-3) << "roll " << roll;
  }
  // Face-on it is no strip: 15 wide, 20 long.
  const Transform face_on = make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 1.0) - kCentre);
  const StripSize s = strip_size(book(&face_on), 1.0);
  EXPECT_NEAR(s.width_m, 0.15, 0.005);
  EXPECT_NEAR(s.length_m, 0.20, 0.005);
  EXPECT_EQ(strip_size({}, 0.9).width_m, 0.0);
}

TEST(AxisStarts, EdgeOnTheTruePoseIsWithinHalfATurnStepOfAStart) {
  const std::vector<Eigen::Vector3f> model = book();
  const PrincipalAxes object = principal_axes(model);
  // Level, the spine alone; from 18 degrees above (the thesis's camera), the spine and a strip of
  // the top, foreshortened; turned in its plane, a corner toward the camera.
  for (const double pitch : {0.0, 18.0, 40.0}) {
    for (const double yaw : {90.0, -90.0}) {
      const Transform truth = pose(yaw, pitch);
      const std::vector<Eigen::Vector3f> strip = book(&truth);
      const StripSize s = strip_size(strip, 0.95);
      EXPECT_NEAR(s.width_m, 0.02, 0.004) << pitch << " " << yaw;
      const std::vector<Transform> starts = edge_on_poses(object, model, strip, s.across, 12);
      ASSERT_EQ(starts.size(), 24u);
      for (const Transform& T : starts) EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-9);
      // Every turn of 30 degrees: the true one within 15 (and the thin axis found exactly, nearly).
      const Nearest n = nearest_start(starts, truth);
      EXPECT_LT(n.degrees, 16.0) << pitch << " " << yaw;
      // The near sides put together: a turn 15 degrees off moves the book's near corner by up to
      // its half-diagonal times the turn (about 4 cm), within ICP's reach on a 20 cm book.
      EXPECT_LT(n.metres, 0.045) << pitch << " " << yaw;
      // In fine steps the truth itself, nearly: the axis and the near side are exact.
      const Nearest fine = nearest_start(edge_on_poses(object, model, strip, s.across, 360), truth);
      EXPECT_LT(fine.degrees, 0.6) << pitch << " " << yaw;
      EXPECT_LT(fine.metres, 0.004) << pitch << " " << yaw;
    }
  }
  // Nothing to place, no direction, one along the ray (no edge seen) or no turns: no starts.
  const Transform level = pose(90, 0);
  const std::vector<Eigen::Vector3f> spine = book(&level);
  EXPECT_TRUE(edge_on_poses(object, model, {}, Eigen::Vector3d::UnitX(), 12).empty());
  EXPECT_TRUE(edge_on_poses(object, model, spine, Eigen::Vector3d::Zero(), 12).empty());
  Eigen::Vector3d spine_mean = Eigen::Vector3d::Zero();
  for (const auto& p : spine) spine_mean += p.cast<double>() / static_cast<double>(spine.size());
  EXPECT_TRUE(edge_on_poses(object, model, spine, spine_mean, 12).empty()) << "along the ray";
  EXPECT_TRUE(edge_on_poses(object, model, spine, Eigen::Vector3d::UnitX(), 0).empty());
  EXPECT_EQ(edge_on_poses(object, model, spine, Eigen::Vector3d::UnitX(), 1).size(), 2u);
}

}  // namespace
}  // namespace viewpose
