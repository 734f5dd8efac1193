// Verification against known answers: a model drawn into a frame at a known pose is checked at
// that pose, and at poses moved off it, where the frame contradicts the model.
#include <cmath>
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {
namespace {

// The jug alone in front of a wall 1.6 m away, drawn without noise; the cluster is the jug's points.
struct Scene {
  CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  TriangleMesh jug = make_jug();
  TriangleMesh wall = test::square(4.0f);
  Transform T_camera_jug =
      make_transform(Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix(), {0.03, 0.02, 0.9});
  DepthImage depth;
  std::vector<Eigen::Vector3f> cluster;

  Scene() {
    const MeshInstance both[] = {{&jug, T_camera_jug}, {&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.6})}};
    const RenderedFrame f = render(both, K, {});
    depth = f.depth;
    const PointCloud cloud = depth_to_cloud(depth, K);
    for (std::size_t i = 0; i < cloud.points.size(); ++i)
      if (f.instance[i] == 0) cluster.push_back(cloud.points[i]);
  }
  Verification check(const Transform& T, const VerifyOptions& o = {}) const {
    const VerifyModel model{&jug, {}, 0.003f, closed_mesh_winding(jug)};
    return verify_pose(model, T, depth, K, cluster, o);
  }
  Transform moved(double dx, double dy, double dz) const {
    return make_transform(Eigen::Matrix3d::Identity(), {dx, dy, dz}) * T_camera_jug;
  }
};

TEST(Verify, TheTruePoseIsAcceptedWithEverythingExplained) {
  const Scene s;
  ASSERT_GT(s.cluster.size(), 5000u);
  const Verification v = s.check(s.T_camera_jug);
  EXPECT_TRUE(v.accepted);
  EXPECT_EQ(v.pixel_step, 1);
  EXPECT_GT(v.inlier_fraction, 0.99);
  EXPECT_LT(v.conflict_fraction, 0.01);
  EXPECT_GT(v.cluster_explained, 0.99);
  EXPECT_GT(v.visible_fraction, 0.95);
  EXPECT_GT(v.model_support, 0.99);
  EXPECT_EQ(v.accepted, passes(v, VerifyOptions{}));
}

TEST(Verify, APoseTheCameraSeesThroughOrBehindItsOwnSurfaceIsRefused) {
  const Scene s;
  // 3 cm nearer the camera: the wall and the jug's own surface are seen behind the model (free space).
  const Verification nearer = s.check(s.moved(0, 0, -0.03));
  EXPECT_FALSE(nearer.accepted);
  EXPECT_GT(nearer.conflict_fraction, 0.5);
  // 3 cm farther: the model sinks behind the jug's own surface, which cannot hide the jug itself.
  const Verification farther = s.check(s.moved(0, 0, 0.03));
  EXPECT_FALSE(farther.accepted);
  EXPECT_GT(farther.hidden_by_cluster, farther.inliers);
  // 8 cm to the side: much of the model lies over the wall.
  const Verification aside = s.check(s.moved(0.08, 0, 0));
  EXPECT_FALSE(aside.accepted);
  EXPECT_LT(aside.cluster_explained, 0.7);
  // What the options say is what `accepted` says.
  for (const Verification& v : {nearer, farther, aside}) EXPECT_EQ(v.accepted, passes(v, VerifyOptions{}));
}

TEST(Verify, JudgingEveryFewPixelsEstimatesTheSameFractionsAndCounts) {
  const Scene s;
  VerifyOptions sampled;
  sampled.max_judged_pixels = 6000;  // the jug's window is about 20,000 pixels: every other pixel
  for (const Transform& T : {s.T_camera_jug, s.moved(0, 0, -0.02), s.moved(0.03, 0, 0)}) {
    const Verification all = s.check(T), some = s.check(T, sampled);
    EXPECT_EQ(some.pixel_step, 2);
    EXPECT_NEAR(some.inlier_fraction, all.inlier_fraction, 0.05);
    EXPECT_NEAR(some.conflict_fraction, all.conflict_fraction, 0.05);
    EXPECT_NEAR(some.cluster_explained, all.cluster_explained, 0.05);
    EXPECT_NEAR(some.visible_fraction, all.visible_fraction, 0.05);
    // Counts in the camera's pixels either way.
    const double judged_all = static_cast<double>(all.inliers + all.conflicts + all.hidden_by_cluster);
    const double judged_some = static_cast<double>(some.inliers + some.conflicts + some.hidden_by_cluster);
    EXPECT_NEAR(judged_some / judged_all, 1.0, 0.1);
    EXPECT_EQ(some.accepted, all.accepted);
  }
  // Coarser still (every 4th pixel): a pose off to the side stays unexplained.
  sampled.max_judged_pixels = 1500;
  const Verification all = s.check(s.moved(0.03, 0, 0)), coarse = s.check(s.moved(0.03, 0, 0), sampled);
  EXPECT_GE(coarse.pixel_step, 3);
  EXPECT_NEAR(coarse.cluster_explained, all.cluster_explained, 0.1);
  EXPECT_FALSE(coarse.accepted);
}

}  // namespace
}  // namespace viewpose
