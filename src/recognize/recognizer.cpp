#include "viewpose/recognize/recognizer.hpp"

#include "viewpose/core/stopwatch.hpp"
#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <mutex>
#include <limits>
#include <span>

#include <omp.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/database/matching.hpp"
#include "viewpose/pose/coarse_fit.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/pose/points_on_model.hpp"
#include "viewpose/pose/resting_plane.hpp"
#include "viewpose/pose/through_planes.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/recognize/candidate_order.hpp"
#include "viewpose/render/simplify.hpp"
#include "viewpose/segment/convex_segments.hpp"
#include "viewpose/segment/depth_gaps.hpp"
#include "viewpose/segment/voxel_grid.hpp"

namespace viewpose {

namespace {

// body(i) for every i in [0, n), on several threads when `parallel`. Within a parallel region (a
// frame's clusters searched side by side, RunOptions::parallel_clusters) as tasks of `grain`
// indices, which a thread with no cluster left takes up: a frame's largest cluster is often most
// of its work, and its stages no longer run on one thread while the other waits. (A thread that
// waits for its own tasks runs only those.) Outside one, a parallel loop of its own. Each index
// once, its result kept by index: the same whichever thread runs it.
template <class Body>
void for_each_index(std::ptrdiff_t n, bool parallel, std::ptrdiff_t grain, const Body& body) {
  if (!parallel || n <= 1) {
    for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
    return;
  }
  FirstException failed;
  if (omp_in_parallel()) {
    // (Unsigned: clang compares the loop's bound with its own unsigned count of iterations.)
    const auto count = static_cast<std::size_t>(n), chunk = static_cast<std::size_t>(grain);
#pragma omp taskloop grainsize(chunk) shared(body, failed)
    for (std::size_t i = 0; i < count; ++i) failed.run(static_cast<std::ptrdiff_t>(i), [&] { body(static_cast<std::ptrdiff_t>(i)); });
  } else {
#pragma omp parallel for schedule(dynamic, grain)
    for (std::ptrdiff_t i = 0; i < n; ++i) failed.run(i, [&] { body(i); });
  }
  failed.rethrow();
}

// The width of clouds together: the largest of their extents along the axes and the diagonals of
// a cube, within 6 % of their diameter (any direction lies within 20 degrees of one of these). A
// bounding box's diagonal overstates it up to 1.7 times (a jug's visible surface's by 7 %).
double width_of(std::initializer_list<const PointCloud*> clouds) {
  static const std::array<Eigen::Vector3f, 13> directions = [] {
    std::array<Eigen::Vector3f, 13> d{};
    std::size_t k = 0;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          // One of each opposite pair: the first non-zero coordinate positive.
          if (x > 0 || (x == 0 && (y > 0 || (y == 0 && z > 0)))) d[k++] = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)).normalized();
        }
    return d;
  }();
  Eigen::Matrix<float, 13, 1> lo = Eigen::Matrix<float, 13, 1>::Constant(std::numeric_limits<float>::infinity());
  Eigen::Matrix<float, 13, 1> hi = -lo;
  bool any = false;
  for (const PointCloud* cloud : clouds) {
    for (const Eigen::Vector3f& p : cloud->points) {
      any = true;
      for (std::size_t k = 0; k < directions.size(); ++k) {
        const auto i = static_cast<Eigen::Index>(k);
        const float x = directions[k].dot(p);
        lo[i] = std::min(lo[i], x);
        hi[i] = std::max(hi[i], x);
      }
    }
  }
  return any ? static_cast<double>((hi - lo).maxCoeff()) : 0.0;
}

// Whether T lies within `metres` and `degrees` of one of `poses` (a pose refused or a place refined
// already: MatchOptions::refused_rotation_deg, merge_rotation_deg).
bool near_any(std::span<const Transform> poses, const Transform& T, double metres, double degrees) {
  return std::any_of(poses.begin(), poses.end(), [&](const Transform& U) {
    return (T.translation() - U.translation()).norm() <= metres && rotation_difference_deg(T.linear(), U.linear()) <= degrees;
  });
}

// The clusters of the points not `explained` (indices into `points`).
std::vector<Cluster> clusters_of_unexplained(const PointCloud& points, const std::vector<char>& explained, const ClusterOptions& options) {
  std::vector<std::uint32_t> rest;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (!explained[i]) rest.push_back(i);
  }
  if (rest.size() < options.min_points) return {};  // (too few for any cluster: most found objects')
  return euclidean_clusters(points, rest, options);
}

}  // namespace

PoseSource pose_source_from_name(std::string_view name) {
  for (std::size_t i = 0; i < std::size(kPoseSourceNames); ++i) {
    if (name == kPoseSourceNames[i]) return static_cast<PoseSource>(i);
  }
  throw Error(fmt::format("source: \"{}\" is none of {}", name, fmt::join(kPoseSourceNames, ", ")));
}

Recognizer::Recognizer(const ViewDatabase& db, RecognizerOptions options)
    // Not owned: a shared_ptr that points at the caller's database and owns nothing.
    : Recognizer(std::shared_ptr<const ViewDatabase>(std::shared_ptr<void>(), &db), std::move(options)) {}

Recognizer::Recognizer(ViewDatabase&& db, RecognizerOptions options)
    : Recognizer(std::make_shared<const ViewDatabase>(std::move(db)), std::move(options)) {}

Recognizer::Recognizer(std::shared_ptr<const ViewDatabase> shared, RecognizerOptions options)
    : db_owner_(shared ? std::move(shared) : throw Error("recognize: no view database given")),
      db_(*db_owner_),
      options_(std::move(options)),
      index_(db_) {
  const ViewDatabase& db = db_;
  if (db.views.empty()) throw Error("recognize: the view database holds no views");
  for (const DatabaseObject& o : db.objects) {
    prepared_.push_back(std::make_unique<PreparedObject>());
    largest_diameter_m_ = std::max(largest_diameter_m_, o.diameter_m);
  }
  // Pair tables may be made later, on a cluster's thread: their options are checked now.
  if (options_.match.source != PoseSource::vfh) check_ppf_options(options_.match.ppf);
  if (!(options_.split.join_gap_m >= 0 && options_.split.join_gap_m <= 1)) {
    throw Error(fmt::format("recognize: the gap between pieces joined is {} m, not within 0-1 m", options_.split.join_gap_m));
  }
  if (!(options_.split.grow_reach_m >= 0 && options_.split.grow_reach_m <= 1)) {
    throw Error(fmt::format("recognize: a part's pose is grown {} m around its model, not within 0-1 m", options_.split.grow_reach_m));
  }
  if (!(options_.match.merge_rotation_deg >= 0 && options_.match.merge_share >= 0)) {
    throw Error(fmt::format("recognize: screened poses are merged within {} degrees and {} of the diameter: neither may be negative or NaN",
                            options_.match.merge_rotation_deg, options_.match.merge_share));
  }
  if (!(options_.accept.max_share_inside_planes >= 0 && options_.accept.max_share_inside_planes <= 1)) {
    throw Error(fmt::format("recognize: the share of a model allowed inside a plane is {}, not within 0-1", options_.accept.max_share_inside_planes));
  }
  if (db.objects.size() <= options_.run.prepare_objects_up_to) {
    // Each object on a thread.
    const auto each_object = [&](const auto& prepare) {
      const auto objects = static_cast<std::ptrdiff_t>(db.objects.size());
      FirstException failed;
#pragma omp parallel for schedule(dynamic, 1)
      for (std::ptrdiff_t o = 0; o < objects; ++o) failed.run(o, [&] { prepare(static_cast<std::uint32_t>(o)); });
      failed.rethrow();
    };
    each_object([&](std::uint32_t o) { icp_target(o).grid(options_.icp.grid_cell_m, options_.icp.reach_m()); });
    // (With touching, only the objects voted for in a detection's rest: made on first use.)
    if (options_.match.source == PoseSource::ppf || options_.match.source == PoseSource::both) {
      each_object([&](std::uint32_t o) { pair_table(o); });
    }
    for (std::uint32_t o = 0; o < db.objects.size() && options_.run.fill_grids_at_start; ++o) {
      if (const NearestGrid* grid = icp_target(o).grid(options_.icp.grid_cell_m, options_.icp.reach_m())) grid->fill_all();  // (nothing to do where stored)
    }
  }
  // Scenes are described at the database's resolution, so that their VFHs are comparable.
  if (options_.segment.voxel_m != SegmentOptions{}.voxel_m && options_.segment.voxel_m != db.params.voxel_m) {
    throw Error(fmt::format("recognize: scenes are described at the database's voxel size ({} mm), not {} mm: "
                            "build the database at the size wanted",
                            db.params.voxel_m * 1000, options_.segment.voxel_m * 1000));
  }
  options_.segment.voxel_m = db.params.voxel_m;
  // The screen's schedule: the coarse stages, few steps on few points (where a pose leads); judged
  // by the share brought within the final stage's reach (at the second stage's 2 cm most poses of
  // the right size bring nearly all of a region: no order).
  screen_icp_ = options_.icp;
  if (!screen_icp_.max_correspondence_m.empty()) screen_reach_m_ = screen_icp_.max_correspondence_m.back();
  if (screen_icp_.max_correspondence_m.size() > 1) screen_icp_.max_correspondence_m.pop_back();
  screen_icp_.max_iterations_per_stage = options_.match.prescreen_iterations;
  screen_icp_.max_source_points = options_.match.prescreen_points;
  screen_icp_.min_fitness_after_first_stage = 0;
  // What the screen led is refined without the first stage (a one-stage schedule: all of it).
  after_screen_icp_ = options_.icp;
  if (after_screen_icp_.max_correspondence_m.size() > 1) after_screen_icp_.max_correspondence_m.erase(after_screen_icp_.max_correspondence_m.begin());
}

