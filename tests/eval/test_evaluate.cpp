// Scoring against known answers: estimates placed at chosen errors from the truth.
#include <numbers>

#include <Eigen/Geometry>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/eval/evaluate.hpp"
#include "viewpose/eval/metrics.hpp"

namespace viewpose {
namespace {

Transform turn(const Eigen::Vector3d& axis, double deg, const Eigen::Vector3d& t = Eigen::Vector3d::Zero()) {
  return make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix(), t);
}

// The 8 corners of a 0.2 x 0.1 x 0.05 m box: diameter = its diagonal.
std::vector<Eigen::Vector3f> box_corners() {
  std::vector<Eigen::Vector3f> c;
  for (float x : {-0.1f, 0.1f})
    for (float y : {-0.05f, 0.05f})
      for (float z : {-0.025f, 0.025f}) c.emplace_back(x, y, z);
  return c;
}

TEST(Metrics, MssdIsTheLargestDistanceAtTheBestSymmetry) {
  const auto pts = box_corners();
  const Transform truth = turn({1, 2, 3}, 40, {0.1, 0.0, 1.0});
  const Transform shifted = truth * make_transform(Eigen::Matrix3d::Identity(), {0.0, 0.004, 0.0});
  EXPECT_NEAR(mssd_error(shifted, truth, pts, {}), 0.004, 1e-9);
  // Half a turn about z: each corner moves to the opposite one in x and y, 2 * |(0.1, 0.05)|.
  const Transform flipped = truth * turn(Eigen::Vector3d::UnitZ(), 180);
  EXPECT_NEAR(mssd_error(flipped, truth, pts, {}), 2 * std::hypot(0.1, 0.05), 1e-6);
  const std::vector<Transform> syms = {Transform::Identity(), turn(Eigen::Vector3d::UnitZ(), 180)};
  EXPECT_NEAR(mssd_error(flipped, truth, pts, syms), 0.0, 1e-6);
  EXPECT_NEAR(rotation_error_deg(flipped.linear(), truth.linear()), 180.0, 1e-6);
  EXPECT_NEAR(rotation_error_deg(turn({0, 1, 0}, 7).linear(), Eigen::Matrix3d::Identity()), 7.0, 1e-9);
}

TEST(Evaluate, SymmetryTransformsFollowTheBopToolkit) {
  ModelInfo info;
  EXPECT_EQ(symmetry_transforms(info).size(), 1u);  // the identity alone
  info.symmetries_discrete = {turn(Eigen::Vector3d::UnitX(), 180)};
  EXPECT_EQ(symmetry_transforms(info).size(), 2u);
  info.symmetries_continuous = {ContinuousSymmetry{Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0, 0, 0.01)}};
  const auto all = symmetry_transforms(info, 0.01);
  ASSERT_EQ(all.size(), 315u * 2u);  // ceil(pi / 0.01) steps, each with both discrete ones
  // Every one keeps a point on the axis (the offset) where it is, and is a rotation about z (or
  // that combined with the half turn about x).
  for (const Transform& S : all) {
    const Eigen::Vector3d on_axis(0, 0, 0.01);
    const Eigen::Vector3d moved = S * on_axis;
    EXPECT_NEAR(std::abs(moved.z() - 0.01) < 1e-9 || std::abs(moved.z() + 0.01) < 1e-9, 1, 0);
  }
}

// A dataset of one scene with `gt` in each image; images numbered from 0.
BopDataset dataset_with(const std::vector<std::vector<GroundTruthPose>>& gt, double diameter) {
  BopDataset ds;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    BopImage im;
    im.scene_id = 1;
    im.im_id = static_cast<int>(i);
    im.gt = gt[i];
    ds.images.push_back(im);
  }
  ModelInfo info;
  info.diameter_m = diameter;
  ds.models[7] = info;
  return ds;
}

