#pragma once
// BOP's Average Recall (Hodan et al., "BOP Challenge 2019/2020"), computed as the BOP toolkit
// (bop_toolkit_lib: pose_error, visibility, pose_matching, score) computes it, so that our numbers
// stand beside published ones:
//
//   VSD   visible surface discrepancy: the model's depth is drawn at the estimate and at the truth,
//         the parts of each visible in the test depth are found (tolerance delta), and e is the share
//         of their union where the two surfaces are farther apart than tau or only one is visible.
//   MSSD  maximum symmetry-aware surface distance (eval/metrics: mssd_error).
//   MSPD  maximum symmetry-aware projection distance, in pixels (eval/metrics: mspd_error).
//
// Errors are computed for each estimate against every ground truth of its object in its image. For
// every error type and threshold (and every tau of VSD) separately, the estimates of each image and
// object are matched greedily by decreasing score, each to the unmatched valid ground truth with the
// lowest error below the threshold. Recall is matched valid ground truths over valid ground truths;
// AR_VSD, AR_MSSD and AR_MSPD are the recalls' means over the thresholds (and taus), AR their mean.
//
// A valid ground truth is visible enough (visib_fract >= 0.1; all are when scene_gt_info.json is
// absent) and, with a BOP19 targets file, of an object listed for its image. With targets, only the
// inst_count best estimates of each listed object in each image take part; without (open mode),
// every estimate does.
//
// Where we differ from the toolkit, knowingly: a continuous symmetry's turns include the identity
// (core/symmetry: symmetry_transforms; the toolkit takes the 314 turns after it), so a perfect
// estimate of a can scores an MSSD of 0 where the toolkit gives at most one turn's (1.1 degrees)
// worth; and depth is drawn by our rasterizer at pixel centres, not by the toolkit's OpenGL.
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"

namespace viewpose {

/// 0.05, 0.10, ..., 0.50: BOP19's VSD taus and thresholds, and its MSSD fractions of the diameter.
std::vector<double> bop_fractions();

struct BopScoreOptions {
  double vsd_delta_m = 0.015;  ///< VSD visibility tolerance: BOP19's 15 mm (ITODD: 5 mm)
  /// VSD misalignment tolerances tau as fractions of the object's diameter: the toolkit divides the
  /// surface distances by the diameter before comparing them with tau (normalized_by_diameter), so
  /// these are 5 % to 50 % of the diameter, not 5 to 50 mm as issue 17 first read them.
  std::vector<double> vsd_taus = bop_fractions();
  std::vector<double> vsd_thresholds = bop_fractions();  ///< correct when e is below
  std::vector<double> mssd_fractions = bop_fractions();  ///< correct below this share of the diameter
  /// MSPD: correct below these many pixels times r = image width / 640 (BOP19: 5, 10, ..., 50).
  std::vector<double> mspd_px = {5, 10, 15, 20, 25, 30, 35, 40, 45, 50};
  double min_visib_fract = 0.1;  ///< BOP19's: less visible ground truths are not valid
  double symmetry_step = 0.01;   ///< continuous symmetries in ceil(pi / step) turns, as the toolkit
  /// BOP19 targets (io/bop: read_bop_targets); none: open mode.
  std::optional<std::vector<BopTarget>> targets;
  /// How an image's depth and intrinsics are read; load_bop_frame when empty (tests give frames
  /// made in memory).
  std::function<BopFrame(const BopImage&)> load_frame;
};

/// Recall of one row (an object, a scene, or everything) under the three errors.
struct BopRecall {
  int targets = 0;               ///< valid ground truths
  std::vector<int> found_vsd;    ///< matched, per tau and threshold: [tau * thresholds + threshold]
  std::vector<int> found_mssd;   ///< matched, per threshold
  std::vector<int> found_mspd;   ///< matched, per threshold
  double ar_vsd = 0, ar_mssd = 0, ar_mspd = 0;
  double ar() const { return (ar_vsd + ar_mssd + ar_mspd) / 3.0; }
};

struct BopScores {
  std::map<int, BopRecall> per_object;  ///< by obj_id, every object with valid ground truth
  std::map<int, BopRecall> per_scene;   ///< by scene_id
  BopRecall total;
  bool targets_mode = false;  ///< a targets file restricted the ground truths and estimates
  int images = 0;             ///< images in the split
  int estimates_used = 0;     ///< estimates that took part in the matching
  double mspd_scale = 1.0;    ///< r = image width / 640 of the first image (the thresholds' scale)
};

/// Which results take part under BOP19 targets: for each image and listed object, its inst_count
/// results of highest score (ties: the first given); results for objects not listed take no part.
/// Without targets every result takes part.
std::vector<bool> results_taking_part(std::span<const BopResult> results,
                                      const std::optional<std::vector<BopTarget>>& targets);

/// A model's surface drawn at a pose inside the window of the image its bounding box projects to:
/// distances from the camera centre along each pixel's ray (not depth along z), metres, NaN where
/// the model is not drawn. Pixels outside the window have no surface.
struct DistanceWindow {
  int u0 = 0, v0 = 0, width = 0, height = 0;  ///< the window's first column and row in the image, size
  std::vector<float> distance_m;              ///< width * height, row-major
  /// The distance at image pixel (u, v); NaN outside the window.
  float at(int u, int v) const;
  /// Whether the two windows share a pixel.
  bool overlaps(const DistanceWindow& other) const;
};
/// The window alone (distance_m left empty): where render_distance would draw.
DistanceWindow projected_window(const TriangleMesh& mesh, const Transform& T_camera_object, const CameraIntrinsics& K);
DistanceWindow render_distance(const TriangleMesh& mesh, const Transform& T_camera_object, const CameraIntrinsics& K,
                               int closed_winding = 0);

/// The test image's depth at pixel (u, v) as a distance along the ray; NaN where missing.
double depth_to_distance(double z, int u, int v, const CameraIntrinsics& K);

/// VSD errors (cost 'step') of an estimate against a ground truth, one per tau (fractions of
/// `diameter_m`), from the test depth (metres along z, NaN or 0 where missing) and the two drawings.
std::vector<double> vsd_errors(const DepthImage& test_depth, const CameraIntrinsics& K, const DistanceWindow& estimate,
                               const DistanceWindow& truth, double delta_m, std::span<const double> taus,
                               double diameter_m);

/// Scores `results` against the dataset. `meshes`: per obj_id, the model in metres (object frame),
/// drawn for VSD and whose vertices are the points of MSSD and MSPD (the toolkit uses models_eval/
/// when a dataset has it). Diameters and symmetries come from models_info.json (the diameter from
/// the mesh when missing). Throws viewpose::Error when an object with valid ground truth or an
/// estimate taking part has no mesh. Images are scored in parallel; the result does not depend on
/// the thread count.
BopScores score_bop(const BopDataset& dataset, const std::map<int, TriangleMesh>& meshes,
                    std::span<const BopResult> results, const BopScoreOptions& options = {});

}  // namespace viewpose