Recognizer::~Recognizer() = default;

const Recognizer::PreparedObject& Recognizer::prepared(std::uint32_t object) const {
  PreparedObject& p = *prepared_[object];
  std::call_once(p.once, [&] {
    const DatabaseObject& o = db_.objects[object];
    const DatabaseParams& made = db_.params;  // what the database's prepared data was made with
    p.target = std::make_unique<IcpTarget>(o.model_points, o.model_normals);
    const float cell_m = options_.icp.grid_cell_m, reach_m = options_.icp.reach_m();
    if (!o.nearest_cells.empty() && cell_m == made.grid_cell_m && reach_m == made.grid_margin_m) {
      p.target->grid(cell_m, reach_m, o.nearest_cells);
    }
    p.occupancy = OccupancyGrid(o.model_points, options_.match.fit_cell_m);
    const float error_m = options_.verify_mesh_error_m;
    if (error_m > 0 && error_m == made.drawn_mesh_error_m && !o.drawn_mesh.triangles.empty()) {
      p.drawn = o.drawn_mesh;
    } else {
      p.drawn = error_m > 0 ? simplify_for_drawing(o.mesh, error_m) : o.mesh;
    }
    p.closed_winding = closed_mesh_winding(p.drawn);
    p.model_box = bounding_box(o.model_points);
    // Every k-th model point, at most kPlaneTestPoints: the share inside a plane is a fraction,
    // judged against 2 %, and is asked of every pose that passes (half turns too), where the 3 mm
    // model grid of a 30 cm jug holds 30,000 points.
    const std::size_t stride = std::max<std::size_t>(1, (o.model_points.size() + kPlaneTestPoints - 1) / kPlaneTestPoints);
    for (std::size_t i = 0; i < o.model_points.size(); i += stride) p.plane_test_points.push_back(o.model_points[i]);
    p.standing_axes = {Eigen::Vector3d::UnitZ()};
    for (const Transform& S : o.symmetries.discrete) p.standing_axes.push_back(S.linear().col(2));
  });
  return p;
}

const PpfModel* Recognizer::pair_table(std::uint32_t object) const {
  PreparedObject& p = *prepared_[object];
  std::call_once(p.ppf_once, [&] {
    const DatabaseObject& o = db_.objects[object];
    // (The options were checked when the recognizer was made: what fails here is the model, which
    // then gives no votes, once, rather than an error in every region.)
    // The database's table where it was made as these options would make it.
    try {
      std::shared_ptr<const PpfTable> stored = o.pair_table;
      if (!stored && db_.pair_tables_on_disk) {
        std::call_once(tables_on_disk_once_, [&] {
          // A file gone or rebuilt since it was loaded (or too large to read now) gives none: each
          // table is then made from its model below, as for a database that stores none (the same
          // table, made slower). Nothing may escape: this can run inside a cluster's task.
          try {
            tables_on_disk_ = read_stored_pair_tables(db_);
          } catch (const std::exception&) {
            tables_on_disk_.clear();
          }
        });
        // (Each object's entry is read once, under its own flag: handed over, not kept twice.)
        if (object < tables_on_disk_.size()) stored = std::move(tables_on_disk_[object]);
      }
      if (stored && stored->made_with(options_.match.ppf)) {
        p.ppf = std::make_unique<PpfModel>(stored, options_.match.ppf);
      } else {
        p.ppf = std::make_unique<PpfModel>(o.model_points, o.model_normals, o.diameter_m, options_.match.ppf);
      }
    } catch (const Error&) {
      p.ppf.reset();
    }
  });
  return p.ppf.get();
}

VerifyModel Recognizer::verify_model(std::uint32_t object) const {
  const DatabaseObject& o = db_.objects[object];
  const PreparedObject& p = prepared(object);
  return {&p.drawn, o.model_points, db_.params.voxel_m, p.closed_winding, o.model_normals};
}

bool Recognizer::out_of_time(Recognition& out) const {
  if (options_.run.deadline_ms > 0 && ms_since(out.started) > options_.run.deadline_ms) out.cut_short = true;
  return out.cut_short;
}

Recognition Recognizer::recognize(const Frame& frame) const {
  const auto start = Clock::now();
  Recognition out;
  out.started = start;
  SegmentTimes seg_times;
  const Segmentation seg = segment_scene(frame.cloud, options_.segment, &seg_times);
  out.times.downsample_ms = seg_times.downsample_ms;
  out.times.segment_ms = seg_times.planes_ms + seg_times.clusters_ms;
  out.clusters = seg.clusters.size();
  const FrameAndPlanes seen{frame.depth, frame.K, seg.planes};
  const std::size_t n = seg.clusters.size();
  const bool side_by_side = options_.run.parallel_clusters && options_.run.parallel_hypotheses && n > 1 &&
                            !options_.accept.on_verified && thread_count() > 1;
  if (!side_by_side) {
    for (const Cluster& cluster : seg.clusters) {
      if (out_of_time(out)) break;
      recognize_region(cluster_points(seg.points, cluster), seen, out, 0);
    }
  } else {
    // Each cluster on its own record, largest first (the longest searches start early), merged in
    // the clusters' order.
    std::vector<Recognition> parts(n);
    std::vector<std::size_t> order(n);
    for (std::size_t c = 0; c < n; ++c) order[c] = c;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return seg.clusters[a].size() > seg.clusters[b].size(); });
    // Each cluster a task: a thread with no cluster left takes up the tasks of another's stages.
    FirstException failed;
#pragma omp parallel
#pragma omp single
    for (const std::size_t c : order) {
#pragma omp task firstprivate(c) shared(parts, seg, seen, start, failed)
      failed.run(static_cast<std::ptrdiff_t>(c), [&] {
        Recognition& part = parts[c];
        part.started = start;
        if (!out_of_time(part)) recognize_region(cluster_points(seg.points, seg.clusters[c]), seen, part, 0);
      });
    }
    failed.rethrow();
    for (Recognition& part : parts) merge_part(std::move(part), out);
  }
  if (options_.split.enabled && options_.split.join_gap_m > 0 && !out_of_time(out)) join_fragments(seg, seen, out);
  if (!out.detections.empty()) drop_inside_planes(seen, out);
  // (Before the claims: they are judged at the poses reported.)
  if (options_.accept.canonical_poses && !seg.planes.empty() && !out.detections.empty()) stand_on_resting_planes(seg.planes, out);
  if (options_.accept.resolve_scene_claims && out.detections.size() > 1) resolve_scene(seen, out);
  out.times.total_ms = ms_since(start);
  return out;
}

bool Recognizer::inside_planes(std::uint32_t object, const Transform& T_camera_object, const FrameAndPlanes& frame) const {
  if (!(options_.accept.max_share_inside_planes < 1) || frame.planes.empty()) return false;
  // Beyond the plane's own inlier band and what verification tolerates at the object's depth
  // (as stand_on_resting_planes judges touching).
  const float margin_m = options_.segment.planes.distance_threshold_m +
                         depth_tolerance(static_cast<float>(T_camera_object.translation().z()), options_.verify);
  return share_inside_planes(frame.planes, frame.depth, frame.K, prepared(object).plane_test_points, T_camera_object, margin_m) >
         options_.accept.max_share_inside_planes;
}

void Recognizer::lift_out_of_planes(std::uint32_t object, Refined& h, std::span<const Eigen::Vector3f> cluster,
                                    const FrameAndPlanes& frame, const VerifyOptions& verify, Recognition& record) const {
  if (!options_.accept.lift_out_of_planes || frame.planes.empty()) return;
  // Sunk by more than the sensor's noise at its depth, as many of its points as inside_planes
  // counts (deeper than inside_planes' margin, more of them than that, it was refused already).
  const float noise_m = depth_tolerance(static_cast<float>(h.T_camera_object.translation().z()), options_.verify);
  const float margin_m = options_.segment.planes.distance_threshold_m + noise_m;
  const PlaneSink sink = sink_into_planes(frame.planes, frame.depth, frame.K, prepared(object).plane_test_points, h.T_camera_object,
                                          margin_m, options_.accept.max_share_inside_planes);
  if (sink.plane < 0 || !(sink.depth_m > noise_m)) return;
  const Eigen::Vector3d up = frame.planes[static_cast<std::size_t>(sink.plane)].coefficients.head<3>().cast<double>();
  Transform lifted = h.T_camera_object;
  lifted.translation() += static_cast<double>(sink.depth_m) * up;
  const Verification v = verify_pose(verify_model(object), lifted, frame.depth, frame.K, cluster, verify);
  const double confidence = v.accepted ? pose_confidence(v) : 0.0;
  if (v.accepted && confidence >= options_.accept.min_confidence) {
    h.T_camera_object = lifted;
    h.v = v;
    h.confidence = confidence;
    ++record.lifted_out_of_planes;
  } else {
    h.accepted = false;
    h.sunk = true;
    ++record.dropped_inside_planes;
  }
}

