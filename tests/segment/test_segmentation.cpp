#include <map>
#include <numbers>
#include <limits>
#include <random>
#include <set>
#include <array>
#include <numeric>

#include <fmt/format.h>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/describe/normals.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"
#include "viewpose/render/view_sphere.hpp"
#include "viewpose/segment/convex_segments.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/segment/segmentation.hpp"
#include "viewpose/segment/voxel_grid.hpp"

namespace viewpose {
namespace {

TEST(VoxelGrid, OnePointPerVoxelAtTheCentroid) {
  // Three points in voxel (0,0,0), one in (1,0,0), one in (-1,-1,-1) at 1 cm leaves.
  const PointCloud c = PointCloud::from_points(
      {{0.001f, 0.002f, 0.003f}, {0.005f, 0.002f, 0.009f}, {0.009f, 0.008f, 0.0f}, {0.015f, 0.005f, 0.005f},
       {-0.005f, -0.005f, -0.005f}, {NAN, 0, 0}});
  const PointCloud v = voxel_downsample(c, 0.01f);
  ASSERT_EQ(v.size(), 3u);
  std::vector<Eigen::Vector3f> expected = {{-0.005f, -0.005f, -0.005f}, {0.005f, 0.004f, 0.004f}, {0.015f, 0.005f, 0.005f}};
  for (const auto& e : expected) {
    bool found = false;
    for (const auto& p : v.points) found = found || (p - e).norm() < 1e-6f;
    EXPECT_TRUE(found) << e.transpose();
  }
}

// A frame's worth of points is binned and averaged on every thread: the same bits as on one, and
// as a plain map from voxel to its points in input order gives (each sum in the points' order).
TEST(VoxelGrid, AFramesPointsGiveTheSameVoxelsOnOneThreadAndOnTwo) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> across(-1.2f, 1.2f), deep(0.4f, 4.0f);
  PointCloud c;
  for (int i = 0; i < 200000; ++i) c.points.emplace_back(across(rng), across(rng), deep(rng));
  for (int i = 0; i < 200000; i += 997) c.points[static_cast<std::size_t>(i)] = Eigen::Vector3f(NAN, 0, 1);
  c.points[5] = Eigen::Vector3f(1e30f, 0, 1);  // outside any grid: left out
  for (int i = 0; i < 50000; ++i) c.points.push_back(c.points[static_cast<std::size_t>(i) * 3] + Eigen::Vector3f(0.0005f, 0, 0));
  // And a dense blob: tens of points a voxel, each voxel's mean and first label checked below.
  std::uniform_real_distribution<float> blob(0.0f, 0.03f);
  for (int i = 0; i < 30000; ++i) c.points.emplace_back(0.5f + blob(rng), -0.3f + blob(rng), 1.7f + blob(rng));
  // One voxel of its own whose mean normal shows the order of its sum: forward, the first two
  // cancel and the third is all that is left, (0.71, 0, 0.71); backward the third is lost against
  // the second, (0, 0, 1).
  const std::size_t ordered = c.points.size();
  for (int i = 0; i < 3; ++i) c.points.emplace_back(0.1001f, 0.0001f, 4.5001f);
  std::normal_distribution<float> g(0.0f, 1.0f);
  for (std::size_t i = 0; i < ordered; ++i) c.normals.push_back(Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized());
  c.normals[17] = Eigen::Vector3f::Constant(NAN);  // not summed
  c.normals.emplace_back(1.0f, 0.0f, 0.0f);
  c.normals.emplace_back(-1.0f, 0.0f, 0.0f);
  c.normals.emplace_back(1e-20f, 0.0f, 1e-20f);
  c.labels.resize(c.points.size());
  std::iota(c.labels.begin(), c.labels.end(), 0u);
  c.rgba.resize(c.points.size());
  for (std::size_t i = 0; i < c.rgba.size(); ++i) c.rgba[i] = static_cast<std::uint32_t>(i * 2654435761u);
  c.width = static_cast<int>(c.points.size());
  const float leaf = 0.003f;
  const int threads = thread_count();
  set_thread_count(1);
  const PointCloud one = voxel_downsample(c, leaf);
  set_thread_count(2);
  const PointCloud two = voxel_downsample(c, leaf);
  set_thread_count(threads);
  ASSERT_EQ(one.size(), two.size());
  ASSERT_EQ(one.labels, two.labels);
  ASSERT_EQ(one.rgba, two.rgba);
  ASSERT_EQ(one.normals.size(), one.size());
  for (std::size_t i = 0; i < one.size(); ++i) {
    ASSERT_EQ(one.points[i], two.points[i]) << i;
    ASSERT_TRUE(one.normals[i] == two.normals[i] || (one.normals[i].hasNaN() && two.normals[i].hasNaN())) << i;
  }
  // The reference: voxels in key order (x, then y, then z), each the mean of its points in input
  // order, labelled by its first point.
  std::map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>> voxels;
  for (std::uint32_t i = 0; i < c.points.size(); ++i) {
    const Eigen::Vector3f& p = c.points[i];
    if (!p.allFinite() || p.x() > 1e3f) continue;
    const float inv = 1.0f / leaf;  // (as the grid scales: a product by the inverse, not a quotient)
    voxels[{static_cast<std::int64_t>(std::floor(p.x() * inv)), static_cast<std::int64_t>(std::floor(p.y() * inv)),
            static_cast<std::int64_t>(std::floor(p.z() * inv))}]
        .push_back(i);
  }
  ASSERT_EQ(one.size(), voxels.size());
  std::size_t k = 0, checked_order = 0;
  for (const auto& [key, members] : voxels) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), nsum = Eigen::Vector3d::Zero();
    for (std::uint32_t i : members) {
      sum += c.points[i].cast<double>();
      if (c.normals[i].allFinite()) nsum += c.normals[i].cast<double>();
    }
    ASSERT_EQ(one.points[k], Eigen::Vector3f((sum / static_cast<double>(members.size())).cast<float>())) << k;
    if (nsum.norm() > 0) ASSERT_EQ(one.normals[k], Eigen::Vector3f(nsum.normalized().cast<float>())) << k;
    else ASSERT_TRUE(one.normals[k].hasNaN()) << k;
    ASSERT_EQ(one.labels[k], members.front()) << k;
    ASSERT_EQ(one.rgba[k], c.rgba[members.front()]) << k;
    if (members.front() == ordered) {
      ASSERT_EQ(members.size(), 3u);
      EXPECT_NEAR(one.normals[k].x(), std::sqrt(0.5f), 1e-6f);
      EXPECT_NEAR(one.normals[k].z(), std::sqrt(0.5f), 1e-6f);
      ++checked_order;
    }
    ++k;
  }
  EXPECT_EQ(checked_order, 1u);
}

