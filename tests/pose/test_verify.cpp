// Verification against known answers: a model drawn into a frame at a known pose is checked at
// that pose, and at poses moved off it, where the frame contradicts the model.
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"
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
    const VerifyModel model{&jug, {}, 0.003f, closed_mesh_winding(jug), {}};
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

// 4000 points spread evenly over the jug's surface (by area, seeded), with their faces' normals: as
// a database's model points are.
void jug_surface(const TriangleMesh& jug, std::vector<Eigen::Vector3f>& points, std::vector<Eigen::Vector3f>& normals) {
  std::vector<double> cumulative;
  double total = 0;
  for (const auto& t : jug.triangles) {
    total += 0.5 * static_cast<double>((jug.vertices[t[1]] - jug.vertices[t[0]]).cross(jug.vertices[t[2]] - jug.vertices[t[0]]).norm());
    cumulative.push_back(total);
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 4000; ++i) {
    const auto k = static_cast<std::size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) - cumulative.begin());
    const auto& t = jug.triangles[std::min(k, jug.triangles.size() - 1)];
    const Eigen::Vector3f a = jug.vertices[t[0]], b = jug.vertices[t[1]], c = jug.vertices[t[2]];
    float r1 = static_cast<float>(u(rng)), r2 = static_cast<float>(u(rng));
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const Eigen::Vector3f n = (b - a).cross(c - a);
    if (!(n.norm() > 0)) continue;
    points.push_back(a + r1 * (b - a) + r2 * (c - a));
    normals.push_back(n.normalized());
  }
}

TEST(Verify, TheQuickTestSeesThroughAMisplacedModelAndNotThroughTheRightOne) {
  const Scene s;
  std::vector<Eigen::Vector3f> points, normals;
  jug_surface(s.jug, points, normals);
  ASSERT_GT(points.size(), 500u);
  const VerifyOptions o;
  const auto quick = [&](const Transform& T, std::span<const Eigen::Vector3f> n) {
    return seen_through(points, n, T, s.depth, s.K, o, 2000);
  };
  // At the true pose: the far side and the inside are hidden by the near side (not judged), the
  // near side judged and hardly ever seen through; without normals the outline's points add some.
  const SeenThrough right = quick(s.T_camera_jug, normals);
  EXPECT_GT(right.judged, 100u);
  EXPECT_LT(right.fraction(), 0.03);
  EXPECT_LT(quick(s.T_camera_jug, {}).fraction(), 0.15);
  EXPECT_LE(right.judged, 2000u);
  // 20 cm to the side, in front of the bare wall: the camera sees the wall 0.7 m behind the model.
  const SeenThrough aside = quick(s.moved(0.2, 0, 0), normals);
  EXPECT_GT(aside.judged, 100u);
  EXPECT_GT(aside.fraction(), 0.95);
  // Behind the wall: everything measured lies in front of the model, nothing is judged.
  EXPECT_EQ(quick(s.moved(0, 0, 1.2), normals).judged, 0u);
  // Out of the image, or no points: nothing judged.
  EXPECT_EQ(quick(s.moved(5.0, 0, 0), normals).judged, 0u);
  EXPECT_EQ(seen_through({}, {}, s.T_camera_jug, s.depth, s.K, o, 512).judged, 0u);
}

