#pragma once
// The whole pipeline on one frame: segment, describe each cluster, match it against the view
// database, and for each match in order turn the CRH roll peaks into poses, refine each with ICP
// and verify it; the first pose that passes is the detection (or, with keep_best, the best of all).
// Objects that touch share a cluster: once one is found its points are explained away and the rest
// recognized again, and a cluster nothing explains is split into convex parts (segment/convex_segments).
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/occupancy_grid.hpp"
#include "viewpose/core/stopwatch.hpp"
#include "viewpose/database/matching.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/describe/crh.hpp"
#include "viewpose/pose/axis_starts.hpp"
#include "viewpose/pose/icp.hpp"
#include "viewpose/pose/ppf.hpp"
#include "viewpose/pose/scene_claims.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/segment/convex_segments.hpp"
#include "viewpose/segment/segmentation.hpp"

namespace viewpose {

/// A hypothesis that passed verification's bounds, as AcceptOptions::on_verified hears of it.
struct VerifiedHypothesis {
  std::uint32_t object_index = 0;  ///< into ViewDatabase::objects
  Transform T_camera_object = Transform::Identity();
  Verification verification;
  double confidence = 0;  ///< pose_confidence(verification)
};

/// Where a region's starting poses come from. `vfh`: its nearest database views by VFH, each turned
/// by its CRH rolls (the thesis). `ppf`: point pair feature votes of the region's own surface against
/// each object's pair table (pose/ppf; needs no clean cluster: an object touching another, or half
/// hidden, still shows pairs of its own points). `both`: the views' poses first, as `vfh` tries them,
/// and where none passes, the votes' poses, with a budget of their own.
/// `touching`: the views' poses everywhere, and in what a detection leaves of its region (an
/// object touching the one found, which no view's VFH describes whole) the votes' poses too, after
/// the views': votes where they are most needed, at a fraction of their cost everywhere.
enum class PoseSource { vfh, ppf, both, touching };

/// The names the command line and the Python module give the sources, in PoseSource's order.
inline constexpr std::string_view kPoseSourceNames[] = {"vfh", "ppf", "both", "touching"};
/// The source of that name; Error ("source: "x" is none of vfh, ppf, both, touching") for another.
PoseSource pose_source_from_name(std::string_view name);
/// The name of `source` (kPoseSourceNames).
inline std::string_view pose_source_name(PoseSource source) { return kPoseSourceNames[static_cast<int>(source)]; }

/// Which database views are tried for a region (a cluster, a convex part, what a detection left of
/// a cluster), the poses each gives, and in what order they are refined and verified.
struct MatchOptions {
  /// `touching` by default: on the real YCB-V dev frames it finds 28 of 28 poses where `vfh` finds
  /// 26 (docs/BENCHMARK.md, "A region's parts before its votes"; "Point pair votes" has the
  /// history); votes cost about 7 ms per object and region of a
  /// real frame, and are cast only where a detection leaves part of its region.
  PoseSource source = PoseSource::touching;
  /// With `touching`: in what a detection leaves of its region, the views' poses are tried on the
  /// whole of it and then on its convex parts (as `vfh` tries them; what a kept pose leaves, or a
  /// region grown from a part's pose, with votes as before), and the votes are cast only where
  /// none of these passes, in the whole of it. (Off, or in a region too wide to be searched whole:
  /// the votes after the whole region's views' poses, and in each part after its views'.) Two
  /// objects touching each other beside a third are most often told apart by the crease between
  /// them, and a part's views cost less than votes for every object. Measured on the real YCB-V
  /// dev frames: the same 28 poses (within 0.5 mm), the vote stage's median 22-29 -> 9 ms a
  /// frame, the frame's 76-101 -> 63-66 ms (docs/BENCHMARK.md). Not on the command line.
  bool votes_after_parts = true;
  /// The pair tables and votes (every source but vfh). Each object's table is the database's where
  /// it stores one made with these options (DatabaseParams::ppf; loaded, or read from its file when
  /// first needed where the database was loaded without them), else made when the recognizer is
  /// (ppf, both: databases of up to RunOptions::prepare_objects_up_to objects) or on first use.
  PpfOptions ppf{};
  std::size_t per_object = 20;  ///< nearest views per region and object (thesis: 20, one object)
  /// At most this many views per region in all, the nearest (each object at most `per_object`): with
  /// up to six objects every object gets its 20; a database of a thousand gets the 120 nearest.
  std::size_t at_most = 120;
  /// CRH peaks: up to 10 rolls per view, down to half the best peak. PCL's 5 and 0.8 missed 1 of 100
  /// frames of the simulated seed experiment (a narrow side view); these found all 100, still
  /// without a false positive (docs/RESULTS.md).
  RollOptions roll = {10, 0.2f, 0.5f};
  /// Every view's every roll is a starting pose; they are ordered by their coarse fit
  /// (pose/coarse_fit: the region on the model and the view on the region, in cells of this size,
  /// from this many points each way), best first, and refined and verified in that order.
  float fit_cell_m = 0.01f;
  std::size_t fit_points = 64;
  /// A thin object seen edge-on (a book, a board: the thesis's failure case, its Figure 16) shows a
  /// strip no rendered view stands exactly in line with. Where a region is such a strip for an
  /// object (pose/axis_starts: its width across the image at most `edge_on_width_share` of the
  /// object's thinnest principal extent plus `edge_on_width_pixels` pixels at the region's depth,
  /// at least `edge_on_min_width_share` of it, and its length at least twice its width; the object
  /// thin, its thinnest extent at most `edge_on_thin_share` of its middle one, and among the
  /// region's nearest views' objects), its edge-on poses are starting poses too, the object's
  /// plane turned about its thin axis in `edge_on_turns` steps each way, ranked with the views' by
  /// coarse fit (0 turns: none). Measured on make results' book (20 x 15 x 2 cm, 80 frames at the
  /// thesis's distances) with `--min-score 0`: 77 -> 78 right (ADD-S), and one wrong pose (score
  /// 0.01) where none passed before (since gone: `doubtful_confidence`); at the default threshold
  /// the same 31. Every other set of make results, the real YCB-V frames and the real negatives:
  /// the same detections (mOSD's test25 tries 51 -> 56 poses).
  int edge_on_turns = 12;
  double edge_on_thin_share = 1.0 / 3.0;
  double edge_on_width_share = 1.5;
  double edge_on_min_width_share = 0.5;
  double edge_on_width_pixels = 4.0;
  /// A short ICP screens the starting poses: once a region's first batch (RunOptions::batch, in
  /// coarse fit order) has failed, its next `prescreen` poses by coarse fit (0: none) are refined by
  /// the ICP schedule's coarse stages alone, `prescreen_iterations` steps each on `prescreen_points`
  /// of the region's points, nothing drawn (a tenth of a full refinement's cost), and then tried in
  /// the order of the share of the region each brought within the final stage's reach of the model
  /// (ties: coarse fit). Coarse fit judges where a pose starts, and a right view whose CRH roll is a
  /// little off starts poorly; the screen judges where it leads. (The parts of a split cluster are
  /// screened all at once, to be ranked against each other by the same measure.) Measured first
  /// with every pose of every region refined and verified, then ranked either way: with all 48
  /// screened from the start, the first right pose was within the first 12 on every real YCB-Video
  /// frame and mOSD's and in the seed room, in 28 of 29 regions of the simulated rooms; in coarse
  /// fit order it lay as late as the 37th. Then as shipped (four in coarse fit order, then eight
  /// screened of the next 48; make results against 48 in coarse fit order): the same poses found on
  /// every set, real YCB-Video frames 0.20 -> 0.11 s median, rooms 0.34 -> 0.22 s.
  /// A screened pose whose turn comes is first put to verification's quick test where the screen
  /// led it (the camera must not see past the model there, VerifyOptions::quick_max_seen_through):
  /// one refused keeps its share of the budget but is not refined in full. Measured on make
  /// results' sets and the real negatives, no pose that went on to pass verification was seen
  /// through at more than 0.36 there; 32 % of the full refinements on the real YCB-Video frames
  /// and 29 % in the rooms were spared, with byte-identical detections.
  std::size_t prescreen = 48;
  std::size_t prescreen_points = 100;
  int prescreen_iterations = 8;
  /// A screened pose is refined in full from where the screen led it, not from where it started,
  /// and without the ICP schedule's first stage: the screen ran the coarse stages on a quarter of
  /// the points, and the rest of the schedule runs on all of them (with the default three stages,
  /// from the 2 cm stage on; an ICP that then leaves less than
  /// IcpOptions::min_fitness_after_first_stage of the region on the model is given up after the
  /// first stage it runs). The screen's steps are not taken again: on the real YCB-Video frames
  /// 24.2 -> 19.7 ICP steps a full refinement (Recognition::icp_steps), the same poses found
  /// (docs/BENCHMARK.md). false: from the starting pose, the whole schedule.
  bool refine_from_screen = true;
  /// Many starting poses of a region lead to one place: the views' rolls and the votes' poses are
  /// thick around each good fit (a fifth to a third of the screened poses on the real YCB-Video and
  /// mOSD frames lay within 5 % of the object's diameter and 10 degrees of another of the same
  /// object). One that the screen led within `merge_rotation_deg` and `merge_share` of the object's
  /// diameter of where it led a pose already refined in full for the region (the same object) is
  /// not refined again: it keeps its place and spends its share of the budget unrefined, as one the
  /// quick test refused (Recognition::screened_merged; 0 degrees: every one is refined).
  /// Measured with refine_from_screen (make results, the real YCB-Video frames, the simulated
  /// rooms): the same poses found on every set, the real negatives' detections unchanged, 6 %
  /// fewer full refinements (docs/BENCHMARK.md). A vote's screened pose (PoseSource::both,
  /// touching) is compared with the places of the region's views' poses too: the same place,
  /// refined from the same pose.
  double merge_rotation_deg = 5;
  double merge_share = 0.02;
  /// At most this many starting poses are refined in full and verified per region, best first, the
  /// convex parts of a split cluster sharing one (0: all of them, in coarse fit order, unscreened,
  /// as the thesis did). The search is a budget, not exhaustive: a region of nothing known (most of
  /// a real frame) costs every pose it is given. With the screen, 12 and 8 both found what 48
  /// in coarse fit order found on every set of make results (8: real YCB-Video 0.09 s median); 12
  /// keeps a margin for frames unlike these, where a right pose ranks later.
  std::size_t max_hypotheses = 12;
  /// Skip the views of objects too small to explain a region: verification wants
  /// verify.min_cluster_explained of its points on the model's surface, and no object can cover
  /// points spread wider than its diameter (plus the depth tolerance and a few pixels each side;
  /// core_width). Changes only what is tried: a large unknown thing (a box, a monitor) is not tried
  /// against every small object's views. (A pose beside a touching neighbour may explain less than
  /// that share, VerifyOptions::min_footprint_explained; the objects narrower than the region are
  /// still skipped: such a pose is looked for among the objects as wide as the region's core.)
  bool skip_objects_too_small = true;
  /// Skip the views that show far more surface than the region has: verification wants
  /// min_visible_fraction (0.4) of the model's judged pixels measured on it and min_model_support
  /// (0.5) of those on the region, so the region must cover a fifth of what the model shows. A view
  /// whose 5 mm copy holds more than 1 / min_region_to_view times the region's points (the region's
  /// count corrected where the sensor samples it more sparsely than 5 mm) cannot pass; 0.1 leaves
  /// half the bound as margin. Measured: 43-45 % of the starting poses in the simulated rooms (small
  /// unknown things against the large box's views), 6 % on the real YCB-Video frames (0: off).
  double min_region_to_view = 0.1;
  /// Once a pose of one object passes, each other object tries up to this many of its next starting
  /// poses (within the budget), and the higher verification score wins (0: the first pass stands).
  std::size_t challenger_views = 3;
  /// Where the pose that passed is doubtful, its confidence below this (more likely wrong than
  /// right: only a `--min-score` below it accepts such a pose), its own object's next poses
  /// challenge it too, up to `challenger_views` of them (0: not): a flat face or a thin edge far
  /// away passes in more than one pose, and the first to pass is not always the right one.
  /// Measured with `--min-score 0`: make results' book 78 right and 1 wrong -> 79 right and none
  /// wrong of 80; the simulated rooms and clutter the same found and false (2 poses of 42 moved a
  /// little), 12-15 % more time; mOSD against HOPE 7 -> 6 false. At the default bound no accepted
  /// pose is doubtful: nothing changes.
  double doubtful_confidence = 0.5;
  double max_region_size_factor = 1.5;  ///< regions wider than this x the largest object are not tried
  /// Many views and rolls of a region refine to the same pose. One that ICP brings within this
  /// rotation and translation of a pose of the same object verification has already refused for the
  /// region is not verified again, and is refused too (rotation 0: every one is verified).
  double refused_rotation_deg = 2;
  double refused_translation_m = 0.002;
};

/// Which verified poses become detections, and in what form.
struct AcceptOptions {
  /// A pose that passes verification's bounds is accepted only when its confidence (pose/confidence:
  /// the estimated probability that it is right) reaches this. A detection's score is that confidence.
  /// The default is the confidence that kept 98 % of the poses right on the simulated rooms and
  /// clutter the model was fit on (docs/CONFIDENCE.md).
  double min_confidence = 0.917;
  bool keep_best = false;  ///< try every hypothesis, keep the best accepted (slower)
  /// Once a pose passes, also try it turned half a turn about each of the object's axes (refined and
  /// verified in turn) and keep the best: objects that are nearly symmetric (a jug whose handle is a
  /// small share of its surface) otherwise come out the wrong way round about as often as not.
  bool try_half_turns = true;
  /// A view's best pose that fails verification only by its free-space conflicts, with at most this
  /// share (looser than verify.max_conflict_fraction), is most often the object the wrong way round
  /// (a jug with its handle behind): its half turns are refined and verified at once, before the next
  /// view (0: not). With try_half_turns.
  double near_miss_conflict_fraction = 0.15;
  /// Report a symmetric object's pose in one canonical form among its equivalent ones (canonical_pose:
  /// the object standing as modelled, z up), so that a box or a can does not flip from frame to frame.
  /// Up is the normal of the removed plane the object stands on (resting_plane_up: a table seen by
  /// a camera rolled or upside down), else the camera's default up.
  bool canonical_poses = true;
  /// The frame as a whole (pose/scene_claims.hpp): of detections that explain the same pixels,
  /// the more confident is kept; one whose evidence another already explains is dropped.
  bool resolve_scene_claims = true;
  SceneClaimOptions scene_claims{};
  /// A pose with more than this share of its model inside a removed plane where the camera saw that
  /// plane (pose/through_planes.hpp: the table it stands on, a wall) is not accepted: no object
  /// stands in a table (1: none refused). Measured: every right detection on the real and simulated
  /// sets 0 (of 200); three false positives that passed every test of verification 0.03-0.12 (a
  /// box taken for another in a real mOSD frame, the pitcher fitted to a can in real YCB-V, the jug
  /// fitted to a can at the seed room's image edge). Judged as a pose passes verification and the
  /// confidence bound, so that the region's search goes on to its next pose; and once more on the
  /// frame's detections (those verified jointly with another). Within 0-1.
  double max_share_inside_planes = 0.02;
  /// A pose that passes with its model sunk into a removed plane by more than the sensor's noise at
  /// its depth (as many of its points as max_share_inside_planes counts), though not by the margin
  /// that refuses it, is lifted along the plane's normal until it rests on it and verified again
  /// there: kept lifted if it passes and is confident enough, refused if not. An object stands on
  /// the table; the plane's band removes its foot with the table, so a right pose may sink a few
  /// millimetres and is the better for lifting, while another object's height (a master chef can,
  /// 14 cm, fitted by its top to a real 13 cm can in mOSD, its foot 17 mm into the table) no longer
  /// fits once it stands where it would have to. A pose refused so has its half turns tried (as a
  /// near miss, where AcceptOptions::try_half_turns allows them): the seed experiment's jug at
  /// 1.25 m first passed flipped, 16 mm in the table, and its turn is right. The search's poses
  /// only: one verified jointly with another is judged by max_share_inside_planes alone. A lifted
  /// detection keeps the ICP fitness and residual of the pose ICP gave, and on_verified hears that
  /// pose. With max_share_inside_planes 1, nothing is lifted either.
  bool lift_out_of_planes = true;
  /// Called in order, on the calling thread, for every hypothesis that passed verification's bounds,
  /// before the confidence threshold: what the confidence model is fit on (viewpose bop --hypotheses).
  std::function<void(const VerifiedHypothesis&)> on_verified{};
};

/// Touching objects: a region in which nothing passes is split at concave creases and steps
/// (segment/convex_segments) and each convex part tried on its own; once something is found, its
/// points are explained away and what is left of the region is tried again.
struct SplitOptions {
  bool enabled = true;
  ConvexSegmentOptions parts{};
  /// Regions wider than this x the largest object, and than min_size_m, are not split (furniture, a
  /// wall left by the planes, a heap whose parts are boxes of every size).
  double max_size_factor = 2.0;
  /// Regions up to this wide are split whatever the largest object: a pile of a few small ones. With
  /// only the three small objects of a YCB-V desk in the database (largest 0.125 m) their 0.28 m
  /// pile was never split, and they were found in 2 of 8 real frames; with this bound in all 8.
  /// (Four times the largest instead also split a real mOSD heap of boxes, 2 boxes of the HOPE
  /// database fitted to its parts.)
  double min_size_m = 0.4;
  int max_depth = 2;  ///< how many times what is left of a region may be split again
  /// A cluster whose first batch of poses (RunOptions::batch, in coarse fit order) fails is
  /// searched on together with its convex parts, within one budget (MatchOptions::max_hypotheses),
  /// its poses and theirs ranked by the screen; not on alone with the whole budget and then its
  /// parts with a budget again. Most clusters that hold one object pass in that first batch; on
  /// real tables the rest are mostly objects touching each other, or nothing known, and their
  /// whole search found little: YCB-V dev (7 objects), 2 of 58 whole clusters, with 466 of the
  /// 912 poses refined. A cluster whose parts are none, or one that is nearly all of it, goes on
  /// alone as before. Searched as before too: what a detection leaves of a region (its neighbours'
  /// votes are cast there), and every region with votes everywhere (PoseSource::both), with
  /// keep_best, an exhaustive search (max_hypotheses 0) or a budget of one batch or less.
  /// false: every cluster alone first, with the whole budget, then its parts with another.
  bool whole_with_parts = true;
  /// A convex part is a small patch and weaker evidence than a whole cluster: a pose found in one is
  /// verified with `verify` tightened to these bounds. Measured on the real YCB-Video frames: true
  /// detections in parts leave 0.06 to 0.11 of the model's unhidden pixels unmeasured; a foam brick
  /// fitted to a patch of a monitor stand with half of it over a region with no depth, 0.46.
  double part_max_unmeasured_fraction = 0.3;
  double part_min_inlier_fraction = 0.9;
  double part_min_cluster_explained = 0.9;
  /// Two objects that touch may stay one region even in convex parts (a can standing on a box, the
  /// crease between them bridged). A pose that passes every bound but the share of the region it
  /// explains (at least this much of it: a touching neighbour's share is missing, not wrong) is kept
  /// aside; if nothing passes in the region, its points are explained away and the rest searched, and
  /// when the rest gives a detection, the kept pose is verified again on the points that detection
  /// leaves, with the part bounds above. Both are reported only together: two poses that explain
  /// the region between them (0: not tried). A pose whose unexplained points all lie beside its
  /// silhouette passes alone (VerifyOptions::min_footprint_explained: the neighbour is unknown), in
  /// parts too: the part bounds tighten the footprint's share, inliers and unmeasured pixels, while
  /// its whole-region floor stays min_cluster_explained_beside.
  double joint_min_cluster_explained = 0.3;
  /// One object the sensor sees in two pieces: a mug's or a bowl's inside and outside, cut apart by
  /// the rim it returns no depth for (and a step over the front rim), or a box by a dark band of
  /// print. Neither piece carries the object alone. Once the frame's clusters are searched, two
  /// pieces that no detection explains are searched as one region, with the part bounds above,
  /// when they lie nearer each other than this, together no wider than the largest object (and
  /// VerifyOptions::max_tolerance_m), nearer the camera than where the depth noise verification
  /// allows (without its cap) reaches the clusters' gap (there a surface breaks into pieces by
  /// noise alone: a Kinect's at about 2 m), and are joined in the image by a path of missing depth no wider than
  /// this at their depth (segment/depth_gaps.hpp). Nearest pair first; a piece in a pair that
  /// gives a detection is in no later pair. The views' poses only: votes over the eight HOPE
  /// objects made the one pair of a real mOSD frame cost 45 ms instead of 5, and the views found
  /// what they found. Measured (`bop --details` and `recognize --json`'s joined_regions at
  /// dcbc1e0): on the real YCB-V dev frames one pair is searched (the mug of 0000 frame 5, found);
  /// on the mOSD frames one in ten, on the simulated rooms seven in 20, none passing (0: not
  /// tried; at most 1 m).
  float join_gap_m = 0.05f;
  /// An object touching an unknown one (a mug against a box no database holds) is cut into convex
  /// parts with the box's, and none of its parts carries it: its outer wall, its inside and its
  /// handle lie in different parts, and a pose found on one part shows a model most of whose
  /// surface lies on the others, so the model's support (VerifyOptions::min_model_support) fails
  /// however well it fits, or passes it narrowly (half the model on the part) with a confidence
  /// below AcceptOptions::min_confidence. Where no part passes, the best pose that met every part
  /// bound but the support, and was not accepted, is grown: the split region's points within this
  /// distance of its model, the piece of them holding most points within verification's depth
  /// tolerance of it (the largest may be a neighbour's that the reach touched; pose/points_on_model),
  /// are searched as a region of their own, with the part bounds (support is then judged on that
  /// piece; what lies beside it stays the unknown neighbour's). Measured on the real YCB-V dev
  /// frames with the mug alone in the database: 0 of 8 found before, 6 of 8 with it (ADD-S; turned
  /// about its axis by 88 degrees on average, its handle hidden), none false; on the real mOSD
  /// frames, which hold no mug, one detection (test33: a cylinder of the mug's size, its handle side
  /// out of sight), where the eight HOPE objects still give none. (Both measured again with the
  /// piece chosen as above, the same; first measured with the largest piece.) Growing by 1 cm
  /// (ICP's last reach; measured with the largest piece) gave better mug poses (17 degrees and 4 mm
  /// off on average, against 88 and 16 mm) but a false jug at 2 m in the simulated seed room,
  /// fitted to the furniture (0: not grown).
  float grow_reach_m = 0.02f;
};

/// Time and threads.
struct RunOptions {
  /// Stop trying poses once the frame has taken this long (0: no limit): what is verified by then
  /// is returned, and Recognition::cut_short says so. Checked before each region, screen and batch
  /// of starting poses (RunOptions::batch, refined side by side), so a frame overruns it by at most
  /// one batch's refinement and verification, a few ms. A pose found in time is kept even if its
  /// challengers and half turns had to be left out.
  double deadline_ms = 0;
  /// Refine and verify independent hypotheses (a batch of starting poses, the half turns) on
  /// several threads, taken in order afterwards: the result is the same either way.
  bool parallel_hypotheses = true;
  /// A frame's clusters are searched side by side, largest first (with
  /// parallel_hypotheses, two or more clusters, and no on_verified: that is heard in order). One
  /// parallel stage a frame instead of a few a cluster: on a machine busy with other programs, a
  /// short stage's threads wait for whichever of them the system has put aside, and two threads
  /// did no better than one. Detections are taken in the clusters' order: the result is the same.
  /// (Stage times are then summed over the threads; the frame's total is its wall time.) Each
  /// cluster is a task, and so are the parts of its parallel stages (the screen, refinement and
  /// verification, coarse fit, CRH rolls, point pair votes): a thread with no cluster left takes
  /// up the stages of one still running (describing a cluster, matching it against a large
  /// database and the votes of one object stay on its thread). A frame's largest cluster was often
  /// most of its work, on one thread while the other waited; measured on the real YCB-Video
  /// frames, 0.096 -> 0.084 s median idle, 0.19 -> 0.16 s with two busy processes beside it
  /// (docs/BENCHMARK.md).
  bool parallel_clusters = true;
  /// Starting poses are refined and verified this many at a time (the first that passes in a batch
  /// is taken, as one after the other would). A fixed number, not the thread count, so that results
  /// do not depend on the machine; enough to keep a few cores busy.
  std::size_t batch = 4;
  /// Databases of at most this many objects are prepared for ICP and verification when the
  /// recognizer is made (a millisecond or two an object with what the database stores, on all
  /// threads), so that the first frames run as fast as the rest; larger ones object by object as
  /// scenes suggest them. Either way the results are the same.
  std::size_t prepare_objects_up_to = 16;
  /// Those objects' nearest-point grids that the database does not store (past DatabaseParams::
  /// max_grid_bytes, or made with other cells than IcpOptions::grid_cell_m and reach_m()) are
  /// filled whole then too (about 0.1 s an object); false: they fill where ICP looks (the first
  /// hypotheses of an object cost a few milliseconds more), which is sooner for a process that
  /// recognizes one frame.
  bool fill_grids_at_start = true;
};

/// Everything a Recognizer can be told, by stage. (Every member has a default initializer, so that
/// designated initializers may name only what they change.) The defaults are what the measurements in
/// docs/RESULTS.md were made with; most programs change at most accept.min_confidence, split.enabled
/// and run.deadline_ms:
///   Recognizer r(db, {.accept = {.min_confidence = 0.8}, .run = {.deadline_ms = 30}});
/// What the database fixes is taken from it: the voxel size scenes are described at (segment.voxel_m
/// must be left as it is or equal the database's) and the ICP copy's (DatabaseParams::icp_voxel_m).
struct RecognizerOptions {
  SegmentOptions segment{};
  MatchOptions match{};
  IcpOptions icp{};
  VerifyOptions verify{};
  /// Verification draws each object's mesh simplified to within this (0: the mesh as it is). CAD and
  /// scanned meshes hold tens of thousands of triangles where a few hundred draw the same depth to
  /// within 2 mm, two fifths of the smallest depth tolerance; drawing was most of a real frame's time.
  float verify_mesh_error_m = 0.002f;
  AcceptOptions accept{};
  SplitOptions split{};
  RunOptions run{};
};

/// How many frames a loaded database will serve: one (a process per file), or a run of them.
enum class FramesToServe { one, many };

/// What a recognizer with `options` needs read of a database: the pair tables only where its
/// source casts votes. With `touching` and one frame to serve, they are read from the
/// file when the first vote is cast instead (ViewDatabase::pair_tables_on_disk): most frames cast
/// none, and reading them was a quarter of a `recognize` process that did not (real mOSD frames,
/// eight objects: 0.11 -> 0.08 s median). A run over many frames reads them at once, so that no
/// frame's time holds their reading.
inline DatabaseLoadOptions database_load_options(const RecognizerOptions& options, FramesToServe frames = FramesToServe::many) {
  const PoseSource source = options.match.source;
  return {.pair_tables = source != PoseSource::vfh && !(source == PoseSource::touching && frames == FramesToServe::one)};
}

struct Detection {
  int object_id = 0;
  std::string object_name;
  std::uint32_t object_index = 0;  ///< into ViewDatabase::objects
  Transform T_camera_object = Transform::Identity();  ///< metres
  double score = 0;          ///< confidence in [0, 1]: the estimated probability that the pose is right (pose/confidence)
  double icp_fitness = 0;    ///< share of cluster points with a model correspondence
  double icp_rmse_m = 0;     ///< RMS point-to-plane residual
  int match_rank = 0;        ///< the view's rank among the region's nearest by VFH (0 = the nearest; -1: from point pair votes or an edge-on start)
  float roll_deg = 0;        ///< the CRH roll that led to it
  /// Best verification score (Verification::score) of the half-turned alternatives (0 if none
  /// passed): verification.score minus this is the margin by which the chosen side won.
  double runner_up_score = 0;
  std::size_t cluster_points = 0;
  bool from_split_cluster = false;  ///< found in a part of a cluster, or in what another detection left of it
  Verification verification;
};

struct StageTimes {
  double downsample_ms = 0, segment_ms = 0, normals_ms = 0, vfh_ms = 0, match_ms = 0, crh_ms = 0, icp_ms = 0,
         verify_ms = 0, total_ms = 0;
  /// Taking a detection's points out of its cluster and clustering the rest again, and splitting
  /// clusters nothing was found in (touching objects).
  double split_ms = 0;
  /// Each stage's time added (a cluster's record into its frame's: RunOptions::parallel_clusters).
  StageTimes& operator+=(const StageTimes& o) {
    downsample_ms += o.downsample_ms, segment_ms += o.segment_ms, normals_ms += o.normals_ms, vfh_ms += o.vfh_ms;
    match_ms += o.match_ms, crh_ms += o.crh_ms, icp_ms += o.icp_ms, verify_ms += o.verify_ms, total_ms += o.total_ms;
    split_ms += o.split_ms;
    return *this;
  }
};

struct Recognition {
  std::vector<Detection> detections;
  StageTimes times;
  std::size_t clusters = 0;
  std::size_t hypotheses = 0;  ///< poses refined and verified
  std::size_t repeats = 0;  ///< of those, refined onto a pose already refused, and not verified again
  std::size_t screened = 0;  ///< starting poses screened by a short ICP (MatchOptions::prescreen)
  /// Of those, refused where the screen led them, by verification's quick test (the camera sees
  /// past the model there), without being refined in full.
  std::size_t screened_out = 0;
  /// Of the screened poses, led by the screen to where another of the region's poses was led and
  /// chosen for full refinement (MatchOptions::merge_rotation_deg), and not refined.
  std::size_t screened_merged = 0;
  /// ICP steps of every pose refined in full: half turns included, and the poses of a batch
  /// refined beside one that passed, which `hypotheses` does not count (the screen's steps not
  /// counted). The refinements' work, the same on any machine.
  std::size_t icp_steps = 0;
  std::size_t split_clusters = 0;  ///< clusters whose search went on in their convex parts
  std::size_t regions = 0;  ///< clusters, parts and remainders described and matched against the database
  /// Convex parts of split clusters that the search never reached (a pose found, the budget spent or
  /// the deadline passed before their turn): neither described nor screened, and not counted in
  /// `regions`.
  std::size_t parts_unreached = 0;
  /// Detections dropped because another, more confident one explains the same pixels.
  std::size_t dropped_as_explained = 0;
  /// Poses that passed verification and the confidence bound but lay inside a removed plane
  /// (AcceptOptions::max_share_inside_planes), refused in the search or dropped from the detections.
  std::size_t dropped_inside_planes = 0;
  /// Poses lifted out of a removed plane they had sunk into a little, and kept there
  /// (AcceptOptions::lift_out_of_planes; those that fail once lifted count as dropped above).
  std::size_t lifted_out_of_planes = 0;
  /// Pairs of unexplained pieces searched as one region (SplitOptions::join_gap_m).
  std::size_t joined_regions = 0;
  /// Regions grown from a part's pose into the rest of its cluster and searched (SplitOptions::grow_reach_m).
  std::size_t grown_regions = 0;
  /// Regions in which point pair votes were called for (MatchOptions::source): each object wide
  /// enough for the region, with a pair table, votes once there; where most of a frame's time goes
  /// when it casts them.
  std::size_t voted_regions = 0;
  /// RunOptions::deadline_ms ran out: clusters, views or checks were left untried.
  bool cut_short = false;
  /// Of the poses the regions' searches refined and verified that met every bound of verification
  /// but whose confidence fell below AcceptOptions::min_confidence (and lay inside no removed
  /// plane), the most confident (`score`: its confidence; its pose as refined, not turned or put in
  /// canonical form). Not a detection, and none where no pose came that close: it tells a user whose
  /// object is not found whether a pose came close, and how close (a box's face seen alone, or a
  /// small patch of an object, scores low: docs/CONFIDENCE.md). Where objects are found it may be
  /// one of theirs at a rival pose, or where the search went on to find it.
  std::optional<Detection> best_below_min_score;
  /// Whether a pose of this confidence is more confident than best_below_min_score (or there is
  /// none): the one rule by which it is kept, within a search and across clusters merged.
  bool more_confident_than_below(double confidence) const {
    return !best_below_min_score || confidence > best_below_min_score->score;
  }
  Clock::time_point started{};  ///< when recognize() began (the deadline counts from it)
};

class Recognizer {
 public:
  /// Shares the database: it lives as long as the last recognizer (or caller) holding it.
  explicit Recognizer(std::shared_ptr<const ViewDatabase> db, RecognizerOptions options = {});
  /// Takes the database: `Recognizer r(ViewDatabase::load(path));` keeps what it loaded.
  explicit Recognizer(ViewDatabase&& db, RecognizerOptions options = {});
  /// Uses a database the caller keeps alive for as long as the recognizer (no copy is made).
  explicit Recognizer(const ViewDatabase& db, RecognizerOptions options = {});
  ~Recognizer();
  const ViewDatabase& database() const { return db_; }
  Recognition recognize(const Frame& frame) const;
  const RecognizerOptions& options() const { return options_; }