// Points on the plane z = 1.2 - 0.5 y (a table seen from above), 4 mm apart, 1.5 x 1.5 m.
std::vector<Eigen::Vector3f> table_points() {
  std::vector<Eigen::Vector3f> pts;
  for (float x = -0.75f; x <= 0.75f; x += 0.004f)
    for (float y = -0.75f; y <= 0.75f; y += 0.004f) pts.emplace_back(x, y, 1.2f - 0.5f * y);
  return pts;
}

// The six faces of an axis-aligned box, sampled every 4 mm.
void add_box(std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (float s = lo[a]; s <= hi[a]; s += 0.004f)
      for (float t = lo[b]; t <= hi[b]; t += 0.004f)
        for (float face : {lo[axis], hi[axis]}) {
          Eigen::Vector3f p;
          p[axis] = face;
          p[a] = s;
          p[b] = t;
          pts.push_back(p);
        }
  }
}

TEST(Planes, FindsTheTableAtItsDistanceAndNormalAndKeepsTheBoxes) {
  std::vector<Eigen::Vector3f> pts = table_points();
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.002f);
  for (auto& p : pts) p.z() += noise(rng);
  const std::size_t table = pts.size();
  add_box(pts, {-0.3f, -0.3f, 0.7f}, {-0.1f, -0.1f, 0.85f});
  add_box(pts, {0.1f, 0.1f, 0.6f}, {0.25f, 0.3f, 0.8f});  // flat faces of 15-20 cm: not "large"
  const PlaneRemoval r = remove_large_planes(PointCloud::from_points(pts));
  ASSERT_EQ(r.removed.size(), 1u);
  const Plane& p = r.removed[0];
  const Eigen::Vector3f n_true = Eigen::Vector3f(0, 0.5f, 1).normalized();
  EXPECT_LT(std::acos(std::abs(p.coefficients.head<3>().dot(n_true))) * 180 / std::numbers::pi, 0.5);
  // Distance of the plane from the camera: 1.2 / |(0, 0.5, 1)| = 1.0733 m.
  EXPECT_NEAR(std::abs(p.coefficients[3]), 1.2 / std::sqrt(1.25), 0.001);
  EXPECT_GT(p.coefficients.head<3>().dot(-Eigen::Vector3f(0, 0, 1.2f)), 0) << "normal faces the camera";
  EXPECT_GT(p.inliers.size(), table * 98 / 100);
  EXPECT_GT(r.remaining.size(), (pts.size() - table) * 9 / 10);  // the boxes stay
}