TEST(Verify, APoseRefusedQuicklyIsNeverOneTheFullTestAccepts) {
  const Scene s;
  std::vector<Eigen::Vector3f> points, normals;
  jug_surface(s.jug, points, normals);
  const VerifyModel model{&s.jug, points, 0.003f, closed_mesh_winding(s.jug), normals};
  VerifyOptions full_only;
  full_only.quick_max_seen_through = 1;
  // The true pose passes both ways, and the quick test leaves it to the full one.
  const Verification right = verify_pose(model, s.T_camera_jug, s.depth, s.K, s.cluster);
  EXPECT_TRUE(right.accepted);
  EXPECT_FALSE(right.refused_quickly);
  EXPECT_FALSE(seen_through_quickly(model, s.T_camera_jug, s.depth, s.K, VerifyOptions{}));
  // Misplaced by 2 to 20 cm across the line of sight: whenever the quick test refuses, the full
  // test refuses too, and the far-off poses are refused quickly.
  int refused_quickly = 0;
  for (const double dx : {0.02, 0.05, 0.1, 0.2}) {
    SCOPED_TRACE(dx);
    const Verification quick = verify_pose(model, s.moved(dx, 0, 0), s.depth, s.K, s.cluster);
    const Verification full = verify_pose(model, s.moved(dx, 0, 0), s.depth, s.K, s.cluster, full_only);
    EXPECT_FALSE(full.refused_quickly);
    // The quick test alone (what the recognizer's screen asks) gives the same verdict and share.
    const std::optional<double> alone = seen_through_quickly(model, s.moved(dx, 0, 0), s.depth, s.K, VerifyOptions{});
    EXPECT_EQ(alone.has_value(), quick.refused_quickly);
    const SeenThrough share = seen_through(points, normals, s.moved(dx, 0, 0), s.depth, s.K, VerifyOptions{}, VerifyOptions{}.quick_points);
    EXPECT_EQ(alone.has_value(), share.judged >= VerifyOptions{}.quick_min_judged && share.fraction() > VerifyOptions{}.quick_max_seen_through);
    if (alone) {
      EXPECT_EQ(*alone, quick.conflict_fraction);
    }
    EXPECT_FALSE(seen_through_quickly(model, s.moved(dx, 0, 0), s.depth, s.K, full_only));
    EXPECT_FALSE(quick.accepted);
    EXPECT_FALSE(full.accepted);
    if (quick.refused_quickly) {
      ++refused_quickly;
      EXPECT_GT(quick.conflict_fraction, 0.5);
      EXPECT_EQ(quick.inliers, 0u) << "nothing else is filled in";
      EXPECT_GT(full.conflict_fraction, 0.05);
    }
  }
  EXPECT_GE(refused_quickly, 2);
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

// A box's front face flush with a wall: what a box seen face-on and a patch cut out of the wall look
// like inside the outline. The wall is the frame; the cluster, the wall's points the face covers.
struct FaceOnWall {
  CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  TriangleMesh box = make_box_mesh({0.20f, 0.15f, 0.10f});
  TriangleMesh wall = test::square(6.0f);
  double wall_z;
  Transform T_camera_box;  // the face at z = -0.05 in the box's frame lies on the wall
  DepthImage depth;
  std::vector<Eigen::Vector3f> cluster;
  // `gap`: how far the wall stands behind the box's face (0: the face is a patch of the wall).
  FaceOnWall(double z, const SensorModel& sensor, double gap = 0) : wall_z(z + gap) {
    T_camera_box = make_transform(Eigen::Matrix3d::Identity(), {0.02, -0.01, z + 0.05});
    const MeshInstance scene[] = {{&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, z + gap})}, {&box, T_camera_box}};
    RenderOptions with_normals;
    with_normals.normals = true;
    depth = simulate_sensor(render(std::span(scene, gap > 0 ? 2 : 1), K, with_normals), K, sensor, 5);
    const MeshInstance b{&box, T_camera_box};
    const RenderedFrame face = render(std::span(&b, 1), K);
    const PointCloud cloud = depth_to_cloud(depth, K);
    for (std::size_t i = 0; i < cloud.points.size(); ++i)
      if (std::isfinite(face.depth.depth_m[i]) && cloud.points[i].allFinite()) cluster.push_back(cloud.points[i]);
  }
  Verification check(const VerifyOptions& o = {}) const {
    const VerifyModel model{&box, {}, 0.003f, closed_mesh_winding(box), {}};
    return verify_pose(model, T_camera_box, depth, K, cluster, o);
  }
};

// Where the model ends, the scene must step away (or be hidden, or missing): a box face seen alone on
// a wall carries on flat all round its outline; the jug before a wall steps away all round.
TEST(Verify, TheOutlineSaysWhetherTheSceneStepsAwayOrCarriesOn) {
  const Verification jug = Scene().check(Scene().T_camera_jug);
  EXPECT_GT(jug.outline_stepped, 100u);
  EXPECT_LT(jug.outline_continuation, 0.02);
  const Verification face = FaceOnWall(1.2, SensorModel::ideal()).check();
  EXPECT_GT(face.inlier_fraction, 0.99);  // inside the outline the face is a perfect fit...
  EXPECT_GT(face.outline_continued, 100u);
  EXPECT_GT(face.outline_continuation, 0.98);  // ...and all round it the wall carries on
  EXPECT_EQ(face.outline_stepped, 0u);
}

// A flat face has nothing inside its outline to tell a box from a patch of wall: it is accepted only
// where the scene steps away around it (the box standing 30 cm before the wall), not where the wall
// carries on (the face flush with it). A curved model needs no such help: the jug's relief speaks.
TEST(Verify, AFlatFaceIsAcceptedOnlyWhereItsOutlineStepsAway) {
  const FaceOnWall flush(1.2, SensorModel::kinect_v1());
  const Verification patch = flush.check();
  EXPECT_GT(patch.inlier_fraction, 0.95);
  EXPECT_GT(patch.cluster_explained, 0.95);
  EXPECT_LT(patch.model_relief_m, 2 * axial_noise_sigma_frontal(1.2));
  EXPECT_FALSE(patch.accepted);
  VerifyOptions outline_ignored;
  outline_ignored.max_flat_outline_continuation = 1.0;
  EXPECT_TRUE(flush.check(outline_ignored).accepted);  // everything else says yes

  const FaceOnWall standing(1.2, SensorModel::kinect_v1(), 0.3);
  const Verification box = standing.check();
  EXPECT_LT(box.outline_continuation, 0.1);
  EXPECT_TRUE(box.accepted);
  const Scene s;
  EXPECT_TRUE(s.check(s.T_camera_jug).accepted);
}