void Recognizer::drop_inside_planes(const FrameAndPlanes& frame, Recognition& out) const {
  const auto t = Clock::now();
  const std::size_t before = out.detections.size();
  std::erase_if(out.detections, [&](const Detection& d) { return inside_planes(d.object_index, d.T_camera_object, frame); });
  out.dropped_inside_planes += before - out.detections.size();
  out.times.verify_ms += ms_since(t);
}

void Recognizer::stand_on_resting_planes(std::span<const Plane> planes, Recognition& out) const {
  const auto t = Clock::now();
  std::vector<Eigen::Vector4f> coefficients;
  for (const Plane& plane : planes) coefficients.push_back(plane.coefficients);
  for (Detection& d : out.detections) {
    const DatabaseObject& object = db_.objects[d.object_index];
    if (object.symmetries.empty()) continue;
    // Touching within the plane's own inlier band (its surface as measured) and what verification
    // tolerates of the pose at the object's depth.
    const float touch_m = options_.segment.planes.distance_threshold_m +
                          depth_tolerance(static_cast<float>(d.T_camera_object.translation().z()), options_.verify);
    const std::vector<Eigen::Vector3d>& standing_axes = prepared(d.object_index).standing_axes;
    if (const std::optional<Eigen::Vector3d> up = resting_plane_up(coefficients, object.model_points, d.T_camera_object, standing_axes, touch_m)) {
      d.T_camera_object = canonical_pose(d.T_camera_object, object.symmetries, *up);
    }
  }
  out.times.verify_ms += ms_since(t);
}

void Recognizer::merge_part(Recognition&& part, Recognition& out) {
  for (Detection& d : part.detections) out.detections.push_back(std::move(d));
  out.times += part.times;  // (a part's segmentation and total are 0: the frame's are its own)
  out.hypotheses += part.hypotheses;
  out.repeats += part.repeats;
  out.screened += part.screened;
  out.screened_out += part.screened_out;
  out.screened_merged += part.screened_merged;
  out.icp_steps += part.icp_steps;
  out.split_clusters += part.split_clusters;
  out.regions += part.regions;
  out.parts_unreached += part.parts_unreached;
  out.dropped_as_explained += part.dropped_as_explained;
  out.dropped_inside_planes += part.dropped_inside_planes;
  out.lifted_out_of_planes += part.lifted_out_of_planes;
  out.joined_regions += part.joined_regions;
  out.grown_regions += part.grown_regions;
  out.voted_regions += part.voted_regions;
  out.cut_short = out.cut_short || part.cut_short;
}

void Recognizer::resolve_scene(const FrameAndPlanes& frame, Recognition& out) const {
  const auto t = Clock::now();
  std::vector<std::size_t> order(out.detections.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  // The most trusted first: confidence, then how well the pose fits (confidences saturate near 1).
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Detection &da = out.detections[a], &db = out.detections[b];
    if (da.score != db.score) return da.score > db.score;
    return da.verification.score > db.verification.score;
  });
  std::vector<std::vector<std::uint32_t>> claims(order.size());
  for_each_index(static_cast<std::ptrdiff_t>(order.size()), options_.run.parallel_hypotheses, 1, [&](std::ptrdiff_t k) {
    const Detection& d = out.detections[order[static_cast<std::size_t>(k)]];
    claims[static_cast<std::size_t>(k)] =
        claimed_pixels(verify_model(d.object_index), d.T_camera_object, frame.depth, frame.K, options_.verify);
  });
  const std::vector<ClaimVerdict> verdicts = resolve_claims(claims, options_.accept.scene_claims);
  std::vector<char> keep(order.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) keep[order[k]] = verdicts[k].kept ? 1 : 0;
  std::vector<Detection> kept;
  for (std::size_t i = 0; i < out.detections.size(); ++i) {
    if (keep[i]) kept.push_back(std::move(out.detections[i]));
  }
  out.dropped_as_explained += out.detections.size() - kept.size();
  out.detections = std::move(kept);
  out.times.verify_ms += ms_since(t);
}

void Recognizer::recognize_region(const PointCloud& points, const FrameAndPlanes& frame, Recognition& out, int depth) const {
  const PoseSource source = options_.match.source;
  // Point pair votes after the views' poses: everywhere (both), or in what a detection left (depth
  // above 0: an object touching the one found).
  const bool votes = source == PoseSource::both || (source == PoseSource::touching && depth > 0);
  const double size = bounding_box(points.points).diagonal();
  if (source == PoseSource::touching && depth > 0 && options_.match.votes_after_parts &&
      size <= options_.match.max_region_size_factor * largest_diameter_m_) {
    // What a detection left: the views' poses, whole and in parts; where nothing passes, votes in
    // the whole of it, described once. (One too wide to be searched whole has votes in its parts,
    // below.) What the views' poses leave to search apart (a kept pose's rest, a region grown from
    // a part's seed) is searched with votes, as without the option.
    const std::size_t before = out.detections.size();
    std::optional<Region> whole;
    search_region(points, size, frame, out, depth, {.region = false, .rest = true}, &whole);
    if (out.detections.size() == before && whole && !out_of_time(out)) search_votes_alone(points, std::move(*whole), frame, out, depth);
    return;
  }
  search_region(points, size, frame, out, depth, {.region = votes, .rest = votes}, nullptr);
}

void Recognizer::search_votes_alone(const PointCloud& points, Region whole, const FrameAndPlanes& frame, Recognition& out, int depth) const {
  // Its views' poses were tried: they count as tried, and the poses refused there stay refused (a
  // vote's pose refined to within MatchOptions::refused_rotation_deg and refused_translation_m of
  // one is not verified again), as do the places its screened poses were refined from (a vote's
  // pose the screen leads to one is not refined: MatchOptions::merge_rotation_deg). The pose it
  // kept as explaining part of the region was offered to explain_jointly there: the votes' search
  // starts without one, as on a region described afresh. (It keeps no seed: a whole region gives
  // none.)
  whole.tried = whole.candidates.size();
  whole.best_partial.reset();
  std::vector<Region> regions;
  regions.push_back(std::move(whole));
  std::optional<Detection> partial;  // a pose that explains part of the region well
  if (std::optional<Detection> det = search(regions, frame, out, &partial, true)) {
    det->from_split_cluster = depth > 0;
    recognize_rest(points, std::move(*det), frame, out, depth);
  } else if (partial && options_.split.enabled && !out_of_time(out)) {
    explain_jointly(points, *partial, frame, part_verify_options(), out, depth, true);
  }
}