// As the BOP toolkit matches: a wrong pose of high score takes nothing, so the right one of lower
// score still finds the instance (paired by nearest regardless, the wrong one would have used it up).
TEST(Evaluate, AWrongPoseOfHighScoreDoesNotHideARightOne) {
  const auto pts = box_corners();
  const double d = 2 * Eigen::Vector3d(0.1, 0.05, 0.025).norm();
  const Transform a = turn({0, 1, 0}, 30, {0.0, 0.0, 1.0});
  const BopDataset ds = dataset_with({{{7, a}}}, d);
  const std::vector<BopResult> results = {
      {1, 0, 7, 0.9, a * make_transform(Eigen::Matrix3d::Identity(), {0.3 * d, 0, 0}), 0.02},  // 30 % off: wrong
      {1, 0, 7, 0.5, a, 0.02},                                                                // right
  };
  const EvalReport r = evaluate(ds, {{7, pts}}, results);
  EXPECT_EQ(r.total.targets, 1);
  EXPECT_EQ(r.total.found_add_s, 1);
  EXPECT_EQ(r.total.found_add, 1);
  EXPECT_EQ(r.total.false_positives, 1);
  EXPECT_FALSE(r.estimates[0].correct_add_s);
  EXPECT_TRUE(r.estimates[0].paired);
  EXPECT_NEAR(r.estimates[0].add_m, 0.3 * d, 1e-9);
  EXPECT_TRUE(r.estimates[1].correct_add_s);
  ASSERT_EQ(r.pr_curve.size(), 2u);
  EXPECT_DOUBLE_EQ(r.pr_curve[0].precision, 0.0);
  EXPECT_DOUBLE_EQ(r.pr_curve[1].recall, 1.0);
  EXPECT_DOUBLE_EQ(r.pr_curve[1].precision, 0.5);
}