TEST(Planes, ThePatchCoversWhereThePlaneWasSeenAndNotItsEquationsEveryPoint) {
  // The table of the test above with a hole 0.4 m square cut from its middle: the plane's patch
  // covers the table, not the hole and not the plane's continuation past the table's edge.
  std::vector<Eigen::Vector3f> pts;
  for (const Eigen::Vector3f& p : table_points()) {
    if (std::abs(p.x()) > 0.2f || std::abs(p.y()) > 0.2f) pts.push_back(p);
  }
  const PlaneRemoval r = remove_large_planes(PointCloud::from_points(pts));
  ASSERT_EQ(r.removed.size(), 1u);
  const PlanePatch& patch = r.removed[0].patch;
  const auto on_table = [](float x, float y) { return Eigen::Vector3f(x, y, 1.2f - 0.5f * y); };
  EXPECT_TRUE(patch.covers(on_table(0.5f, 0.5f)));
  EXPECT_TRUE(patch.covers(on_table(-0.7f, 0.0f)));
  EXPECT_TRUE(patch.covers(on_table(0.21f, 0.0f)));  // the hole's rim
  EXPECT_FALSE(patch.covers(on_table(0.0f, 0.0f)));  // the hole
  EXPECT_FALSE(patch.covers(on_table(0.15f, -0.1f)));
  EXPECT_FALSE(patch.covers(on_table(1.0f, 0.0f)));  // past the edge, on the plane's equation
  EXPECT_FALSE(patch.covers(on_table(0.0f, -0.85f)));
  EXPECT_FALSE(patch.covers(Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_FALSE(PlanePatch{}.covers(on_table(0.5f, 0.5f)));  // a plane of fit_plane, seen nowhere known
}

TEST(Segmentation, WhatLiesPastTheSensorsUsefulRangeFormsNoCluster) {
  // A box at 1 m and a box at 4.5 m, where a Kinect's depth is centimetres of noise: only the near
  // one is a cluster by default; with no limit, both.
  std::vector<Eigen::Vector3f> pts;
  add_box(pts, {-0.1f, -0.1f, 0.95f}, {0.05f, 0.05f, 1.1f});
  add_box(pts, {0.3f, 0.3f, 4.45f}, {0.5f, 0.5f, 4.65f});
  const PointCloud cloud = PointCloud::from_points(pts);
  const Segmentation near = segment_scene(cloud);
  ASSERT_EQ(near.clusters.size(), 1u);
  for (const Eigen::Vector3f& p : near.points.points) EXPECT_LE(p.z(), SegmentOptions{}.max_depth_m);
  SegmentOptions unlimited;
  unlimited.max_depth_m = 0;
  EXPECT_EQ(segment_scene(cloud, unlimited).clusters.size(), 2u);
}

TEST(Clusters, SeparatedBoxesAreSeparateClustersInBothVersions) {
  // Three boxes 5 cm apart, rendered as a depth frame so that the organized version can run too.
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const TriangleMesh box = make_box_mesh({0.1f, 0.1f, 0.1f});
  const MeshInstance boxes[] = {{&box, make_transform(Eigen::Matrix3d::Identity(), {-0.15, 0, 1.0})},
                                {&box, make_transform(Eigen::Matrix3d::Identity(), {0.0, 0, 1.0})},
                                {&box, make_transform(Eigen::Matrix3d::Identity(), {0.15, 0.05, 1.1})}};
  const PointCloud frame = depth_to_cloud(render(boxes, K).depth, K);
  std::vector<std::uint32_t> all;
  for (std::size_t i = 0; i < frame.size(); ++i) if (frame.points[i].allFinite()) all.push_back(static_cast<std::uint32_t>(i));
  const auto by_tree = euclidean_clusters(frame, all);
  const auto by_grid = organized_clusters(frame, all);
  ASSERT_EQ(by_tree.size(), 3u);
  ASSERT_EQ(by_grid.size(), 3u);
  for (std::size_t c = 0; c < 3; ++c) EXPECT_EQ(by_tree[c], by_grid[c]);
  // And two boxes 1 cm apart merge at the 2 cm tolerance: the limit the thesis accepted. (Centres
  // at +-5.53 cm rather than +-5.5: at 5.5 one pixel column's ray grazes the far edge of a box's
  // inner face, exactly, and that one-pixel strip 10 cm back is a cluster of its own.)
  const MeshInstance close[] = {{&box, make_transform(Eigen::Matrix3d::Identity(), {-0.0553, 0, 1.0})},
                                {&box, make_transform(Eigen::Matrix3d::Identity(), {0.0553, 0, 1.0})}};
  const PointCloud pair = depth_to_cloud(render(close, K).depth, K);
  std::vector<std::uint32_t> both;
  for (std::size_t i = 0; i < pair.size(); ++i) if (pair.points[i].allFinite()) both.push_back(static_cast<std::uint32_t>(i));
  EXPECT_EQ(euclidean_clusters(pair, both).size(), 1u);
}

// Objects standing on a table (z = 0, not drawn), seen by a noisy Kinect from `eye` (metres, world
// frame), voxelized at 3 mm as the recognizer does; each point labelled with the object it shows.
PointCloud objects_seen_from(std::span<const MeshInstance> in_world, const Eigen::Vector3d& eye, std::uint64_t seed) {
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const Transform T_camera_world = look_at(eye, {0, 0, 0.04});
  std::vector<MeshInstance> instances(in_world.begin(), in_world.end());
  for (auto& instance : instances) instance.T_camera_object = T_camera_world * instance.T_camera_object;
  RenderOptions options;
  options.normals = true;  // the sensor model's dropouts depend on the incidence angle
  const RenderedFrame frame = render(instances, K, options);
  const DepthImage depth = simulate_sensor(frame, K, SensorModel::kinect_v1(), seed);
  PointCloud cloud = depth_to_cloud(depth, K);
  cloud.labels.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud.labels[i] = static_cast<std::uint32_t>(frame.instance[i] + 1);
  return voxel_downsample(cloud, 0.003f);
}

// Of `segment`, how many points carry each label.
std::map<std::uint32_t, std::size_t> labels_of(const PointCloud& cloud, const Cluster& segment) {
  std::map<std::uint32_t, std::size_t> count;
  for (std::uint32_t i : segment) ++count[cloud.labels[i]];
  return count;
}

TEST(ConvexSegments, ABrickAgainstAMugSplitsIntoTheTwo) {
  // As in YCB-Video's frames: a brick stands on the table touching a mug, in front of it, seen from
  // 70 cm at 40 degrees down. Euclidean clustering cannot part them; their join is a concave crease.
  const TriangleMesh mug = make_mug(), brick = make_box_mesh({0.05f, 0.075f, 0.05f});
  const std::vector<MeshInstance> world = {
      {&mug, Transform::Identity()},
      {&brick, make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.041 + 0.025 - 0.004, 0.02, 0.025))}};
  // Local convexity is not always right where the brick's top ends beside the curved mug: measured,
  // the mug leaks into the brick's segment in 1 of seeds 1 to 8. Asserted: at least 7 of 8 clean.
  int clean = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const PointCloud cloud = objects_seen_from(world, {0.55, 0.2, 0.45}, seed);
    std::vector<std::uint32_t> all(cloud.size());
    std::iota(all.begin(), all.end(), 0u);
    ASSERT_EQ(euclidean_clusters(cloud, all).size(), 1u) << "the objects should touch";
    const std::vector<Cluster> segments = convex_segments(cloud);
    std::map<std::uint32_t, std::size_t> total, largest;
    for (std::uint32_t label : cloud.labels) ++total[label];
    ASSERT_EQ(total.size(), 2u);
    // No segment mixes the two; the brick comes out nearly whole. The mug comes out in pieces (its
    // outside around the brick, and its inside seen over the near rim behind a step), the largest
    // measured at 30 % of it.
    bool pure = true;
    for (const Cluster& segment : segments) {
      const auto count = labels_of(cloud, segment);
      const auto majority = std::max_element(count.begin(), count.end(), [](auto& a, auto& b) { return a.second < b.second; });
      pure = pure && static_cast<double>(majority->second) > 0.95 * static_cast<double>(segment.size());
      largest[majority->first] = std::max(largest[majority->first], majority->second);
    }
    const bool brick_whole = static_cast<double>(largest[2]) > 0.8 * static_cast<double>(total[2]);
    const bool mug_found = static_cast<double>(largest[1]) > 0.25 * static_cast<double>(total[1]);  // measured 0.3
    clean += pure && brick_whole && mug_found;
  }
  EXPECT_GE(clean, 7) << "of 8 seeds";
}