void Recognizer::search_region(const PointCloud& points, double size, const FrameAndPlanes& frame, Recognition& out, int depth,
                               RegionVotes cast, std::optional<Region>* whole_searched) const {
  // Anything found inside a split cluster stands on less evidence than an isolated cluster, and is
  // checked more strictly.
  const VerifyOptions part_verify = part_verify_options();
  // Verification gives no verdict past its range (VerifyOptions::max_depth_m): a region that lies
  // beyond it is not tried at all, rather than tried against every view to no end.
  if (points.size() > 0) {
    double z = 0;
    for (const auto& p : points.points) z += p.z();
    if (z / static_cast<double>(points.size()) > options_.verify.max_depth_m) return;
  }
  const bool votes = cast.region;
  const bool rest_votes = cast.rest;
  std::optional<Detection> partial;  // a pose that explains part of the region well (joint_min_cluster_explained)
  // A cluster whose first batch of poses fails goes on in one budget with its convex parts, if it
  // has any (SplitOptions::whole_with_parts).
  const bool every = options_.accept.keep_best || options_.match.max_hypotheses == 0;
  // (A budget of one batch or less is the whole region's alone, then its parts', as without it.)
  const std::size_t first_batch = std::max<std::size_t>(1, options_.run.batch);
  const bool whole_with_parts = options_.split.whole_with_parts && depth == 0 && !votes && !every && options_.match.max_hypotheses > first_batch;
  // The whole region, described and searched alone (with whole_with_parts, its first batch); where
  // that fails and poses are left, kept to go on with them (Region::tried), else emptied.
  std::vector<Region> whole;
  if (size <= options_.match.max_region_size_factor * largest_diameter_m_) {
    if (std::optional<Region> region = describe_region(points, frame, depth > 0 ? part_verify : options_.verify, out)) {
      // (Alone or with its parts, a whole cluster's pose is no seed to grow: its piece is the cluster.)
      region->gives_seed = false;
      whole.push_back(std::move(*region));
    }
    std::optional<Detection> det = search(whole, frame, out, &partial, votes, nullptr,
                                          whole_with_parts ? first_batch : std::numeric_limits<std::size_t>::max());
    if (det) {
      det->from_split_cluster = depth > 0;
      recognize_rest(points, std::move(*det), frame, out, depth);
      return;
    }
    if (whole_with_parts && !whole.empty() && whole[0].candidates.size() > first_batch) {
      whole[0].tried = first_batch;
    } else {
      if (whole_searched && !whole.empty()) *whole_searched = std::move(whole[0]);
      whole.clear();
    }
  }
  // The rest of the whole region's poses, alone, where it has no parts to share them with: as its
  // search alone would have gone on, screened, within what is left of its budget.
  const auto search_on_alone = [&]() {
    if (whole.empty() || out_of_time(out)) return false;
    std::optional<Detection> det = search(whole, frame, out, &partial, votes, nullptr, options_.match.max_hypotheses - first_batch);
    whole.clear();
    if (!det) return false;
    recognize_rest(points, std::move(*det), frame, out, depth);
    return true;
  };
  // Nothing passed: the region may be objects touching each other. Try its convex parts, largest
  // first (a pile of a few objects: SplitOptions::max_size_factor, min_size_m).
  if (!options_.split.enabled || depth >= options_.split.max_depth ||
      size > std::max(options_.split.min_size_m, options_.split.max_size_factor * largest_diameter_m_) || out_of_time(out)) {
    if (search_on_alone()) return;
    if (partial && options_.split.enabled && !out_of_time(out)) explain_jointly(points, *partial, frame, part_verify, out, depth, rest_votes);
    return;
  }
  auto t = Clock::now();
  const std::vector<Cluster> parts = convex_segments(points, options_.split.parts);
  out.times.split_ms += ms_since(t);
  // One part that is nearly the whole region: the whole region's search goes on, alone.
  if (parts.empty() || (parts.size() == 1 && parts[0].size() > 0.9 * static_cast<double>(points.size()))) {
    if (search_on_alone()) return;
    if (partial && !out_of_time(out)) explain_jointly(points, *partial, frame, part_verify, out, depth, rest_votes);
    return;
  }
  ++out.split_clusters;
  // The parts' starting poses tried together, within one budget (with the whole region's untried
  // ones, first among the regions); each part described when the search reaches it.
  std::vector<Region> regions = std::move(whole);
  const bool with_whole = !regions.empty();
  for (const Cluster& part : parts) {
    PointCloud part_points = cluster_points(points, part);
    if (bounding_box(part_points.points).diagonal() > options_.match.max_region_size_factor * largest_diameter_m_) continue;
    regions.push_back(pending_region(std::move(part_points), part_verify));
  }
  std::optional<Detection> seed;
  std::size_t found_in = regions.size();
  std::optional<Detection> det = search(regions, frame, out, &partial, votes, &seed, std::numeric_limits<std::size_t>::max(), &found_in);
  out.parts_unreached += static_cast<std::size_t>(std::count_if(regions.begin(), regions.end(), [](const Region& r) { return r.pending.has_value(); }));
  const bool in_whole = with_whole && found_in == 0;  // (else in a part, below in a grown region, or nowhere)
  if (!det && seed && !out_of_time(out)) {
    // A part's pose that met every part bound but the model's support and was not accepted: much
    // of the model it shows lies outside the part (a mug's outer wall, cut from its inside and
    // handle at the creases). The region's points near that model, one piece, are searched as a
    // region of their own (SplitOptions::grow_reach_m), when they reach beyond the seed's part and
    // are not the whole region, searched already.
    const PointCloud grown = grown_region(points, *seed);
    if (grown.size() > seed->cluster_points && grown.size() < points.size()) {
      ++out.grown_regions;
      det = recognize_cluster(grown, frame, part_verify, out, rest_votes);
    }
  }
  if (!det) {
    // No part passed alone: a pose that explains part of the region (or of a part) well, and
    // whatever the rest of the region is.
    if (partial && !out_of_time(out)) explain_jointly(points, *partial, frame, part_verify, out, depth, rest_votes);
    return;
  }
  det->from_split_cluster = !in_whole;
  recognize_rest(points, std::move(*det), frame, out, depth);
}

VerifyOptions Recognizer::part_verify_options() const {
  VerifyOptions part = options_.verify;
  part.max_unmeasured_fraction = std::min(part.max_unmeasured_fraction, options_.split.part_max_unmeasured_fraction);
  part.min_inlier_fraction = std::max(part.min_inlier_fraction, options_.split.part_min_inlier_fraction);
  part.min_cluster_explained = std::max(part.min_cluster_explained, options_.split.part_min_cluster_explained);
  return part;
}

std::vector<Recognizer::Piece> Recognizer::unexplained_pieces(const Segmentation& seg, std::span<const Detection> detections,
                                                              double widest) const {
  // Each detection's bounding sphere: only the clusters it reaches lose points to it.
  std::vector<std::pair<Eigen::Vector3f, float>> spheres;
  for (const Detection& d : detections) {
    const BoundingBox& box = prepared(d.object_index).model_box;
    const Eigen::Vector3d centre = d.T_camera_object * (0.5f * (box.min + box.max)).cast<double>();
    spheres.emplace_back(centre.cast<float>(), 0.5f * box.diagonal() + options_.verify.max_tolerance_m);
  }
  // Where the depth noise verification allows reaches the clusters' own gap (a Kinect's at about
  // 2 m), a surface breaks into pieces by noise alone: pieces there say nothing of one object.
  // (Without the tolerance's cap: the depth where the noise itself reaches the gap.)
  const auto too_far = [&](float z) { return !(depth_noise_tolerance(z, options_.verify) < options_.segment.clusters.tolerance_m); };
  std::vector<Piece> pieces;
  const auto keep = [&](PointCloud&& points) {
    if (points.points.empty() || width_of({&points}) > widest) return;
    double z = 0;
    for (const Eigen::Vector3f& p : points.points) z += p.z();
    z /= static_cast<double>(points.size());
    if (too_far(static_cast<float>(z))) return;
    const BoundingBox box = bounding_box(points.points);
    pieces.push_back({std::move(points), box, static_cast<float>(z)});
  };
  for (const Cluster& c : seg.clusters) {
    BoundingBox box;
    for (const std::uint32_t i : c) box.extend(seg.points.points[i]);
    if (box.empty || too_far(box.min.z())) continue;  // (no piece of it can be nearer)
    std::vector<std::size_t> reaching;
    for (std::size_t k = 0; k < spheres.size(); ++k) {
      const auto& [centre, radius] = spheres[k];
      if ((centre.cwiseMax(box.min).cwiseMin(box.max) - centre).norm() <= radius) reaching.push_back(k);
    }
    if (reaching.empty() && box.size().maxCoeff() > widest) continue;  // (wider than that along an axis)
    PointCloud points = cluster_points(seg.points, c);
    if (reaching.empty()) {
      keep(std::move(points));
      continue;
    }
    std::vector<char> explained(points.size(), 0);
    for (const std::size_t k : reaching) {
      const std::vector<char> by_d = explained_points(detections[k], points);
      for (std::size_t i = 0; i < points.size(); ++i) explained[i] = explained[i] || by_d[i];
    }
    for (const Cluster& r : clusters_of_unexplained(points, explained, options_.segment.clusters)) keep(cluster_points(points, r));
  }
  return pieces;
}

