#pragma once
// Scoring pose estimates (BOP19 results) against a dataset's ground truth, as the BOP toolkit does
// for the errors it shares with us: ADD and ADD-S recall at a share of the object's diameter, MSSD
// recall averaged over thresholds, rotation and translation errors, false positives and time.
//
// Pairing, as the BOP toolkit matches. In each image, for each object, the estimates are taken by
// decreasing score; each takes the not yet paired ground-truth instance of its object that is
// nearest under ADD-S, if that is below the threshold (ADD-S is the most lenient of the three). An
// estimate with none is a false positive and takes nothing: a wrong pose of high score does not keep
// a right one from the instance it finds. A ground truth counts as found under ADD (MSSD) when the
// estimate that took it is also within ADD's threshold (MSSD's). A wrong estimate's errors are
// reported against the nearest instance of its object (EstimateOutcome), to say how far off it was. Ground truths less visible than min_visib_fract are not targets: they
// count neither way, nor do estimates that find them. With BOP19 targets (EvalOptions::targets),
// ground truths of objects not listed for their image are not targets either, and only the
// inst_count best estimates of each listed object take part (eval/bop_scores: results_taking_part).
//
// Precision: the estimates counted (all but those that found an invisible ground truth) are sorted
// by score; at each distinct score, those scoring at least that much give a precision (correct under
// ADD-S at correct_fraction, one-to-one as paired above, over counted) and a recall (correct over
// targets): the precision-recall curve over the detection score.
#include <map>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/transform.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"

namespace viewpose {

struct EvalOptions {
  double correct_fraction = 0.1;  ///< ADD and ADD-S: correct below this share of the diameter
  std::vector<double> mssd_fractions = {0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50};  ///< BOP's
  double min_visib_fract = 0.1;   ///< BOP's: less visible ground truths are not targets
  /// Model points used for the errors: the mesh's vertices, thinned evenly to at most this many
  /// (the errors change by well under a millimetre; MSSD with 315 symmetry steps stays fast).
  std::size_t max_model_points = 2000;
  double symmetry_step = 0.01;    ///< continuous symmetries in steps of at most this share of a turn x pi (BOP's)
  std::optional<std::vector<BopTarget>> targets;  ///< BOP19 targets (io/bop: read_bop_targets); none: open mode
};

/// The object's symmetry transforms from models_info.json (identity first), continuous ones in
/// steps as the BOP toolkit discretizes them.
std::vector<Transform> symmetry_transforms(const ModelInfo& info, double step = 0.01);

/// What scoring needs of an object from models_info.json: its diameter (0 when the file does not
/// list the object) and its symmetry transforms (the identity alone when it does not).
struct ObjectScale {
  double diameter_m = 0;
  std::vector<Transform> symmetries;
};
ObjectScale object_scale(const ModelsInfo& models, int obj_id, double symmetry_step = 0.01);

/// One row of the report: an object, a scene, or everything.
struct Score {
  int targets = 0;                   ///< ground truths to find
  int found_add_s = 0, found_add = 0;
  /// ADD(-S), the LINEMOD convention: ADD for objects without symmetries, ADD-S for those with them
  /// (models_info.json), so a symmetric object's equivalent poses are not counted wrong.
  int found_add_or_s = 0;
  double mssd_recall = 0;            ///< mean over the MSSD thresholds of the share found
  int estimates = 0;
  int false_positives = 0;
  /// Of the estimates that are correct under ADD-S: rotation (degrees) and translation (mm) errors.
  double mean_rotation_deg = 0, median_rotation_deg = 0, mean_translation_mm = 0, median_translation_mm = 0;
  double recall_add_s() const { return targets ? static_cast<double>(found_add_s) / targets : 0.0; }
  double recall_add() const { return targets ? static_cast<double>(found_add) / targets : 0.0; }
  double recall_add_or_s() const { return targets ? static_cast<double>(found_add_or_s) / targets : 0.0; }
};

/// What became of one estimate.
struct EstimateOutcome {
  bool in_split = false;   ///< its image is in the dataset's split
  bool taking_part = true; ///< false: beyond the targets (an object not listed, or past inst_count)
  bool counted = false;    ///< counted among the estimates (Score::estimates)
  bool paired = false;     ///< it was paired with a ground truth of its object
  bool target = false;     ///< ...that is a target (visible enough)
  double add_s_m = -1, add_m = -1, mssd_m = -1;  ///< errors against the pair (-1: none)
  bool correct_add_s = false, correct_add = false;
};

/// One point of the precision-recall curve: the estimates scoring at least `score`.
struct PrecisionRecallPoint {
  double score = 0;
  int estimates = 0;  ///< counted estimates at or above the score
  int correct = 0;    ///< of them, correct under ADD-S and paired with a target
  double recall = 0, precision = 0;
};

struct EvalReport {
  std::map<int, Score> per_object;  ///< by obj_id
  std::map<int, Score> per_scene;   ///< by scene_id
  Score total;
  int images = 0;                   ///< images in the split
  int images_timed = 0;             ///< images with a time in the results
  double mean_time_s = 0;           ///< over the timed images
  int ignored_estimates = 0;        ///< estimates for images or objects the dataset does not have
  int beyond_targets = 0;           ///< estimates in the split left out by the targets
  /// One point per distinct score of the counted estimates, by decreasing score; the last one is
  /// the whole report's (recall_add_s, and precision = 1 - false_positives / estimates).
  std::vector<PrecisionRecallPoint> pr_curve;
  double false_positives_per_image() const { return images ? static_cast<double>(total.false_positives) / images : 0.0; }
  std::vector<EstimateOutcome> estimates;  ///< one per result, in the order given
};

/// `model_points`: per obj_id, the model's points in metres (object frame). Throws viewpose::Error
/// when an object with ground truth or estimates has no model or no diameter.
EvalReport evaluate(const BopDataset& dataset, const std::map<int, std::vector<Eigen::Vector3f>>& model_points,
                    std::span<const BopResult> results, const EvalOptions& options = {});

}  // namespace viewpose