TEST(ConvexSegments, EmptyAndNonFiniteInputGiveNoSegments) {
  EXPECT_TRUE(convex_segments(PointCloud{}).empty());
  const PointCloud nans = PointCloud::from_points(std::vector<Eigen::Vector3f>(500, Eigen::Vector3f(NAN, 0, 1)));
  EXPECT_TRUE(convex_segments(nans).empty());
  ConvexSegmentOptions bad;
  bad.cell_m = 0;
  EXPECT_THROW(convex_segments(nans, bad), Error);
}

TEST(ConvexSegments, ConvexAndSmoothObjectsStayWhole) {
  // A box (convex edges), a can and a sphere (smooth), each alone, from several sides: one segment.
  // Cubes seen edge-on or holding few points (the outline) join nothing: measured 86 to 90 % of
  // the points in the segment.
  const TriangleMesh box = make_box_mesh({0.06f, 0.095f, 0.2f}), can = make_can(), ball = make_sphere(0.06, 30);
  const Transform lift_box = make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.1));
  const Transform lift_ball = make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.06));
  const std::vector<MeshInstance> objects = {{&box, lift_box}, {&can, Transform::Identity()}, {&ball, lift_ball}};
  for (const MeshInstance& object : objects) {
    for (double azimuth : {0.3, 1.4, 2.5}) {
      const Eigen::Vector3d eye(0.8 * std::cos(azimuth), 0.8 * std::sin(azimuth), 0.5);
      const PointCloud cloud = objects_seen_from(std::span(&object, 1), eye, 7);
      const std::vector<Cluster> segments = convex_segments(cloud);
      const auto where = fmt::format("object {} azimuth {}", &object - objects.data(), azimuth);
      ASSERT_EQ(segments.size(), 1u) << where;
      EXPECT_GT(static_cast<double>(segments[0].size()), 0.8 * static_cast<double>(cloud.size())) << where;
    }
  }
}

