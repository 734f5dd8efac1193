// The confidence model against cases whose answer is known: a pose that is plainly right, and the
// same evidence made weaker one cue at a time, must order as the evidence says.
#include <cmath>

#include "test_support.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/render/sensor_model.hpp"

namespace viewpose {
namespace {

// What verification reports of the jug at its true pose 0.9 m away in a noisy frame (measured by the
// Verify tests' scene with the sensor model on), written out so that this test needs no rendering.
Verification plainly_right() {
  Verification v;
  v.accepted = true;
  v.mean_depth_m = 0.9;
  v.inlier_fraction = 0.995;
  v.conflict_fraction = 0.003;
  v.unmeasured_fraction = 0.01;
  v.cluster_explained = 0.99;
  v.model_support = 0.99;
  v.visible_fraction = 0.97;
  v.outline_continuation = 0.1;
  v.model_rms_m = 1.3 * axial_noise_sigma_frontal(0.9);
  v.plane_rms_m = 0.012;
  v.model_relief_m = 0.012;
  v.inliers = 15000;
  v.score = v.inlier_fraction * v.cluster_explained;
  return v;
}

TEST(Confidence, FeaturesAreWhatVerificationMeasuredInTheSensorsUnits) {
  const Verification v = plainly_right();
  const ConfidenceFeatures f = confidence_features(v);
  ASSERT_EQ(confidence_feature_names().size(), f.size());
  EXPECT_EQ(confidence_feature_names()[0], "inlier_fraction");
  EXPECT_DOUBLE_EQ(f[0], v.inlier_fraction);
  EXPECT_DOUBLE_EQ(f[4], v.model_support);
  EXPECT_NEAR(f[7], std::log(0.012 / v.model_rms_m), 1e-12);
  EXPECT_NEAR(f[8], 1.3, 1e-12);
  EXPECT_NEAR(f[9], 0.012 / axial_noise_sigma_frontal(0.9), 1e-12);
  EXPECT_NEAR(f[10], std::log10(15001.0), 1e-12);
  // No residual at all (a noise-free frame) is a large but finite ratio, not an infinity.
  Verification exact = v;
  exact.model_rms_m = 0;
  EXPECT_TRUE(std::isfinite(confidence_features(exact)[7]));
}

// An object beside a touching neighbour (VerifyOptions::min_footprint_explained) is judged on the
// cluster's points within its silhouette: the neighbour's points beside it are no evidence against.
TEST(Confidence, APoseBesideANeighbourWeighsThePointsWithinItsSilhouette) {
  Verification beside = plainly_right();
  beside.cluster_explained = 0.6;
  beside.cluster_beside = 0.39;
  beside.footprint_explained = 0.6 / 0.61;
  const double as_measured = pose_confidence(beside);
  beside.explained_beside_neighbour = true;
  EXPECT_DOUBLE_EQ(confidence_features(beside)[3], beside.footprint_explained);
  EXPECT_GT(pose_confidence(beside), as_measured);
  Verification whole = plainly_right();
  whole.cluster_explained = beside.footprint_explained;
  EXPECT_DOUBLE_EQ(pose_confidence(beside), pose_confidence(whole));
}

TEST(Confidence, IsAProbabilityThatFollowsTheEvidence) {
  const Verification right = plainly_right();
  const double p = pose_confidence(right);
  EXPECT_GT(p, 0.95);
  EXPECT_LE(p, 1.0);
  // Each cue made weaker lowers the confidence.
  const auto lower = [&](auto change) {
    Verification v = right;
    change(v);
    return pose_confidence(v);
  };
  EXPECT_LT(lower([](Verification& v) { v.cluster_explained = 0.75; }), p);
  EXPECT_LT(lower([](Verification& v) { v.model_support = 0.6; }), p);
  EXPECT_LT(lower([](Verification& v) { v.outline_continuation = 0.9; }), p);
  EXPECT_LT(lower([](Verification& v) { v.plane_rms_m = v.model_rms_m; }), p);  // a plane explains it as well
  EXPECT_LT(lower([](Verification& v) { v.inliers = 300; }), p);                // little evidence
  // A patch of background: little of the model on the cluster, the outline carrying on, a plane as
  // good as the model, a few hundred pixels: below the default threshold.
  Verification patch = right;
  patch.model_support = 0.75;
  patch.outline_continuation = 0.8;
  patch.plane_rms_m = 0.8 * patch.model_rms_m;
  patch.model_relief_m = 0.002;
  patch.inliers = 800;
  patch.visible_fraction = 0.7;
  EXPECT_LT(pose_confidence(patch), 0.5);
}

TEST(Confidence, TheModelIsTheLogisticOfItsWeights) {
  ConfidenceModel m;
  m.bias = 0.5;
  m.weights[3] = 2.0;
  ConfidenceFeatures f{};
  f[3] = 1.0;
  EXPECT_NEAR(m.probability(f), 1.0 / (1.0 + std::exp(-2.5)), 1e-15);
  EXPECT_NEAR(ConfidenceModel{}.probability(f), 0.5, 1e-15);
}

}  // namespace
}  // namespace viewpose