 private:
  // What the search of a frame reads of it: the depth and intrinsics verification judges poses on,
  // and the planes the segmentation removed, inside which no pose is accepted
  // (AcceptOptions::max_share_inside_planes).
  struct FrameAndPlanes {
    const DepthImage& depth;
    const CameraIntrinsics& K;
    std::span<const Plane> planes;
  };
  // One region searched alone, neither split nor its rest recognized (a region grown from a part's
  // pose, pieces joined, what a kept pose leaves): described, matched, its poses refined and
  // verified; the first (or best) accepted pose. With `votes`, where no view's pose passes, the
  // point pair votes' (PoseSource both, touching). A frame's clusters go through recognize_region.
  std::optional<Detection> recognize_cluster(const PointCloud& points, const FrameAndPlanes& frame, const VerifyOptions& verify,
                                             Recognition& out, bool votes = false) const;
  struct Refined;
  // A starting pose: a database view (by its rank among the region's matches) turned by one CRH roll,
  // a pose from point pair votes (match: kFromPairVotes), or an edge-on start (kFromEdgeOn).
  struct Candidate {
    static constexpr std::uint32_t kFromPairVotes = 0xffffffffu;  // `match` of a pose from point pair votes
    static constexpr std::uint32_t kFromEdgeOn = 0xfffffffeu;     // `match` of an edge-on pose (MatchOptions::edge_on_turns)
    std::uint32_t match = 0;  // into Region::matches (kFromPairVotes, kFromEdgeOn: none)
    bool from_view() const { return match != kFromPairVotes && match != kFromEdgeOn; }
    std::uint32_t object = 0;
    float roll_deg = 0;
    Transform T_camera_object = Transform::Identity();
    double fit = 0;  // coarse_fit
    double screen_fitness = -1;  // the short ICP's share of the region brought onto the model (-1: not screened)
    // Where the short ICP led it: into Region::screened_poses, read only when screened(). An index,
    // not a pose: a region has thousands of candidates, sorted and interleaved, and 48 of them screened.
    std::uint32_t screened_pose = 0;
    bool screened() const { return screen_fitness >= 0; }
    // Screened poses rank above every unscreened one (a share and a coarse fit are not comparable).
    double priority() const { return screened() ? 1.0 + screen_fitness : fit; }
  };
  // What every pose tried for one region needs: its description, its nearest views and the starting
  // poses they give (best coarse fit first), its ICP copy, and the bounds its poses are verified with.
  struct Region {
    Description description;
    std::vector<Match> matches;
    std::vector<Candidate> candidates;
    std::vector<Eigen::Vector3f> icp_source;
    OccupancyGrid grid;  // icp_source's occupied cells (MatchOptions::fit_cell_m): each starting pose's coarse fit
    double icp_points_dense = 0;  // icp_source's count, as if the sensor sampled it at least every 5 mm
    double smallest_diameter = 0;  // objects narrower than this cannot explain the region
    double pixel_m = 0;            // a pixel's width at the region's mean depth (0: no intrinsics)
    VerifyOptions verify;
    VerifyOptions near_miss;  // verify with the looser conflict bound of a pose the wrong way round
    bool try_near_misses = false;
    bool screen_done = false;  // prescreen has ordered its candidates
    std::vector<Transform> screened_poses;  // where the short ICP led each screened candidate
    // By object, where the short ICP led the screened candidates chosen for full refinement so far
    // (MatchOptions::merge_rotation_deg), kept through the votes pass (search_votes_alone): a
    // vote's pose led to one of them is the same place. Chosen one after another, on the calling
    // thread.
    mutable std::vector<std::vector<Transform>> refined_places;
    VerifyOptions partial;  // verify with min_cluster_explained lowered (SplitOptions::joint_min_cluster_explained)
    // The best pose so far that passed `partial` but not `verify` (with a confidence computed as if
    // it had), for search's `partial`.
    mutable std::optional<Detection> best_partial;
    VerifyOptions seed;  // verify without the model's support bound (SplitOptions::grow_reach_m)
    // The best pose that passed `seed` and was not accepted (its cluster_points: point_count).
    mutable std::optional<Detection> best_seed;
    // false: a whole cluster in search_region, whose search may go on with its parts (only
    // parts are grown: SplitOptions::grow_reach_m). (Other regions are searched without a seed.)
    bool gives_seed = true;
    // Its first `tried` candidates were refined already (a whole cluster's first batch, searched on
    // alone or with its parts; all of a region's views' poses, for its votes alone:
    // search_votes_alone): the search starts after them, within the same range for
    // challengers.
    std::size_t tried = 0;
    std::size_t point_count = 0;  // the region's points (the description keeps those with normals)
    // By object, the refined poses verification refused so far (try_candidates skips their
    // repeats). A region's batches are tried one after another, on the calling thread.
    mutable std::vector<std::vector<Transform>> refused;
    // A split cluster's part not described yet (pending_region): its points and the bounds it is
    // verified with. search describes it when its turn comes (describe_pending).
    std::optional<PointCloud> pending;
  };
  // The region described and matched, its starting poses ranked; nullopt when it has too few points
  // with normals.
  std::optional<Region> describe_region(const PointCloud& points, const FrameAndPlanes& frame, const VerifyOptions& verify,
                                        Recognition& out) const;
  // A region of these points, to be described by search when it reaches it (a split cluster's part:
  // with four parts or more the budget seldom reaches the smallest).
  static Region pending_region(PointCloud points, const VerifyOptions& verify);
  // Describes a pending region in place (describe_region); one with too few points with normals is
  // left with no starting poses.
  void describe_pending(Region& region, const FrameAndPlanes& frame, Recognition& out) const;
  // The regions' starting poses tried best first across them (screened by a short ICP, else by
  // coarse fit), within one budget (the convex parts of a cluster share it); the first accepted (or
  // the best), challenged and turned.
  // With `partial`: where nothing passes, the best pose that failed only by the share of its region
  // it explains (SplitOptions::joint_min_cluster_explained), if any and better than the one it holds
  // (a search that goes on keeps what it found before), for explain_jointly. With
  // `seed`: the best that met every bound but the model's support and was not accepted, to grow
  // (SplitOptions::grow_reach_m). Two or more regions (a split cluster's parts, and the whole
  // cluster's untried poses first: SplitOptions::whole_with_parts) each try their first batch,
  // within the budget, before the order across them. `max_poses`: at most this many poses spent
  // in this call (each region's range, which challengers are taken from, stays the budget's).
  // `found_in`: the index of the region the pose returned was found in; regions.size() when none is.
  std::optional<Detection> search(std::vector<Region>& regions, const FrameAndPlanes& frame, Recognition& out,
                                  std::optional<Detection>* partial = nullptr, bool votes = false,
                                  std::optional<Detection>* seed = nullptr,
                                  std::size_t max_poses = std::numeric_limits<std::size_t>::max(),
                                  std::size_t* found_in = nullptr) const;
  // The points of `points` within SplitOptions::grow_reach_m of `seed`'s model, the piece of them
  // it lies on (pose/points_on_model).
  PointCloud grown_region(const PointCloud& points, const Detection& seed) const;
  // `partial`'s points taken out of `points` and the rest searched; when the rest gives a detection
  // and `partial`, verified again on the points that one leaves, passes `verify`, both are added,
  // and what neither explains is recognized again (depth + 1). The rest is searched with the votes'
  // poses as well where the region was (`votes`).
  void explain_jointly(const PointCloud& points, const Detection& partial, const FrameAndPlanes& frame, const VerifyOptions& verify,
                       Recognition& out, int depth, bool votes) const;
  // Every roll of every matched view as a starting pose, best coarse fit first (called by
  // describe_region). With PoseSource ppf, the pair votes' poses instead, object by object
  // (interleave_by_object); with both and touching, search casts the votes where the views' poses
  // fail.
  std::vector<Candidate> rank_candidates(const Region& region, Recognition& out) const;
  // Each object's point pair vote poses for the region, with their coarse fit (the model's points
  // that face the camera standing in for a view's), object by object.
  std::vector<Candidate> pair_vote_candidates(const Region& region) const;
  // Each thin object's edge-on poses where the region is a strip as wide as it is thick
  // (MatchOptions::edge_on_turns), with their coarse fit as pair_vote_candidates gives it.
  std::vector<Candidate> edge_on_candidates(const Region& region) const;
  // The MatchOptions::prescreen starting poses from `from` on (best coarse fit first) refined by a
  // short ICP and put in the order of where it brought them (Candidate::priority), best first.
  void prescreen(Region& region, std::size_t from, Recognition& out) const;
  // Whether a screened pose is not to be refined in full: verification's quick test refuses it
  // where the short ICP led it (the camera sees past the model there; MatchOptions::prescreen says
  // why that is safe), counted in `out.screened_out`; or the short ICP led it where it led one the
  // region has refined already (MatchOptions::merge_rotation_deg), counted in
  // `out.screened_merged`. Such a pose keeps its place in the order and its share of the budget.
  // Tested only when its turn comes; where it passes, its place is recorded as chosen for full
  // refinement (the caller refines it, unless the deadline passes first).
  bool refused_after_screen(const Region& region, const Candidate& c, const FrameAndPlanes& frame, Recognition& out) const;
  // The starting poses `which` (indices into region.candidates), refined and verified together: the
  // first accepted in order (with take_best, the best). A batch in which nothing passes but one pose
  // fails only by its free-space conflicts has that pose's half turns tried at once.
  std::optional<Detection> try_candidates(const Region& region, std::span<const std::size_t> which, bool take_best,
                                          const FrameAndPlanes& frame, Recognition& out) const;
  // Other objects' next starting poses after position `next` (a few each, within `end`); a higher
  // verification score replaces `best`.
  void challenge(const Region& region, std::size_t next, std::size_t end, Detection& best, const FrameAndPlanes& frame,
                 Recognition& out) const;
  // `best` turned half a turn about each of its axes; the best of the four is kept.
  void turn_if_better(const Region& region, Detection& best, const FrameAndPlanes& frame, Recognition& out) const;
  Detection detection_from(const Refined& h, const Region& region, const Candidate& c) const;
  // Whether a pose that passed verification (`passed`) with `confidence` would be the frame's most
  // confident below the bound so far (Recognition::best_below_min_score); keep_below_min_score
  // keeps it, unless it lies inside a removed plane (a lower bound would refuse it there too).
  bool beats_best_below_min_score(bool passed, double confidence, const Recognition& out) const;
  void keep_below_min_score(Detection d, const FrameAndPlanes& frame, Recognition& out) const;
  // A cluster, or what is left of one: recognized whole, else split into convex parts; once a part
  // is recognized, its object's points are taken away and the rest recognized again (depth + 1).
  // With PoseSource touching, what a detection left is searched with the views' poses, whole and in
  // parts, before any vote is cast in it (MatchOptions::votes_after_parts; votes are cast meanwhile
  // in what a pose kept there leaves and in a region grown from a part's seed, and one too wide to
  // be searched whole has its votes in its parts, after each part's views).
  void recognize_region(const PointCloud& points, const FrameAndPlanes& frame, Recognition& out, int depth) const;
  // Where a region's search casts point pair votes: in the region itself and its parts, and in
  // what its poses leave to search apart (a kept pose's rest, a region grown from a part's seed).
  struct RegionVotes {
    bool region = false;
    bool rest = false;
  };
  // recognize_region's search; `size`: the diagonal of the points' bounding box. `whole_searched`,
  // if given: the whole region, when it was described and its poses failed and are not searched
  // on with its parts (at depth above 0, always so).
  void search_region(const PointCloud& points, double size, const FrameAndPlanes& frame, Recognition& out, int depth,
                     RegionVotes cast, std::optional<Region>* whole_searched) const;
  // The votes' poses alone in a whole region whose views' poses search_region tried (its refused
  // poses kept), and what a detection or a kept pose there leaves.
  void search_votes_alone(const PointCloud& points, Region whole, const FrameAndPlanes& frame, Recognition& out, int depth) const;
  // A piece of the frame no detection explains: a cluster no detection reaches, or a cluster of
  // what detections leave of one.
  struct Piece {
    PointCloud points;
    BoundingBox box;
    float depth_m = 0;  // mean
  };
  // The frame's pieces no wider than `widest`, and nearer than where the depth noise verification
  // allows (uncapped) reaches the clusters' gap.
  std::vector<Piece> unexplained_pieces(const Segmentation& seg, std::span<const Detection> detections, double widest) const;
  // Pairs of those pieces near each other and cut apart by missing depth (SplitOptions::
  // join_gap_m), each searched as one region, nearest first; what passes is added.
  void join_fragments(const Segmentation& seg, const FrameAndPlanes& frame, Recognition& out) const;
  // `verify` tightened for a part of a region (SplitOptions::part_*).
  VerifyOptions part_verify_options() const;
  // Adds the detection, then recognizes what of `points` it leaves unexplained (depth + 1).
  void recognize_rest(const PointCloud& points, Detection detection, const FrameAndPlanes& frame, Recognition& out, int depth) const;
  // Which of `points` (camera frame) lie on the detected model's surface, within the verification tolerance.
  std::vector<char> explained_points(const Detection& detection, const PointCloud& points) const;
  // The Euclidean clusters of the points `explained` leaves out (timed as splitting).
  std::vector<Cluster> unexplained_clusters(const PointCloud& points, const std::vector<char>& explained, Recognition& out) const;

