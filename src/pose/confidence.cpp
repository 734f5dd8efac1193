#include "viewpose/pose/confidence.hpp"

#include <algorithm>
#include <cmath>

#include "viewpose/render/sensor_model.hpp"

namespace viewpose {

const std::array<std::string_view, kConfidenceFeatures>& confidence_feature_names() {
  static const std::array<std::string_view, kConfidenceFeatures> names = {
      "inlier_fraction", "conflict_fraction", "unmeasured_fraction", "cluster_explained", "model_support",
      "visible_fraction", "outline_continuation", "log_plane_over_model_rms", "model_rms_in_sigmas",
      "model_relief_in_sigmas", "log10_inliers"};
  return names;
}

ConfidenceFeatures confidence_features(const Verification& v) {
  // The sensor's noise where the pose lies: residuals and relief in its units mean the same at 0.6 m
  // as at 3 m.
  const double sigma = axial_noise_sigma_frontal(std::max(0.3, v.mean_depth_m));
  const double tiny = 1e-5;  // 10 micrometres: below any residual a real sensor gives
  return {v.inlier_fraction,
          v.conflict_fraction,
          v.unmeasured_fraction,
          // A pose beside a touching neighbour is judged on the points within its silhouette: the
          // neighbour's are no evidence against it (VerifyOptions::min_footprint_explained).
          v.explained_beside_neighbour ? v.footprint_explained : v.cluster_explained,
          v.model_support,
          v.visible_fraction,
          v.outline_continuation,
          std::clamp(std::log(std::max(v.plane_rms_m, tiny) / std::max(v.model_rms_m, tiny)), -3.0, 3.0),
          std::min(10.0, v.model_rms_m / sigma),
          std::min(10.0, v.model_relief_m / sigma),
          std::log10(1.0 + static_cast<double>(v.inliers))};
}

double ConfidenceModel::probability(const ConfidenceFeatures& f) const {
  double t = bias;
  for (std::size_t i = 0; i < f.size(); ++i) t += weights[i] * f[i];
  return 1.0 / (1.0 + std::exp(-t));
}

const ConfidenceModel& default_confidence_model() {
  // make confidence (scripts/confidence-data.sh, scripts/fit-confidence.py) on 10,969 poses that passed verification (5,706 right) in simulated
  // rooms and clutter: the built-in shapes and five HOPE objects among unknown ones, walls, furniture
  // (docs/CONFIDENCE.md has the commands, the fit's numbers and the check on real frames).
  static const ConfidenceModel model{-43.3882,
                                     {5.57125, -5.57125, 0.416692, 15.7456, 12.7045, 3.33464, -4.71968, 3.60405,
                                      -0.427686, -0.20812, 2.87572}};
  return model;
}

double pose_confidence(const Verification& v) { return default_confidence_model().probability(confidence_features(v)); }

}  // namespace viewpose