void Recognizer::join_fragments(const Segmentation& seg, const FrameAndPlanes& frame, Recognition& out) const {
  const auto t = Clock::now();
  // Pieces of one object lie within its diameter (and the largest tolerance).
  const double widest = largest_diameter_m_ + options_.verify.max_tolerance_m;
  const std::vector<Piece> pieces = unexplained_pieces(seg, out.detections, widest);
  // The pairs near enough and small enough together to be one object's pieces.
  const float gap = options_.split.join_gap_m;
  struct Pair {
    std::size_t a, b;
    float gap_m;
  };
  std::vector<Pair> pairs;
  std::vector<std::optional<KdTree>> trees(pieces.size());  // each made when first asked for
  for (std::size_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t b = a + 1; b < pieces.size(); ++b) {
      // The boxes' own gap bounds the points' from below: most pairs end here.
      const Eigen::Vector3f box_gap = (pieces[a].box.min - pieces[b].box.max).cwiseMax(pieces[b].box.min - pieces[a].box.max).cwiseMax(0.0f);
      if (box_gap.norm() > gap || width_of({&pieces[a].points, &pieces[b].points}) > widest) continue;
      if (!trees[b]) trees[b].emplace(pieces[b].points.points);
      const KdTree& tree = *trees[b];
      float nearest = gap * gap;
      bool near = false;
      for (const Eigen::Vector3f& p : pieces[a].points.points) {
        std::uint32_t index = 0;
        float d2 = 0;
        if (tree.nearest_within(p, nearest, index, d2)) nearest = d2, near = true;
      }
      if (near) pairs.push_back({a, b, std::sqrt(nearest)});
    }
  }
  // ... and cut apart by the sensor's missing depth (segment/depth_gaps.hpp): no wider in the image
  // than the gap at the nearer one's depth. One pair at a time, so that no other piece's growth
  // takes the pixels between them (a few pairs a frame).
  std::erase_if(pairs, [&](const Pair& pair) {
    const int gap_px = static_cast<int>(std::ceil(gap * frame.K.fx / std::max(0.1f, std::min(pieces[pair.a].depth_m, pieces[pair.b].depth_m))));
    const std::array<std::span<const Eigen::Vector3f>, 2> two = {pieces[pair.a].points.points, pieces[pair.b].points.points};
    return missing_depth_gaps(frame.depth, frame.K, two, db_.params.voxel_m, options_.verify.max_tolerance_m, gap_px).empty();
  });
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.gap_m < y.gap_m; });
  out.times.split_ms += ms_since(t);
  const VerifyOptions part_verify = part_verify_options();
  std::vector<char> used(pieces.size(), 0);
  for (const Pair& pair : pairs) {
    if (used[pair.a] || used[pair.b]) continue;
    if (out_of_time(out)) return;
    PointCloud joined = pieces[pair.a].points;
    const PointCloud& other = pieces[pair.b].points;
    joined.points.insert(joined.points.end(), other.points.begin(), other.points.end());
    joined.normals.clear();  // (described afresh)
    if (!joined.labels.empty()) joined.labels.insert(joined.labels.end(), other.labels.begin(), other.labels.end());
    joined.width = static_cast<int>(joined.points.size());
    ++out.joined_regions;
    // (The views' poses alone: SplitOptions::join_gap_m says why.)
    std::optional<Detection> det = recognize_cluster(joined, frame, part_verify, out);
    if (!det) continue;
    det->from_split_cluster = true;
    out.detections.push_back(std::move(*det));
    used[pair.a] = used[pair.b] = 1;
  }
}

void Recognizer::explain_jointly(const PointCloud& points, const Detection& partial, const FrameAndPlanes& frame, const VerifyOptions& verify,
                                 Recognition& out, int depth, bool votes) const {
  const auto t = Clock::now();
  std::vector<char> explained = explained_points(partial, points);
  out.times.split_ms += ms_since(t);
  for (const Cluster& c : unexplained_clusters(points, explained, out)) {
    if (out_of_time(out)) return;
    const PointCloud rest_points = cluster_points(points, c);
    if (bounding_box(rest_points.points).diagonal() > options_.match.max_region_size_factor * largest_diameter_m_) continue;
    // The rest is searched as the region was (`votes`: both everywhere, touching in what a
    // detection left, there even in the pass of the views' poses alone, MatchOptions::
    // votes_after_parts): a kept pose is not yet a detection, and with `touching` votes cast in the
    // rest of every such pose in a whole cluster were most of a frame of unknown things' time (real
    // mOSD frames: 59 -> 41 ms median without them), finding nothing more on any set of make results.
    std::optional<Detection> other = recognize_cluster(rest_points, frame, verify, out, votes);
    if (!other) continue;
    // The kept pose on what the other leaves of the region: its own share, judged as a part.
    const auto tv = Clock::now();
    const std::vector<char> taken = explained_points(*other, points);
    PointCloud own;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!taken[i]) own.points.push_back(points.points[i]);
    }
    const Verification v = verify_pose(verify_model(partial.object_index), partial.T_camera_object, frame.depth, frame.K, own.points, verify);
    out.times.verify_ms += ms_since(tv);
    const double confidence = v.accepted ? pose_confidence(v) : 0.0;
    if (v.accepted && options_.accept.on_verified) options_.accept.on_verified({partial.object_index, partial.T_camera_object, v, confidence});
    if (!v.accepted || confidence < options_.accept.min_confidence) continue;
    Detection first = partial;
    first.verification = v;
    first.score = confidence;
    first.cluster_points = own.size();
    first.from_split_cluster = other->from_split_cluster = true;
    out.detections.push_back(std::move(first));
    out.detections.push_back(std::move(*other));
    // What neither explains (a third object against these two) is recognized again. (The kept
    // pose is unchanged: its points are those found first.)
    if (!options_.split.enabled || depth >= options_.split.max_depth) return;
    for (std::size_t i = 0; i < points.size(); ++i) explained[i] = explained[i] || taken[i];
    for (const Cluster& l : unexplained_clusters(points, explained, out)) {
      if (out_of_time(out)) return;
      recognize_region(cluster_points(points, l), frame, out, depth + 1);
    }
    return;
  }
}

void Recognizer::recognize_rest(const PointCloud& points, Detection detection, const FrameAndPlanes& frame, Recognition& out,
                                int depth) const {
  // Explain the object's points away and start again on what is left: a smaller object touching it
  // (less of the cluster than verification lets go unexplained), or, in a split cluster, the other
  // objects whole (a mug's concave inside is not one convex part, but it is one cluster).
  const bool go_on = options_.split.enabled && depth < options_.split.max_depth;
  std::vector<Cluster> rest_clusters;
  if (go_on) {
    const auto t = Clock::now();
    const std::vector<char> explained = explained_points(detection, points);
    out.times.split_ms += ms_since(t);
    rest_clusters = unexplained_clusters(points, explained, out);
  }
  out.detections.push_back(std::move(detection));
  for (const Cluster& c : rest_clusters) {
    if (out_of_time(out)) return;
    recognize_region(cluster_points(points, c), frame, out, depth + 1);
  }
}

std::vector<Cluster> Recognizer::unexplained_clusters(const PointCloud& points, const std::vector<char>& explained, Recognition& out) const {
  const auto t = Clock::now();
  std::vector<Cluster> clusters = clusters_of_unexplained(points, explained, options_.segment.clusters);
  out.times.split_ms += ms_since(t);
  return clusters;
}

PointCloud Recognizer::grown_region(const PointCloud& points, const Detection& seed) const {
  return piece_on_model(points, icp_target(seed.object_index), seed.T_camera_object, options_.split.grow_reach_m,
                        options_.verify, options_.icp, options_.segment.clusters);
}

std::vector<char> Recognizer::explained_points(const Detection& detection, const PointCloud& points) const {
  return on_model(points.points, icp_target(detection.object_index), detection.T_camera_object, options_.verify, options_.icp);
}

std::vector<Recognizer::Refined> Recognizer::refine_and_verify(std::span<const Hypothesis> hypotheses,
                                                               std::span<const Eigen::Vector3f> icp_source,
                                                               std::span<const Eigen::Vector3f> cluster, const FrameAndPlanes& frame,
                                                               const VerifyOptions& verify, Recognition& record,
                                                               const std::vector<std::vector<Transform>>* refused) const {
  std::vector<Refined> out(hypotheses.size());
  const auto is_refused = [&](std::uint32_t object, const Transform& T) {
    if (!refused || !(options_.match.refused_rotation_deg > 0)) return false;
    return near_any((*refused)[object], T, options_.match.refused_translation_m, options_.match.refused_rotation_deg);
  };
  // Made before the threads start (each object once, under its own lock).
  for (const Hypothesis& h : hypotheses) prepared(h.object);
  const auto start = Clock::now();
  const auto n = static_cast<std::ptrdiff_t>(out.size());
  for_each_index(n, options_.run.parallel_hypotheses, 1, [&](std::ptrdiff_t k) {
    Refined& h = out[static_cast<std::size_t>(k)];
    const Hypothesis& hypothesis = hypotheses[static_cast<std::size_t>(k)];
    auto t = Clock::now();
    const IcpOptions& schedule = hypothesis.screened ? after_screen_icp_ : options_.icp;
    h.icp = icp_point_to_plane(icp_source, icp_target(hypothesis.object), hypothesis.T_camera_object.inverse(), schedule);
    h.icp_ms = ms_since(t);
    h.T_camera_object = h.icp.T_target_source.inverse();
    if (h.icp.fitness < options_.icp.min_fitness_after_first_stage) return;  // ICP lost the object
    if (is_refused(hypothesis.object, h.T_camera_object)) {
      h.repeat = true;
      return;
    }
    t = Clock::now();
    h.v = verify_pose(verify_model(hypothesis.object), h.T_camera_object, frame.depth, frame.K, cluster, verify);
    h.verify_ms = ms_since(t);
    h.verified = true;
  });
  // Taken in order: the confidence of each pose verification passed, and what the caller hears of it.
  for (std::size_t k = 0; k < out.size(); ++k) {
    Refined& h = out[k];
    record.icp_steps += static_cast<std::size_t>(h.icp.iterations);
    if (!h.verified || !h.v.accepted) continue;
    h.confidence = pose_confidence(h.v);
    if (options_.accept.on_verified) options_.accept.on_verified({hypotheses[k].object, h.T_camera_object, h.v, h.confidence});
    h.accepted = h.confidence >= options_.accept.min_confidence;
    // No object stands inside a table: such a pose is not accepted, and the search goes on to the
    // region's next (pose/through_planes.hpp).
    if (h.accepted && inside_planes(hypotheses[k].object, h.T_camera_object, frame)) {
      h.accepted = false;
      ++record.dropped_inside_planes;
    }
    // Nor a little way into it: lifted onto it, the pose must pass again.
    if (h.accepted) lift_out_of_planes(hypotheses[k].object, h, cluster, frame, verify, record);
  }
  // The wall time, shared between the two stages as their summed times are.
  const double wall = ms_since(start);
  double icp = 0, verified = 0;
  for (const Refined& h : out) icp += h.icp_ms, verified += h.verify_ms;
  if (icp + verified > 0) {
    record.times.icp_ms += wall * icp / (icp + verified);
    record.times.verify_ms += wall * verified / (icp + verified);
  }
  return out;
}

