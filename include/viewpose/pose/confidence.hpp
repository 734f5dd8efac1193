#pragma once
// How likely a verified pose is right: a logistic model over verification's evidence, so that a
// detection's score is a probability a robot can set a threshold on. The evidence is what
// verification measures (pose/verify.hpp), made comparable across distances by the sensor's noise
// there. The weights are fit by scripts/fit-confidence.py on hypotheses that passed verification
// in simulated rooms and clutter, labelled against their ground truth (viewpose bop --hypotheses),
// and checked on real frames; docs/CONFIDENCE.md says on what, and how well it is calibrated.
#include <array>
#include <cstddef>
#include <string_view>

#include "viewpose/pose/verify.hpp"

namespace viewpose {

inline constexpr std::size_t kConfidenceFeatures = 11;
using ConfidenceFeatures = std::array<double, kConfidenceFeatures>;

/// The features, in the order of confidence_features(): inlier, conflict and unmeasured fractions,
/// cluster explained, model support, visible fraction, outline continuation, log of the observed
/// surface's RMS about its best plane over its RMS about the model, that RMS and the model's relief
/// in units of the sensor's noise at the pose's depth, and log10 of the inlier pixels.
const std::array<std::string_view, kConfidenceFeatures>& confidence_feature_names();
ConfidenceFeatures confidence_features(const Verification& v);

/// p = 1 / (1 + exp(-(bias + weights . features))).
struct ConfidenceModel {
  double bias = 0;
  ConfidenceFeatures weights{};
  double probability(const ConfidenceFeatures& features) const;
};

/// The model fit by scripts/fit-confidence.py (its numbers are pasted into confidence.cpp).
const ConfidenceModel& default_confidence_model();

/// The default model's probability that the verified pose `v` is right.
double pose_confidence(const Verification& v);

}  // namespace viewpose