TEST(Normals, SphereNormalsAreRadialWithinTwoDegrees) {
  // A 10 cm sphere seen from 0.6 m, rendered and unprojected: normals point out of its centre.
  const TriangleMesh sphere = make_sphere(0.1);
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const Eigen::Vector3f centre(0, 0, 0.6f);
  const MeshInstance inst{&sphere, make_transform(Eigen::Matrix3d::Identity(), centre.cast<double>())};
  PointCloud organized = depth_to_cloud(render(std::span(&inst, 1), K).depth, K);
  PointCloud voxels = voxel_downsample(organized, 0.003f);
  estimate_normals(voxels);
  estimate_normals_organized(organized);
  for (const PointCloud* c : {&voxels, &organized}) {
    int checked = 0;
    for (std::size_t i = 0; i < c->size(); ++i) {
      const Eigen::Vector3f& p = c->points[i];
      const Eigen::Vector3f& n = c->normals[i];
      if (!p.allFinite() || !n.allFinite()) continue;
      const Eigen::Vector3f radial = (p - centre).normalized();
      if (radial.dot(-centre.normalized()) < 0.3f) continue;  // skip the rim, where neighbours are one-sided
      ASSERT_LT(std::acos(std::clamp(n.dot(radial), -1.0f, 1.0f)) * 180 / std::numbers::pi, 2.0) << p.transpose();
      ++checked;
    }
    EXPECT_GT(checked, 2000);
  }
  // Curvature of a sphere sampled over 1.5 cm is small but not zero; of a plane, zero.
  EXPECT_GT(voxels.curvature[voxels.size() / 2], 0.0f);
}

