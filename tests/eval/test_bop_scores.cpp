// BOP's Average Recall against hand-worked cases: the truth itself, poses moved by known amounts,
// a symmetric object turned about its axis, targets and invisible ground truths.
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/eval/bop_scores.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K{500, 500, 319.5, 239.5, 640, 480};  // r = 640 / 640 = 1: MSPD thresholds 5..50 px

Transform pose(const Eigen::Vector3d& axis, double deg, const Eigen::Vector3d& t) {
  return make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix(), t);
}
Transform moved(const Transform& T, const Eigen::Vector3d& by_camera_frame) {
  Transform out = T;
  out.translation() += by_camera_frame;
  return out;
}

// The objects' depth drawn together, as a sensor would see the scene (no noise).
DepthImage draw(const std::vector<MeshInstance>& instances) { return render(instances, K).depth; }

// An in-memory dataset of one scene; each image's frame is given to the scorer directly.
struct Scene {
  BopDataset ds;
  std::map<int, DepthImage> depth;  // by im_id
  std::map<int, TriangleMesh> meshes;

  void add_object(int id, TriangleMesh mesh, const Symmetries& sym = {}) {
    ModelInfo info;
    info.diameter_m = mesh_diameter(mesh);
    info.symmetries_discrete = sym.discrete;
    info.symmetries_continuous = sym.continuous;
    ds.models[id] = info;
    meshes[id] = std::move(mesh);
  }
  // An image showing `gt` (all drawn), with visible fractions when given.
  void add_image(int im_id, const std::vector<GroundTruthPose>& gt, const std::vector<double>& visib = {}) {
    BopImage im;
    im.scene_id = 1;
    im.im_id = im_id;
    im.camera.K = K;
    im.gt = gt;
    for (double v : visib) {
      GroundTruthInfo info;
      info.visib_fract = v;
      im.gt_info.push_back(info);
    }
    std::vector<MeshInstance> drawn;
    for (const GroundTruthPose& g : gt) drawn.push_back({&meshes.at(g.obj_id), g.T_camera_object});
    depth[im_id] = draw(drawn);
    ds.images.push_back(im);
  }
  BopScores score(const std::vector<BopResult>& results, BopScoreOptions o = {}) const {
    o.load_frame = [this](const BopImage& im) { return BopFrame{depth.at(im.im_id), K}; };
    return score_bop(ds, meshes, results, o);
  }
};

BopResult estimate(int im_id, int obj_id, double score, const Transform& T) { return {1, im_id, obj_id, score, T, -1}; }

std::vector<int> all(int n, int value) { return std::vector<int>(static_cast<std::size_t>(n), value); }

