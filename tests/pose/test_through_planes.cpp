#include "viewpose/pose/through_planes.hpp"

#include <gtest/gtest.h>

namespace viewpose {
namespace {

// A Kinect's intrinsics; the plane z = 1 m facing the camera, seen where `seen_u` says (pixel
// columns), its inliers every second pixel.
CameraIntrinsics kinect() { return CameraIntrinsics{525, 525, 319.5, 239.5, 640, 480}; }

struct SeenPlane {
  PointCloud frame;
  std::vector<Plane> planes;
  SeenPlane(int u_from, int u_to) {
    const CameraIntrinsics K = kinect();
    Plane plane;
    plane.coefficients = Eigen::Vector4f(0, 0, -1, 1);  // -z + 1 = 0; n faces the camera at the origin
    for (int v = 0; v < K.height; v += 2) {
      for (int u = u_from; u < u_to; u += 2) {
        plane.inliers.push_back(static_cast<std::uint32_t>(frame.points.size()));
        frame.points.push_back(K.unproject(u, v, 1.0).cast<float>());
      }
    }
    frame.width = static_cast<int>(frame.points.size());
    planes.push_back(std::move(plane));
  }
};

// A rod along the object's z, 0 to 0.2 m, a point every millimetre (201).
std::vector<Eigen::Vector3f> rod() {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i <= 200; ++i) points.emplace_back(0.0f, 0.0f, 0.001f * static_cast<float>(i));
  return points;
}

Transform at(double x, double z) { return make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, 0.0, z)); }

TEST(ThroughPlanes, TheShareOfAModelThroughASeenPlaneIsWhatLiesPastItsMargin) {
  const SeenPlane table(0, 640);
  const ObservedPlanes observed(table.planes, table.frame, kinect());
  // The rod from 0.9 to 1.1 m along the ray: past 1.01 m (the margin) are 90 of its 201 points.
  EXPECT_NEAR(observed.share_inside(rod(), at(0, 0.9), 0.01f), 90.0 / 201.0, 1.0 / 201.0);
  // Standing in front of it, touching it within the margin: nothing inside.
  EXPECT_EQ(observed.share_inside(rod(), at(0, 0.805), 0.01f), 0.0);
  // Wholly behind it (under a table or a board, seen past its edge): not in it.
  EXPECT_EQ(observed.share_inside(rod(), at(0, 1.05), 0.01f), 0.0);
  // A wider margin takes fewer points.
  EXPECT_NEAR(observed.share_inside(rod(), at(0, 0.9), 0.05f), 50.0 / 201.0, 1.0 / 201.0);
}

TEST(ThroughPlanes, OnlyWhereThePlaneWasSeenDoesItCount) {
  // The plane seen on the image's left half only (x < 0 at 1 m): the rod through it on the right
  // passes where nothing says the plane is (past a table's edge).
  const SeenPlane left_half(0, 320);
  const ObservedPlanes observed(left_half.planes, left_half.frame, kinect());
  EXPECT_GT(observed.share_inside(rod(), at(-0.1, 0.9), 0.01f), 0.4);
  EXPECT_EQ(observed.share_inside(rod(), at(0.1, 0.9), 0.01f), 0.0);
}

TEST(ThroughPlanes, NoPlanesOrNoPointsGiveZero) {
  const SeenPlane table(0, 640);
  EXPECT_EQ(ObservedPlanes({}, table.frame, kinect()).share_inside(rod(), at(0, 0.9), 0.01f), 0.0);
  const ObservedPlanes observed(table.planes, table.frame, kinect());
  EXPECT_EQ(observed.share_inside({}, at(0, 0.9), 0.01f), 0.0);
  // Inliers that index past the frame, and intrinsics without a size, are ignored, not read.
  std::vector<Plane> bad = table.planes;
  bad[0].inliers.push_back(static_cast<std::uint32_t>(table.frame.points.size() + 5));
  EXPECT_NEAR(ObservedPlanes(bad, table.frame, kinect()).share_inside(rod(), at(0, 0.9), 0.01f), 90.0 / 201.0, 1.0 / 201.0);
  CameraIntrinsics no_size = kinect();
  no_size.width = no_size.height = 0;
  EXPECT_EQ(ObservedPlanes(table.planes, table.frame, no_size).share_inside(rod(), at(0, 0.9), 0.01f), 0.0);
}

}  // namespace
}  // namespace viewpose