TEST(Normals, FewerThanThreeNeighboursGiveNaN) {
  PointCloud c = PointCloud::from_points({{0, 0, 1}, {0.001f, 0, 1}, {1, 1, 1}});
  estimate_normals(c);
  for (const auto& n : c.normals) EXPECT_FALSE(n.allFinite());
}

// mOSD (real Kinect frames with per-point object labels): label 20-29 is object 2, 30-39 object 3...
TEST(RealData, MosdClustersMatchEveryObjectThatTouchesNoOther) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  int isolated = 0, isolated_iou90 = 0, touching = 0;
  double touching_iou = 0;
  for (int id : {0, 17, 25, 33, 36, 40, 45, 50, 55, 60}) {
    SCOPED_TRACE(id);
    const PointCloud frame = read_pcd(test::shared_data() / fmt::format("pcl_mosd/test/test{}.pcd", id)).cloud;
    const Segmentation seg = segment_scene(frame);
    ASSERT_GE(seg.planes.size(), 1u) << "the table";
    std::map<int, std::vector<std::uint32_t>> objects;
    for (std::size_t i = 0; i < seg.points.size(); ++i) {
      if (seg.points.labels[i] >= 20) objects[static_cast<int>(seg.points.labels[i] / 10)].push_back(static_cast<std::uint32_t>(i));
    }
    // The table (labels 1-9) is gone: almost none of it is left in a cluster.
    std::size_t table_in_clusters = 0, clustered = 0;
    for (const auto& c : seg.clusters) {
      for (std::uint32_t i : c) table_in_clusters += seg.points.labels[i] < 20 ? 1 : 0;
      clustered += c.size();
    }
    EXPECT_LT(table_in_clusters, clustered / 50 + 20);
    for (const auto& [obj, idx] : objects) {
      // Touching: within the 2 cm clustering tolerance of another object's points.
      std::vector<Eigen::Vector3f> mine;
      for (std::uint32_t i : idx) mine.push_back(seg.points.points[i]);
      const KdTree tree(mine);
      bool touches = false;
      for (const auto& [other, oidx] : objects) {
        if (other == obj) continue;
        for (std::uint32_t j : oidx) {
          std::uint32_t k;
          float d2;
          if (tree.nearest(seg.points.points[j], k, d2) && d2 < 0.02f * 0.02f) touches = true;
        }
      }
      // Every cluster holding this object's points, its purity, and the object's coverage.
      std::size_t covered = 0;
      double best_iou = 0;
      for (const auto& c : seg.clusters) {
        std::size_t inter = 0;
        for (std::uint32_t i : c) inter += (seg.points.labels[i] >= 20 && static_cast<int>(seg.points.labels[i] / 10) == obj) ? 1 : 0;
        if (inter == 0) continue;
        covered += inter;
        best_iou = std::max(best_iou, static_cast<double>(inter) / static_cast<double>(idx.size() + c.size() - inter));
        if (!touches) {
          EXPECT_GT(static_cast<double>(inter) / static_cast<double>(c.size()), 0.95) << "object " << obj << " merged";
        }
      }
      if (touches) {
        ++touching;
        touching_iou += best_iou;
        continue;
      }
      ++isolated;
      isolated_iou90 += best_iou >= 0.9 ? 1 : 0;
      EXPECT_GT(static_cast<double>(covered) / static_cast<double>(idx.size()), 0.9) << "object " << obj << " lost";
    }
  }
  // Measured (docs/RESULTS.md): 16 of 18 isolated objects in one cluster at IoU >= 0.9; the other
  // two are split in two by an occluder in front, not merged. Touching objects merge.
  std::printf("mOSD: isolated objects %d, of which %d at IoU >= 0.9; touching objects %d, mean best IoU %.2f\n", isolated,
              isolated_iou90, touching, touching_iou / std::max(touching, 1));
  EXPECT_EQ(isolated, 18);
  EXPECT_GE(isolated_iou90, 16);
}

}  // namespace
}  // namespace viewpose