TEST(EvalBop, TheTruthScoresOneOnADatasetReadFromDisk) {
  // Two boxes, the nearer hiding part of the farther, written as a BOP dataset and read back.
  test::TempDir dir;
  const auto root = dir.path();
  const auto scene = root / "test" / "000001";
  std::filesystem::create_directories(scene / "depth");
  std::filesystem::create_directories(root / "models");
  const TriangleMesh near_box = make_box_mesh({0.08f, 0.06f, 0.04f}), far_box = make_box_mesh({0.2f, 0.1f, 0.05f});
  const Transform T_near = pose({1, 2, 0}, 30, {0.02, 0.0, 0.7}), T_far = pose({0, 1, 1}, -40, {-0.03, 0.01, 0.9});
  write_file_atomic(root / "camera.json", format_bop_camera({K, 0.1}));
  ModelsInfo models;
  models[1].diameter_m = mesh_diameter(near_box);
  models[2].diameter_m = mesh_diameter(far_box);
  write_file_atomic(root / "models" / "models_info.json", format_models_info(models));
  SceneCameras cams;
  cams[0] = {K, 0.1};
  write_file_atomic(scene / "scene_camera.json", format_scene_camera(cams));
  SceneGroundTruth gt;
  gt[0] = {{1, T_near}, {2, T_far}};
  write_file_atomic(scene / "scene_gt.json", format_scene_gt(gt));
  SceneGroundTruthInfo info;
  info[0] = {GroundTruthInfo{}, GroundTruthInfo{}};
  info[0][0].visib_fract = 1.0;
  info[0][1].visib_fract = 0.6;
  write_file_atomic(scene / "scene_gt_info.json", format_scene_gt_info(info));
  const std::vector<MeshInstance> both = {{&near_box, T_near}, {&far_box, T_far}};
  write_depth_png(scene / "depth" / "000000.png", draw(both), 0.0001);  // 0.1 mm a unit

  const BopDataset ds = open_bop_dataset(root, "test");
  const std::map<int, TriangleMesh> meshes = {{1, near_box}, {2, far_box}};
  const std::vector<BopResult> results = {estimate(0, 1, 0.9, T_near), estimate(0, 2, 0.8, T_far)};
  const BopScores s = score_bop(ds, meshes, results);
  EXPECT_FALSE(s.targets_mode);
  EXPECT_EQ(s.estimates_used, 2);
  EXPECT_EQ(s.total.targets, 2);
  EXPECT_EQ(s.total.found_vsd, all(100, 2));
  EXPECT_EQ(s.total.found_mssd, all(10, 2));
  EXPECT_EQ(s.total.found_mspd, all(10, 2));
  EXPECT_DOUBLE_EQ(s.total.ar_vsd, 1.0);
  EXPECT_DOUBLE_EQ(s.total.ar_mssd, 1.0);
  EXPECT_DOUBLE_EQ(s.total.ar_mspd, 1.0);
  EXPECT_DOUBLE_EQ(s.total.ar(), 1.0);
  ASSERT_EQ(s.per_object.size(), 2u);
  EXPECT_DOUBLE_EQ(s.per_object.at(2).ar(), 1.0);
  EXPECT_DOUBLE_EQ(s.per_scene.at(1).ar(), 1.0);
  EXPECT_DOUBLE_EQ(s.mspd_scale, 1.0);

  // Nothing estimated: nothing found.
  const BopScores none = score_bop(ds, meshes, std::vector<BopResult>{});
  EXPECT_EQ(none.total.targets, 2);
  EXPECT_DOUBLE_EQ(none.total.ar(), 0.0);
}