// An object touching something unknown shares a cluster with it (a jug with a can against its side,
// as segmentation leaves them): the jug explains only its own part of the cluster, and the can's
// points lie beside its silhouette. The right pose is accepted on the points within its silhouette;
// a pose moved off it, or a model fitted to a patch of a larger surface (the wall carrying on all
// round it), is not.
TEST(Verify, AnObjectWithAnUnknownNeighbourIsJudgedOnThePointsWithinItsSilhouette) {
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const TriangleMesh jug = make_jug(), can = make_can(0.07, 0.26), wall = test::square(4.0f);
  const Transform T_camera_jug = make_transform(Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitX()).toRotationMatrix(), {0.0, 0.0, 0.9});
  // The can stands against the jug's side, a little behind it: one cluster in the depth image.
  const Transform T_camera_can = make_transform(Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitX()).toRotationMatrix(), {0.157, 0.0, 0.9});
  const MeshInstance scene[] = {{&jug, T_camera_jug}, {&can, T_camera_can}, {&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.6})}};
  const RenderedFrame f = render(scene, K, {});
  const PointCloud cloud = depth_to_cloud(f.depth, K);
  std::vector<Eigen::Vector3f> cluster;
  std::size_t can_points = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (f.instance[i] == 0 || f.instance[i] == 1) cluster.push_back(cloud.points[i]);
    can_points += f.instance[i] == 1;
  }
  ASSERT_GT(can_points, cluster.size() / 3);  // the neighbour is a large share of the cluster
  const VerifyModel model{&jug, {}, 0.003f, closed_mesh_winding(jug), {}};
  const Verification v = verify_pose(model, T_camera_jug, f.depth, K, cluster, {});
  EXPECT_LT(v.cluster_explained, VerifyOptions{}.min_cluster_explained);
  EXPECT_GT(v.cluster_beside, 0.3);
  EXPECT_GT(v.footprint_explained, 0.96);  // (the can's points within the margin of the silhouette are not beside it)
  EXPECT_LT(v.outline_continuation, 0.5);
  EXPECT_TRUE(v.explained_beside_neighbour);
  EXPECT_TRUE(v.accepted);
  VerifyOptions whole_cluster;  // the bound on the whole cluster alone refuses it
  whole_cluster.min_footprint_explained = 0;
  EXPECT_FALSE(verify_pose(model, T_camera_jug, f.depth, K, cluster, whole_cluster).accepted);
  // Each of the rule's bounds refuses it alone: the whole cluster's floor, a footprint share
  // stricter than the cluster bound asked of the footprint (as in a convex part, tightened), and
  // the margin: counted within 30 px of the silhouette, the can's nearest points are no longer
  // beside the jug but unexplained within its footprint.
  VerifyOptions floor_above;
  floor_above.min_cluster_explained_beside = v.cluster_explained + 0.01;
  EXPECT_FALSE(verify_pose(model, T_camera_jug, f.depth, K, cluster, floor_above).accepted);
  VerifyOptions strict_part;
  strict_part.min_cluster_explained = v.footprint_explained + 0.005;
  EXPECT_FALSE(verify_pose(model, T_camera_jug, f.depth, K, cluster, strict_part).accepted);
  VerifyOptions wide_margin;
  wide_margin.beside_margin_px = 30;
  const Verification wide = verify_pose(model, T_camera_jug, f.depth, K, cluster, wide_margin);
  EXPECT_LT(wide.cluster_beside, v.cluster_beside - 0.05);
  EXPECT_LT(wide.footprint_explained, wide_margin.min_footprint_explained);
  EXPECT_FALSE(wide.accepted);
  // 2 cm off to the side, the jug's own points within the silhouette are left unexplained.
  const Transform aside = make_transform(Eigen::Matrix3d::Identity(), {-0.02, 0, 0}) * T_camera_jug;
  const Verification off = verify_pose(model, aside, f.depth, K, cluster, {});
  EXPECT_LT(off.footprint_explained, VerifyOptions{}.min_footprint_explained);
  EXPECT_FALSE(off.accepted);

  // A box face flush with a wall, its cluster the whole patch of wall around it: the points within
  // the face's silhouette are explained and the rest lies beside it, but the wall carries on all
  // round the outline: a patch of a larger thing, not an object beside a neighbour. (The bound for
  // flat faces is lifted, and the footprint's loosened for the wall just past the silhouette: this
  // is the neighbour rule's own outline test.)
  const FaceOnWall flush(1.2, SensorModel::ideal());
  std::vector<Eigen::Vector3f> patch;
  for (const Eigen::Vector3f& p : depth_to_cloud(flush.depth, flush.K).points)
    if (p.allFinite() && std::abs(p.x() - 0.02f) < 0.15f && std::abs(p.y() + 0.01f) < 0.11f) patch.push_back(p);
  VerifyOptions lenient;
  lenient.max_flat_outline_continuation = 1.0;
  lenient.min_footprint_explained = 0.85;
  const VerifyModel box{&flush.box, {}, 0.003f, closed_mesh_winding(flush.box), {}};
  const Verification face = verify_pose(box, flush.T_camera_box, flush.depth, flush.K, patch, lenient);
  EXPECT_LT(face.cluster_explained, 0.7);
  EXPECT_GT(face.cluster_beside, 0.3);
  EXPECT_GT(face.footprint_explained, lenient.min_footprint_explained);
  EXPECT_GT(face.outline_continuation, 0.9);
  EXPECT_FALSE(face.explained_beside_neighbour);
  EXPECT_FALSE(face.accepted);
  lenient.max_beside_outline_continuation = 1.0;
  EXPECT_TRUE(verify_pose(box, flush.T_camera_box, flush.depth, flush.K, patch, lenient).accepted);  // the outline refused it
}

