#pragma once
// Hypothesis verification by rendering: the model is drawn at the hypothesized pose into the
// camera and compared with the observed depth, pixel by pixel, within a tolerance that grows with
// the sensor's noise at that depth.
//   inlier:   the observed surface is where the model says it is
//   conflict: the observed surface is *behind* the model: the camera sees through where the model
//             would be (free space), which a correct pose cannot explain
//   occluded: the observed surface is in front of the model: something hides it; no evidence,
//             unless the something is the cluster being explained (hidden_by_cluster: a conflict)
//   unknown:  no measurement at that pixel; no evidence
// and the scene cluster must be explained by the model in turn. These are the cues PCL's GHV meant
// to weigh (explained scene points, visible model outliers, clutter, occlusion), for one
// hypothesis at a time, without GHV's inverted normal filter.
#include <optional>
#include <span>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

struct VerifyOptions {
  float base_tolerance_m = 0.005f;  ///< tolerance = base + noise_factor * sensor sigma at that depth
  float noise_factor = 2.5f;
  /// ... but never more than this: past it the sensor's noise is larger than the shapes it is to
  /// tell apart (at 3.5 m a Kinect's 2.5 sigma is 5 cm, the depth of a jug), and a tolerance that
  /// kept growing let a flat patch of a far wall pass for any object.
  float max_tolerance_m = 0.02f;
  /// Poses whose judged surface lies farther than this on average get no verdict: a Kinect or
  /// Xtion's depth there is noise of centimetres in steps of 4 cm (docs/SENSOR_MODEL.md).
  double max_depth_m = 3.5;
  /// A pose whose visible surface is flat (its relief below this many sensor sigmas at its depth)
  /// has nothing inside its outline to tell it from a patch of any flat surface, a box face from a
  /// wall: its outline must then say it. At most this share of that outline may carry on at the
  /// model's depth (measured: box faces seen alone on real desk and simulated walls carry on over
  /// 74-100 %, right poses of flat-looking objects under 60 %, docs/CONFIDENCE.md).
  double flat_relief_sigmas = 2.0;
  double max_flat_outline_continuation = 0.6;
  int edge_margin_px = 2;           ///< model pixels this close to its outline or a depth step are not judged
  double min_inlier_fraction = 0.7;    ///< of the model's judged pixels that are not occluded
  /// Where the camera sees through the model (free space) a correct pose has almost nothing: the
  /// tolerance already allows 2.5 sigma of noise. On the simulated seed experiment every detection
  /// with 9 to 15 % conflicts was the jug the wrong way round (ADD-S at the 10 % limit, ADD failing);
  /// with 5 % those are refused and the right way found instead (docs/RESULTS.md).
  double max_conflict_fraction = 0.05;
  double min_cluster_explained = 0.7;  ///< of the scene cluster's points
  /// An object touching something unknown (a box with a mug against it) shares a cluster with it,
  /// and explains only its own part. Such a pose meets the cluster bound all the same when the
  /// cluster's points it leaves unexplained all lie beside it, outside its silhouette (by more than
  /// beside_margin_px): of the points within its silhouette at least min_footprint_explained (and
  /// at least min_cluster_explained) are on its surface, of the whole cluster at least
  /// min_cluster_explained_beside, and at most max_beside_outline_continuation of its outline
  /// carries on at its depth (the neighbour meets it on one side; a model fitted to a patch of a
  /// larger thing has that thing carrying on all round it). Measured, poses that passed every other
  /// bound (make results' sets, the real negatives): right ones 0.96-0.99 within the silhouette and
  /// 0.16-0.28 of the outline carried on; wrong ones at most 0.93, or 0.46-0.87 carried on.
  /// 0: off (the cluster bound as it was).
  double min_footprint_explained = 0.95;
  double min_cluster_explained_beside = 0.3;
  double max_beside_outline_continuation = 0.5;
  int beside_margin_px = 3;
  /// Of the model's inlier pixels (where the observed surface is the model's), at least this share
  /// must belong to the cluster: a small patch of clutter that a curved model happens to fit, with
  /// the rest of the model lying on other things, is not an object. Measured in pixels, so it does
  /// not depend on how densely the sensor samples at that distance.
  double min_model_support = 0.5;
  /// At least this share of the model's outline must be seen matching (not hidden, not unmeasured):
  /// a global descriptor says little about an object mostly out of sight, and such hypotheses were
  /// the false positives on real clutter (measured: true detections 0.57 to 1.0, clutter 0.09, 0.37).
  double min_visible_fraction = 0.4;
  /// At most this share of the model's unhidden pixels may have no measurement. Off (1) by default:
  /// dark and shiny objects return little depth. The recognizer tightens it for parts of split
  /// clusters, where a small patch is weaker evidence (RecognizerOptions::part_max_unmeasured_fraction).
  double max_unmeasured_fraction = 1.0;
  /// Model pixels hidden by the scene cluster itself count as conflicts: a pose cannot put the
  /// object behind the very surface it is to explain. Hidden by anything else is occlusion.
  bool cluster_cannot_hide_model = true;
  std::size_t min_inliers = 150;  ///< in the camera's pixels
  /// Where the model's window would cover more pixels than this, it is drawn and judged on every
  /// s-th pixel of every s-th row (the smallest s that fits): the fractions are estimated from an
  /// even sample, and the time per hypothesis stops growing with the camera's resolution and the
  /// object's nearness (an object at 0.6 m seen with a 1067 px focal length covers 11 times the
  /// pixels of one at 1 m with 525). Counts are reported in the camera's pixels all the same.
  std::size_t max_judged_pixels = 40000;
  /// The cheapest test first: before the model is drawn, up to `quick_points` of its points (evenly
  /// spread, all sides) are projected into the frame, and a pose the camera sees past at more than
  /// this share of the points it judges is refused there (seen_through). The full test refuses at a
  /// conflict share of max_conflict_fraction (0.05; near misses 0.15), counting more as conflicts
  /// than the quick share does; measured over 60,000 poses verified on the real YCB-Video frames and
  /// the simulated rooms and seed experiment, no pose that passed either bound had a quick share
  /// above 0.46, while 41-45 % of those tried on real frames and rooms lay above 0.5, each refused
  /// at a hundredth of the cost of drawing it. 1 (or more): never refused quickly.
  double quick_max_seen_through = 0.5;
  std::size_t quick_points = 512;
  std::size_t quick_min_judged = 40;  ///< fewer points judged than this: no quick verdict
};