namespace viewpose {
namespace {

// Clusters by definition: the connected components of "closer than the tolerance", by brute force.
std::vector<Cluster> brute_force_clusters(const PointCloud& cloud, float tolerance) {
  const std::size_t n = cloud.size();
  std::vector<int> label(n, -1);
  std::vector<Cluster> out;
  for (std::size_t s = 0; s < n; ++s) {
    if (label[s] >= 0) continue;
    Cluster c{static_cast<std::uint32_t>(s)};
    label[s] = static_cast<int>(out.size());
    for (std::size_t q = 0; q < c.size(); ++q)
      for (std::size_t j = 0; j < n; ++j)
        if (label[j] < 0 && (cloud.points[j] - cloud.points[c[q]]).norm() <= tolerance) {
          label[j] = label[s];
          c.push_back(static_cast<std::uint32_t>(j));
        }
    std::sort(c.begin(), c.end());
    out.push_back(c);
  }
  return out;
}

TEST(Clusters, CubeGridGivesExactlyTheTransitiveClosure) {
  // Random blobs with gaps around the tolerance, so that many pairs of cubes are near misses.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-0.15f, 0.15f);
  std::normal_distribution<float> g(0.0f, 0.012f);
  std::vector<Eigen::Vector3f> pts;
  for (int blob = 0; blob < 25; ++blob) {
    const Eigen::Vector3f centre(u(rng), u(rng), 1.0f + u(rng));
    for (int k = 0; k < 40; ++k) pts.push_back(centre + Eigen::Vector3f(g(rng), g(rng), g(rng)));
  }
  pts.push_back(Eigen::Vector3f::Constant(NAN));
  const PointCloud cloud = PointCloud::from_points(pts);
  std::vector<std::uint32_t> all(cloud.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  ClusterOptions o;
  o.min_points = 1;
  std::vector<Cluster> expected = brute_force_clusters(PointCloud::from_points({pts.begin(), pts.end() - 1}), o.tolerance_m);
  std::vector<Cluster> got = euclidean_clusters(cloud, all, o);
  ASSERT_GT(expected.size(), 5u);
  const auto by_first = [](const Cluster& a, const Cluster& b) { return a.front() < b.front(); };
  std::sort(expected.begin(), expected.end(), by_first);
  std::sort(got.begin(), got.end(), by_first);
  EXPECT_EQ(got, expected);
  EXPECT_TRUE(euclidean_clusters(cloud, {}, o).empty()) << "no indices, no clusters";
}

TEST(Clusters, PairsLinkAcrossEveryNeighbouringCube) {
  // Pairs of points in neighbouring cubes (of side tolerance / sqrt(3)), at every offset up to two
  // cubes on each axis, each pair far from every other: whether a pair is one cluster or two rests
  // on its one link alone. Each lies near the cubes' facing corners, some just within the
  // tolerance and some just beyond; the test checks that links are made at every offset whose
  // cubes' nearest corners lie within it. A neighbour left out of the search, or a link missed at
  // any offset, fails.
  ClusterOptions o;
  o.min_points = 1;
  const float cube = o.tolerance_m / std::sqrt(3.0f);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> u(0.02f, 0.98f);
  // A coordinate within its cube: near the side facing the other cube (d > 0: the far side), or anywhere.
  const auto local = [&](int d) { return cube * (d > 0 ? 1.0f - 0.2f * u(rng) : d < 0 ? 0.2f * u(rng) : u(rng)); };
  std::vector<Eigen::Vector3f> pts;
  std::vector<Cluster> expected;
  std::set<std::array<int, 3>> linked_offsets;
  int site = 0;
  for (int dx = -2; dx <= 2; ++dx)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dz = -2; dz <= 2; ++dz) {
        for (int trial = 0; trial < 24; ++trial, ++site) {
          // Each pair at its own site, 12 cubes (14 cm) from the next along a row.
          const Eigen::Vector3f origin = cube * Eigen::Vector3f(static_cast<float>(12 * (site % 40)), static_cast<float>(12 * (site / 40 % 40)),
                                                                static_cast<float>(80 + 12 * (site / 1600)));
          const Eigen::Vector3f a = origin + Eigen::Vector3f(local(dx), local(dy), local(dz));
          const Eigen::Vector3f b = origin + cube * Eigen::Vector3f(static_cast<float>(dx), static_cast<float>(dy), static_cast<float>(dz)) +
                                    Eigen::Vector3f(local(-dx), local(-dy), local(-dz));
          const auto first = static_cast<std::uint32_t>(pts.size());
          pts.push_back(a);
          pts.push_back(b);
          if ((a - b).squaredNorm() <= o.tolerance_m * o.tolerance_m) {
            expected.push_back({first, first + 1});
            linked_offsets.insert({dx, dy, dz});
          } else {
            expected.push_back({first});
            expected.push_back({first + 1});
          }
        }
      }
  // Every offset but the eight two cubes away on all three axes, whose corners lie a tolerance apart.
  EXPECT_EQ(linked_offsets.size(), 5u * 5u * 5u - 8u);
  const std::size_t pairs = pts.size() / 2;
  EXPECT_GT(expected.size() - pairs, pairs / 10) << "pairs just too far apart, too";
  const PointCloud cloud = PointCloud::from_points(pts);
  std::vector<std::uint32_t> all(cloud.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<Cluster> got = euclidean_clusters(cloud, all, o);
  const auto by_first = [](const Cluster& l, const Cluster& r) { return l.front() < r.front(); };
  std::sort(expected.begin(), expected.end(), by_first);
  std::sort(got.begin(), got.end(), by_first);
  EXPECT_EQ(got, expected);
}

}  // namespace
}  // namespace viewpose