std::optional<Recognizer::Region> Recognizer::describe_region(const PointCloud& points, const FrameAndPlanes& frame,
                                                              const VerifyOptions& verify, Recognition& out) const {
  DescribeTimes dt;
  Region region;
  region.point_count = points.size();
  region.description = describe(points, db_.params.describe, &dt);
  region.verify = region.near_miss = verify;
  region.refused.resize(db_.objects.size());
  region.refined_places.resize(db_.objects.size());
  out.times.normals_ms += dt.normals_ms;
  out.times.vfh_ms += dt.vfh_ms;
  out.times.crh_ms += dt.crh_ms;
  const Description& d = region.description;
  if (d.cloud.size() < 3) return std::nullopt;
  ++out.regions;
  const auto t_match = Clock::now();
  if (options_.match.source != PoseSource::ppf) region.matches = index_.nearest(d.vfh, options_.match.per_object, options_.match.at_most);
  out.times.match_ms += ms_since(t_match);
  region.icp_source = voxel_downsample(d.cloud, db_.params.icp_voxel_m).points;
  region.grid = OccupancyGrid(region.icp_source, options_.match.fit_cell_m);
  // Where the sensor's pixels lie farther apart than the ICP copy's voxels, the region holds fewer
  // of them than its surface would: counted as if sampled densely (an upper bound on its surface).
  region.icp_points_dense = static_cast<double>(region.icp_source.size());
  if (frame.K.fx > 0 && !region.icp_source.empty()) {
    double z_sum = 0;
    for (const auto& p : region.icp_source) z_sum += static_cast<double>(p.z());
    const double pixel_m = z_sum / static_cast<double>(region.icp_source.size()) / frame.K.fx;
    const double voxel_m = static_cast<double>(db_.params.icp_voxel_m);
    if (pixel_m > voxel_m) region.icp_points_dense *= (pixel_m / voxel_m) * (pixel_m / voxel_m);
  }
  // Objects whose diameter is below this cannot have min_cluster_explained of the region on their
  // surface (an explained point lies within the depth tolerance, and a pixel or so, of the model).
  if (options_.match.skip_objects_too_small && frame.K.fx > 0) {
    float z_far = 0;
    for (const auto& p : d.cloud.points) z_far = std::max(z_far, p.z());
    const double slack = 2.0 * (depth_tolerance(z_far, verify) + 4.0 * z_far / frame.K.fx);
    region.smallest_diameter = core_width(d.cloud.points, verify.min_cluster_explained) - slack;
  }
  region.partial = verify;
  region.seed = verify;
  region.seed.min_model_support = 0;
  region.partial.min_cluster_explained = std::min(verify.min_cluster_explained, options_.split.joint_min_cluster_explained);
  region.near_miss.max_conflict_fraction = std::max(verify.max_conflict_fraction, options_.accept.near_miss_conflict_fraction);
  region.try_near_misses = options_.accept.try_half_turns && region.near_miss.max_conflict_fraction > verify.max_conflict_fraction;
  region.candidates = rank_candidates(region, out);
  return region;
}

Recognizer::Region Recognizer::pending_region(PointCloud points, const VerifyOptions& verify) {
  Region region;
  region.point_count = points.size();
  region.verify = verify;
  region.pending = std::move(points);
  return region;
}

void Recognizer::describe_pending(Region& region, const FrameAndPlanes& frame, Recognition& out) const {
  if (!region.pending) return;
  std::optional<Region> described = describe_region(*region.pending, frame, region.verify, out);
  region.pending.reset();
  if (described) region = std::move(*described);
}

void Recognizer::prescreen(Region& region, std::size_t from, Recognition& out) const {
  const MatchOptions& m = options_.match;
  region.screen_done = true;
  // Past the deadline the search stops at its next step anyway: no screen to spend time on.
  if (from >= region.candidates.size() || region.icp_source.empty() || out_of_time(out)) return;
  const std::size_t n = std::min(m.prescreen, region.candidates.size() - from);
  const auto t = Clock::now();
  const auto first = region.candidates.begin() + static_cast<std::ptrdiff_t>(from);
  for (auto c = first; c != first + static_cast<std::ptrdiff_t>(n); ++c) prepared(c->object);  // (each object once)
  const auto count = static_cast<std::ptrdiff_t>(n);
  const std::size_t base = region.screened_poses.size();
  region.screened_poses.resize(base + n);
  for_each_index(count, options_.run.parallel_hypotheses, 4, [&](std::ptrdiff_t k) {
    Candidate& c = first[k];
    const IcpTarget& target = icp_target(c.object);
    // The grid keeps the sizes of its first use: the full schedule's reach, not the screen's.
    target.grid(options_.icp.grid_cell_m, options_.icp.reach_m());
    const IcpResult r = icp_point_to_plane(region.icp_source, target, c.T_camera_object.inverse(), screen_icp_);
    c.screen_fitness = icp_fitness(region.icp_source, target, r.T_target_source, screen_reach_m_, screen_icp_);
    c.screened_pose = static_cast<std::uint32_t>(base + static_cast<std::size_t>(k));
    region.screened_poses[c.screened_pose] = r.T_target_source.inverse();
  });
  // Best screened first; equals keep their coarse-fit order. The unscreened rest keep theirs after.
  std::stable_sort(first, first + count, [](const Candidate& a, const Candidate& b) { return a.screen_fitness > b.screen_fitness; });
  if (std::all_of(first, first + count, [](const Candidate& c) { return c.match == Candidate::kFromPairVotes; })) {
    interleave_by_object(first, first + count);
  }
  out.screened += n;
  out.times.icp_ms += ms_since(t);
}

bool Recognizer::refused_after_screen(const Region& region, const Candidate& c, const FrameAndPlanes& frame, Recognition& out) const {
  // (The measurement that makes this safe: MatchOptions::prescreen.)
  if (!c.screened()) return false;
  const Transform& T_camera_object = region.screened_poses[c.screened_pose];
  if (seen_through_quickly(verify_model(c.object), T_camera_object, frame.depth, frame.K, region.verify)) {
    ++out.screened_out;
    return true;
  }
  if (!(options_.match.merge_rotation_deg > 0)) return false;
  std::vector<Transform>& places = region.refined_places[c.object];
  const double reach = options_.match.merge_share * db_.objects[c.object].diameter_m;
  if (near_any(places, T_camera_object, reach, options_.match.merge_rotation_deg)) {
    ++out.screened_merged;
    return true;
  }
  places.push_back(T_camera_object);
  return false;
}

std::vector<Recognizer::Candidate> Recognizer::rank_candidates(const Region& region, Recognition& out) const {
  const auto t0 = Clock::now();
  const Description& d = region.description;
  // Each view's rolls; views of objects too small for the region give none.
  std::vector<std::vector<float>> rolls(region.matches.size());
  const auto n = static_cast<std::ptrdiff_t>(region.matches.size());
  for_each_index(n, options_.run.parallel_hypotheses && n > 8, 16, [&](std::ptrdiff_t m) {
    const ViewEntry& view = db_.views[region.matches[static_cast<std::size_t>(m)].view];
    if (db_.objects[view.object].diameter_m < region.smallest_diameter) return;
    if (static_cast<double>(view.icp_points.size()) * options_.match.min_region_to_view > region.icp_points_dense) return;
    rolls[static_cast<std::size_t>(m)] = crh_roll_angles(view.crh, d.crh, options_.match.roll);
  });
  out.times.crh_ms += ms_since(t0);
  const auto t1 = Clock::now();
  std::vector<Candidate> candidates;
  for (std::size_t m = 0; m < region.matches.size(); ++m) {
    const ViewEntry& view = db_.views[region.matches[m].view];
    for (const float roll : rolls[m]) {
      const Transform T_camera_view = crh_alignment(view.centroid.cast<double>(), d.centroid.cast<double>(), roll);
      candidates.push_back({static_cast<std::uint32_t>(m), view.object, roll, T_camera_view * view.T_view_object, 0.0});
    }
  }
  for (Candidate& c : candidates) prepared(c.object);  // (each object once)
  const auto count = static_cast<std::ptrdiff_t>(candidates.size());
  for_each_index(count, options_.run.parallel_hypotheses && count > 64, 32, [&](std::ptrdiff_t k) {
    Candidate& c = candidates[static_cast<std::size_t>(k)];
    const ViewEntry& view = db_.views[region.matches[c.match].view];
    const CoarseFitInputs in{region.icp_source, &region.grid, view.icp_points, &prepared(c.object).occupancy};
    c.fit = coarse_fit(in, c.T_camera_object * view.T_view_object.inverse(), c.T_camera_object, options_.match.fit_points);
  });
  if (options_.match.source == PoseSource::ppf) {
    for (Candidate& c : pair_vote_candidates(region)) candidates.push_back(c);
    ++out.voted_regions;
  }
  // Best fit first; equal fits keep the order of the views' VFH distance and their rolls' peaks.
  std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.fit > b.fit; });
  if (options_.match.source == PoseSource::ppf) interleave_by_object(candidates.begin(), candidates.end());
  out.times.match_ms += ms_since(t1);
  return candidates;
}