TEST(EvalBop, ATranslationAcrossTheImageGivesItsMssdAndPixelShift) {
  const TriangleMesh box = make_box_mesh({0.1f, 0.06f, 0.04f});
  const Transform truth = pose({1, -1, 2}, 35, {0.01, -0.02, 0.8});
  // Every point moves by d in space; in the image by fx d / z, most for the nearest point.
  double z_min = INFINITY, z_max = 0;
  for (const Eigen::Vector3f& v : box.vertices) {
    z_min = std::min(z_min, (truth * v.cast<double>()).z());
    z_max = std::max(z_max, (truth * v.cast<double>()).z());
  }
  const double d = 22.5 * z_min / K.fx;  // MSPD 22.5 px: correct from 25 px up, 6 thresholds of 10
  const Transform shifted = moved(truth, {d, 0, 0});
  const std::vector<Transform> identity = {Transform::Identity()};
  EXPECT_NEAR(mssd_error(shifted, truth, box.vertices, identity), d, 1e-9);
  EXPECT_NEAR(mspd_error(shifted, truth, box.vertices, identity, K), 22.5, 1e-6);
  EXPECT_GT(22.5, K.fx * d / z_max + 1.0);  // the farthest point moves clearly less: the max is the nearest's

  Scene sc;
  sc.add_object(3, box);
  sc.add_image(0, {{3, truth}});
  const double diameter = sc.ds.models.at(3).diameter_m;
  ASSERT_GT(d / diameter, 0.25 + 0.01);  // MSSD between the 0.25 and 0.30 thresholds: 5 of 10
  ASSERT_LT(d / diameter, 0.30 - 0.01);
  const BopScores s = sc.score({estimate(0, 3, 1.0, shifted)});
  EXPECT_EQ(s.total.found_mssd, (std::vector<int>{0, 0, 0, 0, 0, 1, 1, 1, 1, 1}));
  EXPECT_EQ(s.total.found_mspd, (std::vector<int>{0, 0, 0, 0, 1, 1, 1, 1, 1, 1}));
  EXPECT_DOUBLE_EQ(s.total.ar_mssd, 0.5);
  EXPECT_DOUBLE_EQ(s.total.ar_mspd, 0.6);
  EXPECT_DOUBLE_EQ(s.total.ar(), (s.total.ar_vsd + 0.5 + 0.6) / 3);

  // The thresholds of MSPD scale with the image's width: at 320 px wide, 2.5 to 25 px.
  Scene half;
  half.add_object(3, box);
  half.add_image(0, {{3, truth}});
  BopScoreOptions o;
  CameraIntrinsics K_half = K;
  K_half.width = 320;
  o.load_frame = [&](const BopImage& im) { return BopFrame{half.depth.at(im.im_id), K_half}; };
  const DepthImage cropped = [&] {
    DepthImage c(320, 480);
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 320; ++u) c.at(u, v) = half.depth.at(0).at(u, v);
    return c;
  }();
  half.depth[0] = cropped;
  const BopScores narrow = score_bop(half.ds, half.meshes, std::vector<BopResult>{estimate(0, 3, 1.0, shifted)}, o);
  EXPECT_DOUBLE_EQ(narrow.mspd_scale, 0.5);
  EXPECT_EQ(narrow.total.found_mspd, (std::vector<int>{0, 0, 0, 0, 0, 0, 0, 0, 0, 1}));  // only 25 px > 22.5
}

TEST(EvalBop, VsdOfAFrontalPlateMovedAlongTheAxis) {
  // A 20 x 20 cm plate 2 mm thick facing the camera at 1 m; its front face at 0.999 m.
  const TriangleMesh plate = make_box_mesh({0.2f, 0.2f, 0.002f});
  const double diameter = mesh_diameter(plate);  // 0.28285 m
  const Transform truth = make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.0});
  const DepthImage test = draw({{&plate, truth}});
  // Pixel centres whose ray meets the front face at depth z: |u - cx| <= fx 0.1 / z, the same in v.
  const auto side = [](double z_front) {
    int n = 0;
    for (int u = 0; u < K.width; ++u) n += std::abs(u - K.cx) <= K.fx * 0.1 / z_front;
    return n;
  };
  const DistanceWindow gt = render_distance(plate, truth, K);
  const std::vector<double> taus = bop_fractions();
  {
    // 20 mm farther: smaller in the image, and 20 mm behind the surface seen (more than delta =
    // 15 mm) but visible where the truth is. The surfaces are 20 mm (x the ray's slant, at most
    // 1 %) apart: 0.0707 to 0.0714 of the diameter, between the first two taus.
    const double d = 0.02;
    const DistanceWindow est = render_distance(plate, moved(truth, {0, 0, d}), K);
    const double n_gt = std::pow(side(0.999), 2), n_est = std::pow(side(0.999 + d), 2);
    EXPECT_EQ(n_gt, 100.0 * 100.0);
    EXPECT_EQ(n_est, 98.0 * 98.0);
    const std::vector<double> e = vsd_errors(test, K, est, gt, 0.015, taus, diameter);
    ASSERT_EQ(e.size(), 10u);
    EXPECT_NEAR(e[0], 1.0, 1e-12);  // tau 5 %: every pixel of the union is wrong
    for (std::size_t t = 1; t < 10; ++t) EXPECT_NEAR(e[t], (n_gt - n_est) / n_gt, 1e-12) << t;  // only the rim
    // Matched: from tau 10 % on, e = 0.0396 is below every threshold; AR_VSD = 9 x 10 / 100.
    Scene sc;
    sc.add_object(1, plate);
    sc.add_image(0, {{1, truth}});
    const BopScores s = sc.score({estimate(0, 1, 1.0, moved(truth, {0, 0, d}))});
    EXPECT_DOUBLE_EQ(s.total.ar_vsd, 0.9);
  }
  {
    // 20 mm nearer: larger, in front of the surface seen, so visible everywhere it is drawn; the
    // truth is the part of it the union does not lose.
    const double d = -0.02;
    const DistanceWindow est = render_distance(plate, moved(truth, {0, 0, d}), K);
    const double n_gt = std::pow(side(0.999), 2), n_est = std::pow(side(0.999 + d), 2);
    EXPECT_EQ(n_est, 102.0 * 102.0);
    const std::vector<double> e = vsd_errors(test, K, est, gt, 0.015, taus, diameter);
    EXPECT_NEAR(e[0], 1.0, 1e-12);
    for (std::size_t t = 1; t < 10; ++t) EXPECT_NEAR(e[t], (n_est - n_gt) / n_est, 1e-12) << t;
  }
  {
    // Hidden behind a wall 10 cm in front of it: neither is visible, except where depth is missing.
    DepthImage wall(K.width, K.height);
    for (float& z : wall.depth_m) z = 0.9f;
    EXPECT_EQ(vsd_errors(wall, K, gt, gt, 0.015, taus, diameter), std::vector<double>(10, 1.0));  // empty union
    for (int v = 0; v < 240; ++v)
      for (int u = 0; u < K.width; ++u) wall.at(u, v) = NAN;  // the top half unmeasured: visible there
    EXPECT_EQ(vsd_errors(wall, K, gt, gt, 0.015, taus, diameter), std::vector<double>(10, 0.0));
  }
  // Drawn in its window, the plate is what the whole image shows.
  const RenderedFrame whole = render(std::vector<MeshInstance>{{&plate, truth}}, K);
  for (int v = 0; v < K.height; v += 7)
    for (int u = 0; u < K.width; u += 5) {
      const double expected = depth_to_distance(whole.depth.at(u, v), u, v, K);
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(gt.at(u, v))) << u << "," << v;
      } else {
        EXPECT_NEAR(gt.at(u, v), expected, 1e-6) << u << "," << v;
      }
    }
}