struct Verification {
  bool accepted = false;
  double mean_depth_m = 0;  ///< mean model depth over the judged pixels
  double score = 0;  ///< inlier fraction x cluster explained, in [0, 1]
  double inlier_fraction = 0;
  double conflict_fraction = 0;
  double cluster_explained = 0;
  /// Of the cluster's points, the share that lie beside the model: unexplained, and farther than
  /// VerifyOptions::beside_margin_px from its silhouette (a touching neighbour's, not the model's).
  double cluster_beside = 0;
  /// cluster_explained of the cluster's points within the model's silhouette: those not beside it.
  double footprint_explained = 0;
  /// The cluster bound was met only by the footprint: a touching neighbour's points are left over
  /// (VerifyOptions::min_footprint_explained). Confidence then weighs footprint_explained.
  bool explained_beside_neighbour = false;
  double model_support = 0;  ///< share of the model's inlier pixels that the cluster covers
  double visible_fraction = 0;  ///< inliers / every interior model pixel (hidden and unmeasured ones too)
  double unmeasured_fraction = 0;  ///< unknown / (inliers + conflicts + unknown): model pixels with no depth
  std::size_t inliers = 0, conflicts = 0, occluded = 0, unknown = 0;
  std::size_t hidden_by_cluster = 0;  ///< model pixels behind the cluster's own surface (conflicts too)
  /// Refused by the quick test (seen_through) before the model was drawn: conflict_fraction holds
  /// the quick share, inlier_fraction its complement, every other field is 0.
  bool refused_quickly = false;
  int pixel_step = 1;  ///< s: the model was judged on every s-th pixel (counts are scaled by s^2)
  /// The outline: just outside the model's silhouette, the scene should step away (farther than
  /// the model's edge by more than the tolerance), be hidden by something in front, or be missing;
  /// where it carries on at the edge's depth, the model is a patch cut out of a larger surface.
  /// Counted in outline samples, each looked at a few pixels beyond the edge, outward.
  std::size_t outline_continued = 0, outline_stepped = 0, outline_in_front = 0, outline_unknown = 0;
  double outline_continuation = 0;  ///< continued / (continued + stepped)
  /// Model against plane over the inlier pixels: RMS of the observed depth about the model, and
  /// RMS distance of the observed points from their own best plane; and the model's own relief (its
  /// drawn points' RMS distance from their best plane). A curved model on a flat patch explains it
  /// no better than the plane does.
  double model_rms_m = 0, plane_rms_m = 0, model_relief_m = 0;
};