std::vector<Recognizer::Candidate> Recognizer::pair_vote_candidates(const Region& region) const {
  const Description& d = region.description;
  const auto objects = static_cast<std::ptrdiff_t>(db_.objects.size());
  std::vector<std::vector<Candidate>> by_object(db_.objects.size());
  for (std::uint32_t o = 0; o < db_.objects.size(); ++o) {
    if (db_.objects[o].diameter_m >= region.smallest_diameter) prepared(o), pair_table(o);  // (each once, before the threads)
  }
  for_each_index(objects, options_.run.parallel_hypotheses, 1, [&](std::ptrdiff_t k) {
    const auto o = static_cast<std::uint32_t>(k);
    const DatabaseObject& object = db_.objects[o];
    if (object.diameter_m < region.smallest_diameter) return;
    const PpfModel* found = pair_table(o);
    if (!found) return;
    const PpfModel& table = *found;
    // The region sampled as the object's table was, at its own step (a share of its diameter).
    const OrientedPoints scene = ppf_sample(d.cloud.points, d.cloud.normals, table.sample_step_m(), table.normal_split_deg());
    for (const PpfHypothesis& h : table.hypotheses(scene)) {
      const double fit = coarse_fit_facing(region.icp_source, region.grid, table.sampled().points, table.sampled().normals,
                                           prepared(o).occupancy, h.T_camera_object, options_.match.fit_points);
      by_object[o].push_back({Candidate::kFromPairVotes, o, 0.0f, h.T_camera_object, fit});
    }
  });
  std::vector<Candidate> all;
  for (const std::vector<Candidate>& c : by_object) all.insert(all.end(), c.begin(), c.end());
  return all;
}

std::vector<Recognizer::Hypothesis> Recognizer::half_turns(const Transform& T_camera_object, std::uint32_t object) const {
  // Half a turn about each of the object's own axes, through its box centre.
  const BoundingBox box = bounding_box(db_.objects[object].model_points);
  const Eigen::Vector3d centre = (0.5f * (box.min + box.max)).cast<double>();
  std::vector<Hypothesis> turned;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
    turned.push_back({object, T_camera_object * make_transform(R, centre - R * centre)});
  }
  return turned;
}

Detection Recognizer::detection_from(const Refined& h, const Region& region, const Candidate& c) const {
  const DatabaseObject& object = db_.objects[c.object];
  Detection det;
  det.object_id = object.id;
  det.object_name = object.name;
  det.object_index = c.object;
  det.T_camera_object = h.T_camera_object;
  det.score = h.confidence;
  det.icp_fitness = h.icp.fitness;
  det.icp_rmse_m = h.icp.inlier_rmse;
  det.match_rank = c.match == Candidate::kFromPairVotes ? -1 : static_cast<int>(c.match);
  det.roll_deg = c.roll_deg;
  det.cluster_points = region.description.cloud.size();
  det.verification = h.v;
  return det;
}

std::optional<Detection> Recognizer::try_candidates(const Region& region, std::span<const std::size_t> which,
                                                    bool take_best, const FrameAndPlanes& frame, Recognition& out) const {
  std::optional<Detection> found;
  std::vector<Hypothesis> hypotheses;
  for (const std::size_t i : which) {
    // A screened pose from where the screen led it (MatchOptions::refine_from_screen).
    const Candidate& c = region.candidates[i];
    if (c.screened() && options_.match.refine_from_screen) hypotheses.push_back({c.object, region.screened_poses[c.screened_pose], true});
    else hypotheses.push_back({c.object, c.T_camera_object});
  }
  // All at once on the threads there are; then taken in order, as one after the other would.
  const Description& d = region.description;
  const std::vector<Refined> refined =
      refine_and_verify(hypotheses, region.icp_source, d.cloud.points, frame, region.verify, out, &region.refused);
  const Refined* nearest_miss = nullptr;
  std::size_t nearest_miss_at = 0;
  for (std::size_t k = 0; k < refined.size(); ++k) {
    const Refined& h = refined[k];
    const Candidate& c = region.candidates[which[k]];
    ++out.hypotheses;
    if (h.repeat) ++out.repeats;
    if (!h.verified) continue;
    if (!h.accepted) region.refused[c.object].push_back(h.T_camera_object);
    if (!h.v.accepted && region.partial.min_cluster_explained > 0 && passes(h.v, region.partial) &&
        (!region.best_partial || h.v.score > region.best_partial->verification.score)) {
      region.best_partial = detection_from(h, region, c);
      region.best_partial->score = pose_confidence(h.v);
    }
    // A seed to grow: every part bound met but the model's support, and not accepted, whether it
    // failed the support or passed it narrowly and scored below the confidence bound (a pose
    // refused only for lying inside a plane is no seed: it would be refused again).
    const bool scored_low = h.v.accepted && h.confidence < options_.accept.min_confidence;
    if ((!h.v.accepted || scored_low) && region.gives_seed && options_.split.grow_reach_m > 0 && passes(h.v, region.seed) &&
        (!region.best_seed || h.v.score > region.best_seed->verification.score)) {
      region.best_seed = detection_from(h, region, c);
      region.best_seed->cluster_points = region.point_count;  // as grown_region counts points
    }
    if (!h.v.accepted) {
      if (region.try_near_misses && passes(h.v, region.near_miss) && (!nearest_miss || h.v.score > nearest_miss->v.score)) {
        nearest_miss = &h;
        nearest_miss_at = k;
      }
      continue;
    }
    if (!h.accepted) {
      // Passed verification, but not confidently enough, or sunk into a table and refused when
      // lifted onto it. The latter may be the object turned: a jug half a turn about its axis seats
      // deeper on the surface seen, and the turn is right (the simulated seed experiment at 1.25 m).
      if (h.sunk && region.try_near_misses && (!nearest_miss || h.v.score > nearest_miss->v.score)) {
        nearest_miss = &h;
        nearest_miss_at = k;
      }
      continue;
    }
    if (found && found->verification.score >= h.v.score) continue;
    found = detection_from(h, region, c);
    if (!take_best) break;
  }
  if (!found && nearest_miss && !out_of_time(out)) {
    // Nothing passed, but one pose failed only by seeing through it, or sank into a table: try it
    // turned about its axes.
    const Candidate& c = region.candidates[which[nearest_miss_at]];
    const std::vector<Refined> turned = refine_and_verify(half_turns(nearest_miss->T_camera_object, c.object),
                                                          region.icp_source, d.cloud.points, frame, region.verify, out);
    out.hypotheses += turned.size();
    for (const Refined& h : turned) {
      if (h.accepted && (!found || h.v.score > found->verification.score)) found = detection_from(h, region, c);
    }
  }
  return found;
}

void Recognizer::challenge(const Region& region, std::size_t next, std::size_t end, Detection& best, const FrameAndPlanes& frame,
                           Recognition& out) const {
  // Another object may explain the region better (two boxes of similar size): the other objects'
  // next few starting poses are tried, and the higher verification score wins.
  std::vector<std::size_t> tried(db_.objects.size(), 0), which;
  for (std::size_t i = next; i < end; ++i) {
    const std::uint32_t object = region.candidates[i].object;
    if (object == best.object_index || tried[object]++ >= options_.match.challenger_views) continue;
    if (!refused_after_screen(region, region.candidates[i], frame, out)) which.push_back(i);
  }
  const std::size_t batch = std::max<std::size_t>(1, options_.run.batch);
  for (std::size_t i = 0; i < which.size() && !out_of_time(out); i += batch) {
    const std::span<const std::size_t> some(which.data() + i, std::min(batch, which.size() - i));
    std::optional<Detection> det = try_candidates(region, some, true, frame, out);
    if (det && det->verification.score > best.verification.score) best = std::move(*det);
  }
}

void Recognizer::turn_if_better(const Region& region, Detection& best, const FrameAndPlanes& frame, Recognition& out) const {
  // The pose turned about the object's own axes, each refined and verified; the best is kept, and
  // the runner-up's score says by how much it won.
  const std::vector<Refined> turned = refine_and_verify(half_turns(best.T_camera_object, best.object_index),
                                                        region.icp_source, region.description.cloud.points, frame,
                                                        region.verify, out);
  out.hypotheses += turned.size();
  double runner_up = 0;
  for (const Refined& h : turned) {
    if (!h.accepted) continue;
    if (h.v.score > best.verification.score) {
      runner_up = std::max(runner_up, best.verification.score);
      best.T_camera_object = h.T_camera_object;
      best.score = h.confidence;
      best.icp_fitness = h.icp.fitness;
      best.icp_rmse_m = h.icp.inlier_rmse;
      best.verification = h.v;
    } else {
      runner_up = std::max(runner_up, h.v.score);
    }
  }
  best.runner_up_score = runner_up;
}

