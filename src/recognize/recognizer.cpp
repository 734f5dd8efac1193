// The recognizer's frame: making it (the database's objects prepared once), one frame through the
// stages (segment, the clusters side by side, the planes' and the scene's tests on what they
// found). A region's search is in regions.cpp, a region's poses in search.cpp.
#include "viewpose/recognize/recognizer.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <span>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "viewpose/core/stopwatch.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/pose/resting_plane.hpp"
#include "viewpose/pose/through_planes.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/render/simplify.hpp"

#include "recognize/for_each_index.hpp"

namespace viewpose {

using detail::for_each_index;

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
    p.axes = principal_axes(o.model_points);
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
  // The more confident; of two alike, the earlier cluster's (parts merge in the clusters' order).
  if (part.best_below_min_score && out.more_confident_than_below(part.best_below_min_score->score)) {
    out.best_below_min_score = std::move(part.best_below_min_score);
  }
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

}  // namespace viewpose
