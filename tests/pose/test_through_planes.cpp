#include "viewpose/pose/through_planes.hpp"

#include <gtest/gtest.h>

#include "viewpose/segment/planes.hpp"

namespace viewpose {
namespace {

// A Kinect's intrinsics; a plane at z = 1 m facing the camera (-z + 1 = 0), measured in some
// pixels and nowhere else. The planes tested are the ones the segmentation removes from such an
// image, with the patches it saw them in.
CameraIntrinsics kinect() { return CameraIntrinsics{525, 525, 319.5, 239.5, 640, 480}; }

// The plane z = depth_m measured in the columns [u_from, u_to) of the rows [v_from, v_to).
void see_plane(DepthImage& depth, int u_from, int u_to, int v_from = 0, int v_to = 480, float depth_m = 1.0f) {
  for (int v = v_from; v < v_to; ++v)
    for (int u = u_from; u < u_to; ++u) depth.at(u, v) = depth_m;
}

DepthImage plane_seen(int u_from, int u_to) {
  DepthImage depth(640, 480);
  see_plane(depth, u_from, u_to);
  return depth;
}

std::vector<Plane> planes_in(const DepthImage& depth) { return remove_large_planes(depth_to_cloud(depth, kinect())).removed; }

// A rod along the object's z, 0 to 0.2 m, a point every millimetre (201).
std::vector<Eigen::Vector3f> rod() {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i <= 200; ++i) points.emplace_back(0.0f, 0.0f, 0.001f * static_cast<float>(i));
  return points;
}

Transform at(double x, double z) { return make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, 0.0, z)); }

// The rod's share inside the planes removed from `depth`, judged on `depth`.
double share(const DepthImage& depth, const Transform& T, float margin_m) {
  return share_inside_planes(planes_in(depth), depth, kinect(), rod(), T, margin_m);
}

TEST(ThroughPlanes, TheShareOfAModelThroughASeenPlaneIsWhatLiesPastItsMargin) {
  const DepthImage table = plane_seen(0, 640);
  const std::vector<Plane> planes = planes_in(table);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_TRUE(planes[0].coefficients.isApprox(Eigen::Vector4f(0, 0, -1, 1), 1e-4f));
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
  // Something else measured where the plane was seen (a surface 20 cm nearer): not the plane seen.
  DepthImage nearer = plane_seen(0, 640);
  for (float& z : nearer.depth_m) z = 0.8f;
  EXPECT_EQ(share_inside_planes(planes_in(plane_seen(0, 640)), nearer, kinect(), rod(), at(0, 0.9), 0.01f), 0.0);
}

TEST(ThroughPlanes, TheSameHeightMeasuredOffThePlanesPatchIsNotThePlane) {
  // The plane seen on the image's left half, and at the rod's foot on the right (x = 0.1 m, pixel
  // 372) a small surface at the plane's height, apart from the patch: an object's own front where
  // it crosses the height of a box's top beside it (a riser). The depth there lies on the plane,
  // but the plane is not there.
  DepthImage riser = plane_seen(0, 320);
  see_plane(riser, 360, 385, 225, 255);  // 4.8 x 5.7 cm: less than the 0.01 m2 a patch needs
  ASSERT_EQ(planes_in(riser).size(), 1u);
  EXPECT_EQ(share(riser, at(0.1, 0.9), 0.01f), 0.0);
  // A second large patch of the same plane there (another table at the same height) is the plane.
  DepthImage two_tables = plane_seen(0, 320);
  see_plane(two_tables, 360, 640);
  EXPECT_GT(share(two_tables, at(0.1, 0.9), 0.01f), 0.4);
}

TEST(ThroughPlanes, NoPlanesNoPatchNoPointsOrAnotherImageSizeGiveZero) {
  const DepthImage table = plane_seen(0, 640);
  const std::vector<Plane> planes = planes_in(table);
  EXPECT_EQ(share_inside_planes({}, table, kinect(), rod(), at(0, 0.9), 0.01f), 0.0);
  EXPECT_EQ(share_inside_planes(planes, table, kinect(), {}, at(0, 0.9), 0.01f), 0.0);
  CameraIntrinsics other = kinect();
  other.width = 320;
  EXPECT_EQ(share_inside_planes(planes, table, other, rod(), at(0, 0.9), 0.01f), 0.0);
  // A plane with no patch (fit_plane's) was seen nowhere.
  std::vector<Plane> no_patch = planes;
  no_patch[0].patch = {};
  EXPECT_EQ(share_inside_planes(no_patch, table, kinect(), rod(), at(0, 0.9), 0.01f), 0.0);
  // Of two planes, the larger share: the second one, 5 cm behind the depth measured, changes nothing.
  std::vector<Plane> two = planes;
  two.push_back(planes[0]);
  two[1].coefficients = Eigen::Vector4f(0, 0, -1, 1.05f);
  EXPECT_NEAR(share_inside_planes(two, table, kinect(), rod(), at(0, 0.9), 0.01f), 90.0 / 201.0, 1.0 / 201.0);
}

TEST(ThroughPlanes, HowDeepAModelSinksIsTheDepthItsShareOfPointsReaches) {
  const DepthImage table = plane_seen(0, 640);
  const std::vector<Plane> planes = planes_in(table);
  ASSERT_EQ(planes.size(), 1u);
  const auto sink = [&](double z, double share) { return sink_into_planes(planes, table, kinect(), rod(), at(0, z), 0.01f, share); };
  // The rod from 0.815 to 1.015 m: 15 mm into the plane at 1 m, its last 16 points past it.
  PlaneSink s = sink(0.815, 1.0 / 201.0);
  EXPECT_EQ(s.plane, 0);
  EXPECT_NEAR(s.depth_m, 0.015f, 1e-4f);
  // The depth that 5 of its points reach: 4 mm less.
  EXPECT_NEAR(sink(0.815, 5.0 / 201.0).depth_m, 0.011f, 1e-4f);
  // More points than have sunk: none reach any depth.
  EXPECT_EQ(sink(0.815, 20.0 / 201.0).plane, -1);
  EXPECT_EQ(sink(0.815, 20.0 / 201.0).depth_m, 0.0f);
  // Resting on it, or wholly behind it (under a board seen past its edge): nothing sinks.
  EXPECT_EQ(sink(0.8, 1.0 / 201.0).plane, -1);
  EXPECT_EQ(sink(1.05, 1.0 / 201.0).plane, -1);
  // A share of 0 asks for nothing.
  EXPECT_EQ(sink(0.815, 0.0).plane, -1);
  // Where the plane was not seen, it does not count (past a table's edge).
  const DepthImage half = plane_seen(0, 320);
  EXPECT_EQ(sink_into_planes(planes_in(half), half, kinect(), rod(), at(0.1, 0.815), 0.01f, 1.0 / 201.0).plane, -1);
}

}  // namespace
}  // namespace viewpose