// Model against plane: the jug's visible surface has relief, and where the jug is truly there the
// observed points have it too; a flat face on a flat wall has none either way.
TEST(Verify, ModelAndPlaneResidualsTellACurvedSurfaceFromAFlatOne) {
  const Scene s;
  const Verification jug = s.check(s.T_camera_jug);
  EXPECT_GT(jug.model_relief_m, 0.008);
  EXPECT_NEAR(jug.plane_rms_m, jug.model_relief_m, 0.001);  // noise-free: the observed surface is the model's
  EXPECT_LT(jug.model_rms_m, 0.0005);
  const Verification face = FaceOnWall(1.2, SensorModel::ideal()).check();
  EXPECT_LT(face.model_relief_m, 1e-4);
  EXPECT_LT(face.plane_rms_m, 1e-4);
}

// Past 3.5 m a Kinect's depth is centimetres of noise in 4 cm steps: the tolerance that grew with it
// let a box face pass on a wall at 3.8 m (as it does with the cap and the range lifted); neither the
// tolerance's cap nor the range limit lets it now. Nearer, at 1.2 m, the face on the wall is judged
// as it always was (and refused only by its outline, which verification reports).
TEST(Verify, AFarWallGetsNoVerdictAndTheToleranceHasACap) {
  const FaceOnWall far(3.8, SensorModel::kinect_v1());
  ASSERT_GT(far.cluster.size(), 500u);
  VerifyOptions uncapped;
  uncapped.max_tolerance_m = 1.0f;
  uncapped.max_depth_m = 100;
  uncapped.max_flat_outline_continuation = 1.0;  // (the outline would refuse it too: see above)
  const Verification loose = far.check(uncapped);
  EXPECT_TRUE(loose.accepted);  // what the grown tolerance allowed
  const Verification v = far.check();
  EXPECT_FALSE(v.accepted);
  EXPECT_NEAR(v.mean_depth_m, 3.8, 0.01);  // the face, on the wall
  EXPECT_FLOAT_EQ(depth_tolerance(3.8f, VerifyOptions{}), 0.02f);
  EXPECT_LT(depth_tolerance(1.0f, VerifyOptions{}), 0.011f);  // nearer, the noise's tolerance as before
  // The noise's own tolerance: the same below the cap; at 3.8 m far past it (5 mm + 2.5 sigma of
  // 2.3 cm: 6.3 cm).
  EXPECT_FLOAT_EQ(depth_noise_tolerance(1.0f, VerifyOptions{}), depth_tolerance(1.0f, VerifyOptions{}));
  EXPECT_GT(depth_noise_tolerance(3.8f, VerifyOptions{}), 0.05f);
  // The cap alone: with the range lifted, the centimetres of noise fall outside 2 cm.
  VerifyOptions range_lifted;
  range_lifted.max_depth_m = 100;
  const Verification capped = far.check(range_lifted);
  EXPECT_LT(capped.inlier_fraction, loose.inlier_fraction);
  EXPECT_LT(capped.inlier_fraction, 0.85);
}

}  // namespace
}  // namespace viewpose