  std::shared_ptr<const ViewDatabase> db_owner_;  // empty-owned when the caller keeps the database
  const ViewDatabase& db_;
  RecognizerOptions options_;
  // One initial pose refined by ICP and, unless ICP lost the object, verified.
  struct Refined {
    IcpResult icp;
    Transform T_camera_object = Transform::Identity();
    Verification v;
    bool verified = false;
    bool repeat = false;  // not verified: ICP brought it onto a pose already refused
    double confidence = 0;  // pose_confidence(v), for those v passes
    bool accepted = false;  // v passes, the confidence reaches min_confidence, and it lies in no plane
    bool sunk = false;  // v passed, but the pose sank into a plane and failed lifted onto it (lift_out_of_planes)
    double icp_ms = 0, verify_ms = 0;
  };
  // An initial pose of an object.
  struct Hypothesis {
    std::uint32_t object = 0;
    Transform T_camera_object = Transform::Identity();
    bool screened = false;  // where the screen led it: refined from the schedule's second stage
  };
  // Each hypothesis refined and verified, in parallel when allowed; the results in the order given,
  // so that what is made of them does not depend on the threads. Those ICP brings onto a pose in
  // `refused` (by object; may be null) are not verified. A pose that passes but lies inside a plane
  // is not accepted, and counted in `out` (Recognition::dropped_inside_planes), as are the times;
  // one sunk a little into a plane is lifted onto it and verified again (lift_out_of_planes).
  std::vector<Refined> refine_and_verify(std::span<const Hypothesis> hypotheses, std::span<const Eigen::Vector3f> icp_source,
                                         std::span<const Eigen::Vector3f> cluster, const FrameAndPlanes& frame,
                                         const VerifyOptions& verify, Recognition& out,
                                         const std::vector<std::vector<Transform>>* refused = nullptr) const;
  // `T_camera_object` turned half a turn about each of `object`'s axes, as hypotheses of it.
  std::vector<Hypothesis> half_turns(const Transform& T_camera_object, std::uint32_t object) const;
  // What ICP and verification need of an object, made when the recognizer is (small databases,
  // RunOptions::prepare_objects_up_to) or on its first hypothesis: a database of a thousand objects
  // costs nothing for the objects a scene never suggests. The drawing mesh and the grid's cells are
  // taken from the database where it stores them for these options.
  static constexpr std::size_t kPlaneTestPoints = 2000;
  struct PreparedObject {
    std::once_flag once;
    std::unique_ptr<IcpTarget> target;
    OccupancyGrid occupancy;  // of the model points, for coarse_fit
    TriangleMesh drawn;      // the mesh verification draws (simplified)
    int closed_winding = 0;  // closed_mesh_winding of `drawn`
    // Its z, and where its symmetries turn z elsewhere (a cube's), those too: the axes it may stand
    // on (stand_on_resting_planes).
    std::vector<Eigen::Vector3d> standing_axes;
    BoundingBox model_box;  // of the model points (a detection's reach, join_fragments)
    PrincipalAxes axes;     // of the model points (edge_on_candidates)
    std::vector<Eigen::Vector3f> plane_test_points;  // at most kPlaneTestPoints of them, evenly through their order (inside_planes)
    std::once_flag ppf_once;  // the pair table is made only where pair votes are asked for
    std::unique_ptr<PpfModel> ppf;
  };
  const PreparedObject& prepared(std::uint32_t object) const;
  // The object's pair table; null where its model gives none (fewer than two oriented points).
  const PpfModel* pair_table(std::uint32_t object) const;
  const IcpTarget& icp_target(std::uint32_t object) const { return *prepared(object).target; }
  // Past the deadline (and marks `out` cut short): no further views, parts or checks are tried.
  bool out_of_time(Recognition& out) const;
  // Drops the detections whose pixels more confident ones already explain (AcceptOptions::
  // resolve_scene_claims; pose/scene_claims: claimed_pixels, resolve_claims).
  void resolve_scene(const FrameAndPlanes& frame, Recognition& out) const;
  // Each symmetric object that stands on one of the frame's removed planes reported standing on it
  // as modelled (canonical_pose with the plane's up; search chose with the camera's default up).
  // Timed as verification.
  void stand_on_resting_planes(std::span<const Plane> planes, Recognition& out) const;
  // Whether `object`'s model at `T_camera_object` lies inside one of the frame's removed planes
  // (AcceptOptions::max_share_inside_planes).
  bool inside_planes(std::uint32_t object, const Transform& T_camera_object, const FrameAndPlanes& frame) const;
  // AcceptOptions::lift_out_of_planes on `h`, a pose of `object` accepted in `cluster`: lifted out
  // of the plane it sank into and verified again, or refused.
  void lift_out_of_planes(std::uint32_t object, Refined& h, std::span<const Eigen::Vector3f> cluster, const FrameAndPlanes& frame,
                          const VerifyOptions& verify, Recognition& record) const;
  // Drops the detections whose models lie inside a removed plane: those of the ways that verify a
  // pose without refine_and_verify (a pose explained jointly with another).
  void drop_inside_planes(const FrameAndPlanes& frame, Recognition& out) const;
  // A cluster's own record (RunOptions::parallel_clusters) added to the frame's: its detections
  // after those before, its counts and stage times summed.
  static void merge_part(Recognition&& part, Recognition& out);
  // What verification draws of an object.
  VerifyModel verify_model(std::uint32_t object) const;

  std::vector<std::unique_ptr<PreparedObject>> prepared_;  // one per object
  // The pair tables of a database loaded without them (ViewDatabase::pair_tables_on_disk), read
  // when the first object's table is first asked for (its first vote; with ppf or both and a
  // database of at most RunOptions::prepare_objects_up_to objects, when the recognizer is made);
  // each handed to its object's PpfModel; empty where unreadable (the tables are then made from
  // the models). A database loaded for ppf or both has read them already (database_load_options).
  mutable std::once_flag tables_on_disk_once_;
  mutable std::vector<std::shared_ptr<const PpfTable>> tables_on_disk_;
  ViewIndex index_;
  double largest_diameter_m_ = 0;
  // The short ICP's screen (prescreen): the schedule's coarse stages on few points, few steps each;
  // the share of a region brought within the final stage's reach, screen_reach_m_, ranks a pose.
  IcpOptions screen_icp_;
  float screen_reach_m_ = 0.01f;
  // The full schedule without its first stage, for the poses the screen led
  // (MatchOptions::refine_from_screen).
  IcpOptions after_screen_icp_;
};

}  // namespace viewpose