std::optional<Detection> Recognizer::recognize_cluster(const PointCloud& points, const FrameAndPlanes& frame,
                                                       const VerifyOptions& verify, Recognition& out, bool votes) const {
  std::vector<Region> regions;
  if (std::optional<Region> region = describe_region(points, frame, verify, out)) regions.push_back(std::move(*region));
  return search(regions, frame, out, nullptr, votes);
}

std::optional<Detection> Recognizer::search(std::vector<Region>& regions, const FrameAndPlanes& frame, Recognition& out,
                                            std::optional<Detection>* partial, bool votes, std::optional<Detection>* seed,
                                            std::size_t max_poses, std::size_t* found_in) const {
  // The starting poses of every region, best first across them (by the screen, else coarse fit), a
  // batch at a time from one region, until one passes or the budget is spent (with keep_best: all
  // of them, the best kept). The regions share the budget: the parts of one cluster compete for it.
  const bool every = options_.accept.keep_best || options_.match.max_hypotheses == 0;
  const std::size_t budget = every ? std::numeric_limits<std::size_t>::max() : options_.match.max_hypotheses;
  const std::size_t spend = std::min(max_poses, budget);  // this call's share of it
  const std::size_t batch = std::max<std::size_t>(1, options_.run.batch);
  // The short ICP's screen (prescreen): a region alone is screened only once its first batch, in
  // coarse fit order, has failed (most recognized regions pass in it); the parts of a split
  // cluster (when there are two or more) from their first pose, to be ranked against each other by
  // one measure (each part when the search reaches it, below). The exhaustive search (and
  // keep_best) tries every pose anyway: no order to choose.
  const bool screen = !every && options_.match.prescreen > 0;
  if (found_in) *found_in = regions.size();  // (none, until a pose is returned)
  std::vector<std::size_t> next(regions.size(), 0), end(regions.size());
  std::optional<Detection> best;
  std::size_t best_region = 0;
  std::vector<std::size_t> which;
  // One batch of region r: `batch` places in its order, refined and verified together; a pose
  // better than the best so far is kept. A pose the screen refused keeps its place and spends its
  // share of the budget unrefined (the next batch is chosen across the regions again, as if it had
  // been refined).
  const auto try_batch = [&](std::size_t r, std::size_t& spent) {
    which.clear();
    for (std::size_t taken = 0; next[r] < end[r] && taken < batch && spent < spend; ++next[r], ++spent, ++taken) {
      if (!refused_after_screen(regions[r], regions[r].candidates[next[r]], frame, out)) which.push_back(next[r]);
    }
    if (which.empty()) return;
    std::optional<Detection> det = try_candidates(regions[r], which, options_.accept.keep_best, frame, out);
    if (det && (!best || det->verification.score > best->verification.score)) {
      best = std::move(det);
      best_region = r;
    }
  };
  // With `votes` (PoseSource both, touching), the views' poses first, exactly as vfh alone tries
  // them; where none passes, the point pair votes' poses, with a budget of their own: what vfh
  // finds is found the same way. (With ppf, the votes' poses are the region's candidates already.)
  const int sources = votes && options_.match.source != PoseSource::ppf ? 2 : 1;
  for (int source = 0; source < sources && !best && !out_of_time(out); ++source) {
    // The votes' poses replace the views' (cast when the region's turn comes, as below).
    std::vector<char> votes_due(regions.size(), source == 1);
    const auto cast_votes = [&](Region& region) {
      const auto t = Clock::now();
      region.candidates.clear();
      if (region.description.cloud.size() >= 3) region.candidates = pair_vote_candidates(region), ++out.voted_regions;  // (else: no poses)
      region.screened_poses.clear();
      std::stable_sort(region.candidates.begin(), region.candidates.end(), [](const Candidate& x, const Candidate& y) { return x.fit > y.fit; });
      interleave_by_object(region.candidates.begin(), region.candidates.end());
      region.screen_done = false;
      region.tried = 0;
      out.times.match_ms += ms_since(t);
    };
    for (std::size_t r = 0; r < regions.size(); ++r) {
      next[r] = source == 0 ? regions[r].tried : 0;
      end[r] = regions[r].pending || votes_due[r] ? 0 : std::min(regions[r].candidates.size(), budget);
    }
    // The parts of a split cluster are described (and their votes cast, in the votes' turn), and
    // screened all at once from their first pose (to be ranked against each other), each as late as
    // it can be: just before its first batch, and the rest before the order across them takes over.
    // The poses tried are the same, in the same order, as with every part described and screened
    // first, but the parts the budget never reaches (the smallest of four or more, below) cost
    // nothing. Measured on the real YCB-V dev frames (7 objects): 131 regions described instead of
    // 193, 5,793 poses screened instead of 8,268, the frame's median 71 -> 60 ms, the same
    // detections byte for byte. (One difference: a part whose description fails, fewer than three
    // points with normals, still counts among the parts, where described first it was dropped; with
    // one good part left, that part is then searched as a part, not as a lone region. Parts hold at
    // least ConvexSegmentOptions::min_points, 100: no such part was seen.)
    const auto reach_part = [&](std::size_t r) {
      if (out_of_time(out)) return;
      if (regions[r].pending || votes_due[r]) {
        describe_pending(regions[r], frame, out);
        if (votes_due[r]) cast_votes(regions[r]), votes_due[r] = false;
        end[r] = std::min(regions[r].candidates.size(), budget);
      }
      if (screen && regions.size() > 1 && !regions[r].screen_done) prescreen(regions[r], next[r], out);
    };
    std::size_t spent = 0;
    // A split cluster's parts each try their first batch (their best screened poses), largest part
    // first, before the order across them takes over: a part of a known object beside an unknown
    // larger one (a mug against a box) screens below the poses of the known object fitted to the
    // larger one's part, and the shared budget was spent before its turn came
    // (SplitOptions::grow_reach_m then uses its pose). With three regions or more (a whole cluster
    // searched on with its parts is one, first) this round spends the whole budget, and the
    // smallest of four or more get none. Measured: giving each part
    // fewer (half the budget shared among them) found the mug of YCB-V 0000 alone in the database in
    // 2 of 8 frames, a batch each in 6.
    if (regions.size() > 1 && !every) {
      for (std::size_t r = 0; r < regions.size() && spent < spend && !best && !out_of_time(out); ++r) {
        reach_part(r);
        try_batch(r, spent);
      }
    }
    if (spent < spend && !best) {
      for (std::size_t r = 0; r < regions.size(); ++r) reach_part(r);
    }
    while (spent < spend && !(best && !options_.accept.keep_best)) {
      if (out_of_time(out)) break;
      if (screen && regions.size() == 1 && !regions[0].screen_done && next[0] > 0) prescreen(regions[0], next[0], out);
      // The region whose next starting pose ranks best (the first of equals: parts come largest first).
      // (Vote poses are in object-by-object order within a region, not best first: a region's next
      // pose stands for it.)
      std::size_t r = regions.size();
      for (std::size_t i = 0; i < regions.size(); ++i) {
        if (next[i] < end[i] && (r == regions.size() || regions[i].candidates[next[i]].priority() > regions[r].candidates[next[r]].priority())) r = i;
      }
      if (r == regions.size()) break;
      try_batch(r, spent);
    }
  }
  if (!best) {
    // The best of the regions' kept poses (best_seed, best_partial) into `into`, where it is better
    // than what `into` holds (the first of equals); canonical, if asked, when it replaces it.
    const auto best_kept = [&](std::optional<Detection> Region::*kept, std::optional<Detection>& into, bool canonical) {
      const Detection* better = into ? &*into : nullptr;
      for (const Region& region : regions) {
        const std::optional<Detection>& k = region.*kept;
        if (k && (!better || k->verification.score > better->verification.score)) better = &*k;
      }
      if (!better || (into && better == &*into)) return;
      into = *better;
      if (canonical) into->T_camera_object = canonical_pose(into->T_camera_object, db_.objects[into->object_index].symmetries);
    };
    if (seed) best_kept(&Region::best_seed, *seed, false);
    if (partial) best_kept(&Region::best_partial, *partial, options_.accept.canonical_poses);
    return best;
  }
  if (found_in) *found_in = best_region;
  const Region& region = regions[best_region];
  if (!options_.accept.keep_best && options_.match.challenger_views > 0) challenge(region, next[best_region], end[best_region], *best, frame, out);
  if (options_.accept.try_half_turns && !out_of_time(out)) turn_if_better(region, *best, frame, out);
  if (options_.accept.canonical_poses) {
    // Of the poses the object's symmetries make equivalent, always the same one.
    best->T_camera_object = canonical_pose(best->T_camera_object, db_.objects[best->object_index].symmetries);
  }
  return best;
}

}  // namespace viewpose