TEST(EvalBop, ASymmetricObjectTurnedAboutItsAxisScoresAsTheTruth) {
  TriangleMesh can = make_can(0.04, 0.12, 64);
  centre_on_bounding_box(can);
  ASSERT_NEAR(bounding_box(can).max.z(), 0.06, 1e-6);  // the axis is z
  const Transform truth = pose({1, 0.3, 0}, 70, {0.0, 0.02, 0.75});
  const Transform turned = truth * pose({0, 0, 1}, 37, {0, 0, 0});
  const std::vector<BopResult> results = {estimate(0, 5, 1.0, turned)};
  Scene sc;
  Symmetries axis;
  axis.continuous = {ContinuousSymmetry{Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()}};
  sc.add_object(5, can, axis);
  sc.add_image(0, {{5, truth}});
  const BopScores s = sc.score(results);
  EXPECT_DOUBLE_EQ(s.total.ar_mssd, 1.0);
  EXPECT_DOUBLE_EQ(s.total.ar_mspd, 1.0);
  EXPECT_GT(s.total.ar_vsd, 0.95);  // the same surface, up to the facets' edges

  // Declared without its symmetry, the turn is an error of 2 r sin(37 / 2) = 25 mm on the rim.
  sc.ds.models.at(5).symmetries_continuous.clear();
  const BopScores plain = sc.score(results);
  EXPECT_LT(plain.total.ar_mssd, 0.8);
  EXPECT_LT(plain.total.ar_mspd, 0.8);
}