/// How many of a model's points, at a pose, the camera sees past: of `points` (object frame; up to
/// max_points of them, evenly spread), those that project into the frame onto a measured pixel
/// within the tolerance of them or beyond it are judged, and those beyond it (the camera sees
/// farther than the model's surface there) are seen through. Points with something measured in
/// front of them (the model's own far side, occluders) are not judged: no drawing is needed to
/// tell which of the model's points are visible. With `normals` (either sign; empty: none), points
/// whose surface the line of sight grazes (within 30 degrees) are not judged either: they lie on
/// the outline, where a pixel's error reads as seen through.
struct SeenThrough {
  std::size_t judged = 0, seen_through = 0;
  double fraction() const { return judged ? static_cast<double>(seen_through) / static_cast<double>(judged) : 0.0; }
};
SeenThrough seen_through(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, const Transform& T_camera_object, const DepthImage& observed,
                         const CameraIntrinsics& K, const VerifyOptions& options, std::size_t max_points);

/// Whether `v` meets every bound of `options` (what verify_pose sets `accepted` from).
bool passes(const Verification& v, const VerifyOptions& options);

/// Whether `v` meets the cluster bound of `options` only as an object whose unexplained cluster
/// points lie beside it (VerifyOptions::min_footprint_explained), not by cluster_explained itself.
bool explained_beside_neighbour(const Verification& v, const VerifyOptions& options);

/// Tolerance (m) at depth z: base + factor * Kinect sigma(z), at most max_tolerance_m.
float depth_tolerance(float z_m, const VerifyOptions& options);
/// The same without the cap: what the sensor's noise alone asks for at depth z.
float depth_noise_tolerance(float z_m, const VerifyOptions& options);

/// The model as verification draws it: its mesh, or, for an object scanned as a point cloud (no
/// triangles), its points splatted at their spacing.
struct VerifyModel {
  const TriangleMesh* mesh = nullptr;
  std::span<const Eigen::Vector3f> points;  ///< the model cloud (voxel grid of the views), object frame
  float point_spacing_m = 0.003f;
  int closed_winding = 0;  ///< closed_mesh_winding(*mesh): a closed mesh is drawn without its back faces
  std::span<const Eigen::Vector3f> normals;  ///< the points' normals (either sign; none: not known)
};

/// verify_pose's quick test alone (VerifyOptions::quick_max_seen_through): the share of the
/// model's judged points the camera sees past at this pose, when it refuses the pose (more than
/// that share, of at least quick_min_judged points); nothing when it does not. The recognizer's
/// screen applies it where its short ICP leads a starting pose (MatchOptions::prescreen).
std::optional<double> seen_through_quickly(const VerifyModel& model, const Transform& T_camera_object, const DepthImage& observed,
                                           const CameraIntrinsics& K, const VerifyOptions& options);

Verification verify_pose(const VerifyModel& model, const Transform& T_camera_object, const DepthImage& observed,
                         const CameraIntrinsics& K, std::span<const Eigen::Vector3f> cluster_points,
                         const VerifyOptions& options = {});

}  // namespace viewpose