TEST(Evaluate, RecallFalsePositivesAndErrorsOnKnownEstimates) {
  const auto pts = box_corners();
  const double d = 2 * Eigen::Vector3d(0.1, 0.05, 0.025).norm();
  const Transform a = turn({0, 1, 0}, 30, {0.0, 0.0, 1.0}), b = turn({1, 0, 0}, -20, {0.2, 0.0, 1.2});
  const Transform c = turn({1, 1, 0}, 60, {-0.2, 0.1, 0.9});
  // Image 0: two instances; image 1: one; image 2: one, never estimated.
  BopDataset ds = dataset_with({{{7, a}, {7, b}}, {{7, c}}, {{7, a}}}, d);
  const auto shift = [](const Transform& T, double metres) { return T * make_transform(Eigen::Matrix3d::Identity(), {metres, 0, 0}); };
  std::vector<BopResult> results = {
      {1, 0, 7, 0.9, a, 0.020},                                   // exact
      {1, 0, 7, 0.8, shift(b, 0.07 * d), 0.020},                  // 7 % off: correct at 10 %, MSSD below 0.10 d only
      {1, 1, 7, 0.9, c * turn(Eigen::Vector3d::UnitZ(), 180), 0.040},  // a half turn: ADD-S right, ADD wrong
      {1, 1, 7, 0.5, shift(c, 0.5), 0.040},                       // a second estimate, nothing left to find: FP
      {1, 9, 7, 0.9, a, 0.5},                                     // an image not in the split: ignored
  };
  const std::map<int, std::vector<Eigen::Vector3f>> models = {{7, pts}};
  const EvalReport r = evaluate(ds, models, results);
  EXPECT_EQ(r.images, 3);
  EXPECT_EQ(r.ignored_estimates, 1);
  EXPECT_EQ(r.images_timed, 2);
  EXPECT_NEAR(r.mean_time_s, 0.030, 1e-12);
  const Score& s = r.total;
  EXPECT_EQ(s.targets, 4);
  EXPECT_EQ(s.found_add_s, 3);  // box corners: the half turn about z maps the corner set onto itself
  EXPECT_EQ(s.found_add, 2);
  EXPECT_EQ(s.estimates, 4);
  EXPECT_EQ(s.false_positives, 1);
  // MSSD without symmetries: the exact one at all 10 thresholds, the 7 % one at the 9 from 0.10 up,
  // the half turn at none: (10 + 9) / 10 / 4 targets.
  EXPECT_NEAR(s.mssd_recall, 19.0 / 40.0, 1e-12);
  EXPECT_NEAR(s.median_translation_mm, 0.0, 1e-6);  // errors of 0, 0.07 d and 0 mm
  EXPECT_NEAR(s.mean_translation_mm, 1000 * 0.07 * d / 3, 1e-6);
  EXPECT_NEAR(s.mean_rotation_deg, 60.0, 1e-6);     // 0, 0 and 180 degrees
  EXPECT_EQ(r.per_object.at(7).targets, 4);
  ASSERT_EQ(r.estimates.size(), results.size());
  EXPECT_TRUE(r.estimates[0].correct_add && r.estimates[0].correct_add_s);
  EXPECT_NEAR(r.estimates[1].add_m, 0.07 * d, 1e-9);
  EXPECT_TRUE(r.estimates[2].correct_add_s && !r.estimates[2].correct_add);
  // The second estimate finds nothing left; its errors are against the instance of its kind that is there.
  EXPECT_TRUE(r.estimates[3].paired);
  EXPECT_FALSE(r.estimates[3].correct_add_s);
  EXPECT_GT(r.estimates[3].add_s_m, 0.1 * d);
  EXPECT_FALSE(r.estimates[4].in_split);
  ASSERT_EQ(r.per_scene.size(), 1u);

  EXPECT_EQ(s.found_add_or_s, 2);  // no symmetries declared: ADD

  // Precision over the score: 0.9 (two, both right), 0.8 (right), 0.5 (the false positive).
  ASSERT_EQ(r.pr_curve.size(), 3u);
  EXPECT_EQ(r.pr_curve[0].score, 0.9);
  EXPECT_EQ(r.pr_curve[0].estimates, 2);
  EXPECT_EQ(r.pr_curve[0].correct, 2);
  EXPECT_DOUBLE_EQ(r.pr_curve[0].recall, 0.5);
  EXPECT_DOUBLE_EQ(r.pr_curve[0].precision, 1.0);
  EXPECT_DOUBLE_EQ(r.pr_curve[1].recall, 0.75);
  EXPECT_DOUBLE_EQ(r.pr_curve[1].precision, 1.0);
  EXPECT_EQ(r.pr_curve[2].score, 0.5);
  EXPECT_DOUBLE_EQ(r.pr_curve[2].recall, 0.75);  // the whole report's
  EXPECT_DOUBLE_EQ(r.pr_curve[2].precision, 0.75);
  EXPECT_DOUBLE_EQ(r.false_positives_per_image(), 1.0 / 3.0);
  EXPECT_TRUE(r.estimates[3].counted);
  EXPECT_FALSE(r.estimates[4].counted);

  // BOP19 targets: image 1 asks for one instance (its best estimate only), image 2 for none.
  EvalOptions with_targets;
  with_targets.targets = std::vector<BopTarget>{{1, 0, 7, 2}, {1, 1, 7, 1}};
  const EvalReport t = evaluate(ds, models, results, with_targets);
  EXPECT_EQ(t.total.targets, 3);  // image 2's is not listed
  EXPECT_EQ(t.total.found_add_s, 3);
  EXPECT_EQ(t.total.estimates, 3);
  EXPECT_EQ(t.total.false_positives, 0);  // the second estimate of image 1 takes no part
  EXPECT_EQ(t.beyond_targets, 1);
  EXPECT_EQ(t.ignored_estimates, 1);
  EXPECT_FALSE(t.estimates[3].taking_part);
  EXPECT_TRUE(t.estimates[3].in_split);
  EXPECT_DOUBLE_EQ(t.pr_curve.back().precision, 1.0);

  // Declared symmetric about z, the half turn is right under MSSD and ADD(-S) too.
  ds.models[7].symmetries_discrete = {turn(Eigen::Vector3d::UnitZ(), 180)};
  const EvalReport symmetric = evaluate(ds, models, results);
  EXPECT_NEAR(symmetric.total.mssd_recall, 29.0 / 40.0, 1e-12);
  EXPECT_EQ(symmetric.total.found_add_or_s, 3);
  EXPECT_EQ(symmetric.total.found_add, 2);
}

TEST(Evaluate, InvisibleGroundTruthIsNoTargetAndMissingModelsAreAnError) {
  const auto pts = box_corners();
  const Transform a = turn({0, 1, 0}, 30, {0.0, 0.0, 1.0});
  BopDataset ds = dataset_with({{{7, a}}}, 0.2);
  ds.images[0].gt_info = {GroundTruthInfo{}};
  ds.images[0].gt_info[0].visib_fract = 0.05;
  const std::vector<BopResult> found = {{1, 0, 7, 0.9, a, 0.01}};
  const EvalReport r = evaluate(ds, {{7, pts}}, found);
  EXPECT_EQ(r.total.targets, 0);
  EXPECT_EQ(r.total.false_positives, 0);
  EXPECT_EQ(r.total.estimates, 0);
  EXPECT_THROW(evaluate(ds, {}, found), Error);
}

}  // namespace
}  // namespace viewpose
