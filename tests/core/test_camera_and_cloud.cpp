#include <cmath>
#include <limits>

#include "test_support.hpp"
#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/mesh.hpp"

namespace viewpose {
namespace {

using test::expect_error;

TEST(Camera, ProjectInvertsUnproject) {
  const CameraIntrinsics K{570.3, 568.1, 320.7, 241.9, 640, 480};
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.1, -0.2, 0.8), Eigen::Vector3d(-0.5, 0.4, 2.5), Eigen::Vector3d(0, 0, 1)}) {
    const Eigen::Vector2d uv = K.project(p);
    EXPECT_TRUE(K.unproject(uv.x(), uv.y(), p.z()).isApprox(p, 1e-12));
  }
  // The principal point sees the optical axis.
  EXPECT_TRUE(K.project({0, 0, 3}).isApprox(Eigen::Vector2d(320.7, 241.9)));
}

TEST(Camera, ValidateRefusesImpossibleIntrinsics) {
  EXPECT_NO_THROW(CameraIntrinsics::kinect_v1().validate());
  expect_error([] { CameraIntrinsics{0, 525, 319.5, 239.5, 640, 480}.validate(); }, "focal");
  expect_error([] { CameraIntrinsics{525, NAN, 319.5, 239.5, 640, 480}.validate(); }, "focal");
  expect_error([] { CameraIntrinsics{525, 525, INFINITY, 239.5, 640, 480}.validate(); }, "principal");
  expect_error([] { CameraIntrinsics{525, 525, 319.5, 239.5, 0, 480}.validate(); }, "size");
  expect_error([] { CameraIntrinsics{525, 525, 319.5, 239.5, 640, 1 << 20}.validate(); }, "size");
}

TEST(DepthToCloud, UnprojectsEveryPixelAndKeepsHolesAsNaN) {
  const CameraIntrinsics K{500, 400, 3.5, 2.5, 8, 6};
  DepthImage d(8, 6);
  for (int v = 0; v < 6; ++v)
    for (int u = 0; u < 8; ++u) d.at(u, v) = 2.0f;
  d.at(1, 1) = 0.0f;                                     // no return
  d.at(2, 2) = std::numeric_limits<float>::quiet_NaN();  // no return
  d.at(7, 5) = -1.0f;                                    // impossible: treated as no return
  EXPECT_EQ(d.count_valid(), 45u);
  const PointCloud c = depth_to_cloud(d, K);
  ASSERT_EQ(c.width, 8);
  ASSERT_EQ(c.height, 6);
  ASSERT_TRUE(c.organized());
  EXPECT_EQ(c.count_finite(), 45u);
  EXPECT_FALSE(c.points[1 * 8 + 1].allFinite());
  EXPECT_FALSE(c.points[2 * 8 + 2].allFinite());
  // Pixel (7, 0): x = (7 - 3.5) * 2 / 500, y = (0 - 2.5) * 2 / 400.
  EXPECT_NEAR(c.points[7].x(), 0.014, 1e-7);
  EXPECT_NEAR(c.points[7].y(), -0.0125, 1e-7);
  EXPECT_FLOAT_EQ(c.points[7].z(), 2.0f);
}

TEST(DepthToCloud, RefusesSizeMismatch) {
  expect_error([] { depth_to_cloud(DepthImage(320, 240), CameraIntrinsics::kinect_v1()); }, "320x240");
}

TEST(PointCloud, BoundingBoxSkipsNonFinitePoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto c = PointCloud::from_points({{1, 2, 3}, {nan, 0, 0}, {-1, 5, 2}, {INFINITY, 1, 1}});
  const BoundingBox b = bounding_box(c.points);
  ASSERT_FALSE(b.empty);
  EXPECT_EQ(b.min, Eigen::Vector3f(-1, 2, 2));
  EXPECT_EQ(b.max, Eigen::Vector3f(1, 5, 3));
  EXPECT_EQ(c.count_finite(), 2u);
  EXPECT_TRUE(bounding_box(std::vector<Eigen::Vector3f>{{nan, nan, nan}}).empty);
}

TEST(PointCloud, CoreWidthIsTheNarrowestIntervalHoldingTheShareOnTheWidestAxis) {
  // 1001 points evenly along a 1 m segment, turned: the shortest interval holding 70 % is 0.7 m.
  const Eigen::Matrix3f R = Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i <= 1000; ++i) line.push_back(R * Eigen::Vector3f(0.001f * static_cast<float>(i), 0, 0) + Eigen::Vector3f(5, -2, 1));
  EXPECT_NEAR(core_width(line, 0.7), 0.7, 0.002);
  EXPECT_NEAR(core_width(line, 1.0), 1.0, 1e-4);
  // A dense 10 cm square with 25 % of the points far off in a line: the outliers widen the box
  // to a metre, not the core (70 % of the points fit in the square).
  std::vector<Eigen::Vector3f> patch;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) patch.push_back(R * Eigen::Vector3f(0.1f * i / 29.0f, 0.1f * j / 29.0f, 0));
  for (int i = 0; i < 300; ++i) patch.push_back(R * Eigen::Vector3f(0.2f + 0.003f * static_cast<float>(i), 0.05f, 0));
  EXPECT_GT(bounding_box(patch).diagonal(), 1.0f);
  EXPECT_LE(core_width(patch, 0.7), 0.1 + 1e-5);
  EXPECT_GT(core_width(patch, 0.95), 0.3);
  // Non-finite points are skipped; fewer than two points have no width.
  patch.push_back(Eigen::Vector3f::Constant(NAN));
  EXPECT_LE(core_width(patch, 0.7), 0.1 + 1e-5);
  EXPECT_EQ(core_width(std::vector<Eigen::Vector3f>{{1, 2, 3}}, 0.7), 0.0);
  EXPECT_EQ(core_width({}, 0.7), 0.0);
}

TEST(PointCloud, CheckConsistentCatchesMismatchedAttributes) {
  auto c = test::sample_cloud(4, 3, true, true, true);
  EXPECT_NO_THROW(c.check_consistent());
  c.normals.pop_back();
  expect_error([&] { c.check_consistent(); }, "normals");
  auto d = test::sample_cloud(4, 3, false, false, false);
  d.width = 5;
  expect_error([&] { d.check_consistent(); }, "5x3");
}

TEST(Mesh, BoxHasAnalyticAreaAndOutwardFaces) {
  const TriangleMesh box = make_box_mesh({0.2f, 0.3f, 0.5f});
  ASSERT_EQ(box.triangles.size(), 12u);
  EXPECT_NEAR(box.surface_area(), 2 * (0.2 * 0.3 + 0.3 * 0.5 + 0.2 * 0.5), 1e-6);
  for (const auto& t : box.triangles) {
    const Eigen::Vector3f a = box.vertices[t[0]], b = box.vertices[t[1]], c = box.vertices[t[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    EXPECT_GT(n.dot((a + b + c) / 3.0f), 0.0f) << "a face points inwards";
  }
  const BoundingBox bb = bounding_box(box);
  EXPECT_TRUE(bb.size().isApprox(Eigen::Vector3f(0.2f, 0.3f, 0.5f)));
}

TEST(Mesh, CheckConsistentCatchesBadIndices) {
  TriangleMesh m = make_box_mesh({1, 1, 1});
  m.triangles.push_back({0, 1, 8});
  expect_error([&] { m.check_consistent(); }, "vertex 8 of 8");
}

}  // namespace
}  // namespace viewpose