TEST(EvalBop, TargetsLimitTheEstimatesAndTheGroundTruths) {
  const TriangleMesh box = make_box_mesh({0.1f, 0.06f, 0.04f});
  const Transform truth = pose({0, 1, 0}, 20, {0.0, 0.0, 0.8});
  Scene sc;
  sc.add_object(2, box);
  sc.add_object(4, make_box_mesh({0.05f, 0.05f, 0.05f}));
  sc.add_image(0, {{2, truth}, {4, pose({1, 0, 0}, 10, {0.15, 0.05, 0.9})}});
  // The best-scored estimate is 30 cm off; the exact one scores less. Object 4 is not estimated.
  const std::vector<BopResult> results = {estimate(0, 2, 0.9, moved(truth, {0.3, 0, 0})), estimate(0, 2, 0.5, truth)};

  const BopScores open = sc.score(results);
  EXPECT_EQ(open.estimates_used, 2);
  EXPECT_EQ(open.total.targets, 2);                 // both objects, in open mode
  EXPECT_DOUBLE_EQ(open.per_object.at(2).ar(), 1.0);  // the wrong one matches nothing, the right one matches
  EXPECT_DOUBLE_EQ(open.per_object.at(4).ar(), 0.0);
  EXPECT_DOUBLE_EQ(open.total.ar(), 0.5);

  BopScoreOptions one;
  one.targets = std::vector<BopTarget>{{1, 0, 2, 1}};  // object 2 only, one instance: the best estimate only
  const BopScores limited = sc.score(results, one);
  EXPECT_TRUE(limited.targets_mode);
  EXPECT_EQ(limited.estimates_used, 1);
  EXPECT_EQ(limited.total.targets, 1);  // object 4 is no target
  EXPECT_EQ(limited.per_object.count(4), 0u);
  EXPECT_DOUBLE_EQ(limited.total.ar(), 0.0);

  BopScoreOptions two;
  two.targets = std::vector<BopTarget>{{1, 0, 2, 2}, {1, 0, 4, 1}};
  const BopScores both = sc.score(results, two);
  EXPECT_EQ(both.estimates_used, 2);
  EXPECT_EQ(both.total.targets, 2);
  EXPECT_DOUBLE_EQ(both.per_object.at(2).ar(), 1.0);

  BopScoreOptions elsewhere;
  elsewhere.targets = std::vector<BopTarget>{{1, 7, 2, 1}};  // another image: nothing here is a target
  const BopScores away = sc.score(results, elsewhere);
  EXPECT_EQ(away.total.targets, 0);
  EXPECT_EQ(away.estimates_used, 0);

  const std::vector<bool> part = results_taking_part(results, one.targets);
  EXPECT_EQ(part, (std::vector<bool>{true, false}));
  EXPECT_EQ(results_taking_part(results, std::nullopt), (std::vector<bool>{true, true}));
}

TEST(EvalBop, InvisibleGroundTruthsAreNeitherTargetsNorMatched) {
  const TriangleMesh box = make_box_mesh({0.1f, 0.06f, 0.04f});
  const Transform hidden = pose({0, 1, 0}, 20, {-0.1, 0.0, 0.8}), seen = pose({1, 0, 0}, -30, {0.1, 0.0, 0.8});
  Scene sc;
  sc.add_object(2, box);
  sc.add_image(0, {{2, hidden}, {2, seen}}, {0.05, 0.8});
  // Exact at the hidden one (best score) and at the seen one.
  const BopScores s = sc.score({estimate(0, 2, 0.9, hidden), estimate(0, 2, 0.5, seen)});
  EXPECT_EQ(s.total.targets, 1);
  EXPECT_DOUBLE_EQ(s.total.ar(), 1.0);
  // The hidden one found alone finds no target.
  const BopScores only_hidden = sc.score({estimate(0, 2, 0.9, hidden)});
  EXPECT_EQ(only_hidden.total.targets, 1);
  EXPECT_DOUBLE_EQ(only_hidden.total.ar(), 0.0);
  // An object without a mesh is named.
  Scene no_mesh = sc;
  no_mesh.meshes.clear();
  test::expect_error([&] { no_mesh.score({}); }, "no model for object 2");
}

}  // namespace
}  // namespace viewpose
