#include "viewpose/pose/through_planes.hpp"

#include <gtest/gtest.h>

namespace viewpose {
namespace {

// A Kinect's intrinsics; the plane z = 1 m facing the camera, measured in the pixel columns
// [u_from, u_to), nothing measured elsewhere.
CameraIntrinsics kinect() { return CameraIntrinsics{525, 525, 319.5, 239.5, 640, 480}; }

const std::vector<Eigen::Vector4f> kPlane = {Eigen::Vector4f(0, 0, -1, 1)};  // -z + 1 = 0; n faces the camera at the origin

DepthImage plane_seen(int u_from, int u_to) {
  DepthImage depth(640, 480);
  for (int v = 0; v < depth.height; ++v)
    for (int u = u_from; u < u_to; ++u) depth.at(u, v) = 1.0f;
  return depth;
}

// A rod along the object's z, 0 to 0.2 m, a point every millimetre (201).
std::vector<Eigen::Vector3f> rod() {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i <= 200; ++i) points.emplace_back(0.0f, 0.0f, 0.001f * static_cast<float>(i));
  return points;
}

Transform at(double x, double z) { return make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, 0.0, z)); }

double share(const DepthImage& depth, const Transform& T, float margin_m, std::span<const Eigen::Vector4f> planes = kPlane) {
  return share_inside_planes(planes, depth, kinect(), rod(), T, margin_m);
}

TEST(ThroughPlanes, TheShareOfAModelThroughASeenPlaneIsWhatLiesPastItsMargin) {
  const DepthImage table = plane_seen(0, 640);
  // The rod from 0.9 to 1.1 m along the ray: past 1.01 m (the margin) are 90 of its 201 points.
  EXPECT_NEAR(share(table, at(0, 0.9), 0.01f), 90.0 / 201.0, 1.0 / 201.0);
  // Standing in front of it, touching it within the margin: nothing inside.
  EXPECT_EQ(share(table, at(0, 0.805), 0.01f), 0.0);
  // Wholly behind it (under a table or a board, seen past its edge): not in it.
  EXPECT_EQ(share(table, at(0, 1.05), 0.01f), 0.0);
  // A wider margin takes fewer points.
  EXPECT_NEAR(share(table, at(0, 0.9), 0.05f), 50.0 / 201.0, 1.0 / 201.0);
}

TEST(ThroughPlanes, OnlyWhereThePlaneWasSeenDoesItCount) {
  // The plane measured on the image's left half only (x < 0 at 1 m): the rod through it on the
  // right passes where nothing says the plane is (past a table's edge).
  const DepthImage left_half = plane_seen(0, 320);
  EXPECT_GT(share(left_half, at(-0.1, 0.9), 0.01f), 0.4);
  EXPECT_EQ(share(left_half, at(0.1, 0.9), 0.01f), 0.0);
  // Something else measured there (a surface 20 cm nearer than the plane): not the plane seen.
  DepthImage nearer = plane_seen(0, 640);
  for (float& z : nearer.depth_m) z = 0.8f;
  EXPECT_EQ(share(nearer, at(0, 0.9), 0.01f), 0.0);
}

TEST(ThroughPlanes, NoPlanesNoPointsOrAnotherImageSizeGiveZero) {
  const DepthImage table = plane_seen(0, 640);
  EXPECT_EQ(share(table, at(0, 0.9), 0.01f, {}), 0.0);
  EXPECT_EQ(share_inside_planes(kPlane, table, kinect(), {}, at(0, 0.9), 0.01f), 0.0);
  CameraIntrinsics other = kinect();
  other.width = 320;
  EXPECT_EQ(share_inside_planes(kPlane, table, other, rod(), at(0, 0.9), 0.01f), 0.0);
  // Of two planes, the larger share: the second one, seen nowhere, changes nothing.
  const std::vector<Eigen::Vector4f> two = {kPlane[0], Eigen::Vector4f(0, 0, -1, 1.05f)};
  EXPECT_NEAR(share(table, at(0, 0.9), 0.01f, two), 90.0 / 201.0, 1.0 / 201.0);
}

}  // namespace
}  // namespace viewpose
