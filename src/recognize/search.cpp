// A region's poses: described and ranked (views' rolls by coarse fit, point pair votes), screened
// by a short ICP, refined and verified within the budget, challenged by other objects and turned
// half a turn. Which regions are searched is in regions.cpp.
#include "viewpose/recognize/recognizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "viewpose/core/stopwatch.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/pose/coarse_fit.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/recognize/candidate_order.hpp"
#include "viewpose/segment/voxel_grid.hpp"

#include "recognize/for_each_index.hpp"

namespace viewpose {

namespace {

// The middle share of a region's points whose width across the image is its strip's (a few stray
// points at its edge, the sensor's, do not widen it).
constexpr double kStripShare = 0.95;

// Whether T lies within `metres` and `degrees` of one of `poses` (a pose refused or a place refined
// already: MatchOptions::refused_rotation_deg, merge_rotation_deg).
bool near_any(std::span<const Transform> poses, const Transform& T, double metres, double degrees) {
  return std::any_of(poses.begin(), poses.end(), [&](const Transform& U) {
    return (T.translation() - U.translation()).norm() <= metres && rotation_difference_deg(T.linear(), U.linear()) <= degrees;
  });
}

}  // namespace

using detail::for_each_index;

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
    region.pixel_m = z_sum / static_cast<double>(region.icp_source.size()) / frame.K.fx;
    const double voxel_m = static_cast<double>(db_.params.icp_voxel_m);
    if (region.pixel_m > voxel_m) region.icp_points_dense *= (region.pixel_m / voxel_m) * (region.pixel_m / voxel_m);
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
  for (const Candidate& c : edge_on_candidates(region)) candidates.push_back(c);
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

std::vector<Recognizer::Candidate> Recognizer::edge_on_candidates(const Region& region) const {
  const MatchOptions& m = options_.match;
  std::vector<Candidate> out;
  if (m.edge_on_turns < 1 || region.matches.empty()) return out;
  // The region's shape as the camera sees it: only a strip can be a thin object's edge.
  const StripSize strip = strip_size(region.icp_source, kStripShare);
  if (!(strip.width_m > 0) || strip.length_m < 2.0 * strip.width_m) return out;
  // The objects among the region's nearest views, most of them prepared for the views' poses
  // already (a database of a thousand objects is not prepared whole for one strip).
  std::vector<std::uint32_t> objects;
  for (const Match& match : region.matches) objects.push_back(db_.views[match.view].object);
  std::sort(objects.begin(), objects.end());
  objects.erase(std::unique(objects.begin(), objects.end()), objects.end());
  for (const std::uint32_t o : objects) {
    const DatabaseObject& object = db_.objects[o];
    if (object.diameter_m < region.smallest_diameter) continue;
    const PreparedObject& p = prepared(o);
    const Eigen::Vector3d& extent = p.axes.extent;  // widest first
    if (!(extent[2] <= m.edge_on_thin_share * extent[1])) continue;
    const double thickness = extent[2];
    if (!(strip.width_m <= m.edge_on_width_share * thickness + m.edge_on_width_pixels * region.pixel_m)) continue;
    if (!(strip.width_m >= m.edge_on_min_width_share * thickness)) continue;
    for (const Transform& T : edge_on_poses(p.axes, p.plane_test_points, region.description.cloud.points, strip.across, m.edge_on_turns)) {
      const double fit = coarse_fit_facing(region.icp_source, region.grid, object.model_points, object.model_normals, p.occupancy, T, m.fit_points);
      out.push_back({Candidate::kFromEdgeOn, o, 0.0f, T, fit});
    }
  }
  return out;
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
  det.match_rank = c.from_view() ? static_cast<int>(c.match) : -1;
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
    if (beats_best_below_min_score(h.v.accepted, h.confidence, out)) keep_below_min_score(detection_from(h, region, c), frame, out);
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
      if (beats_best_below_min_score(h.v.accepted, h.confidence, out)) keep_below_min_score(detection_from(h, region, c), frame, out);
    }
  }
  return found;
}

bool Recognizer::beats_best_below_min_score(bool passed, double confidence, const Recognition& out) const {
  return passed && confidence < options_.accept.min_confidence && out.more_confident_than_below(confidence);
}

void Recognizer::keep_below_min_score(Detection d, const FrameAndPlanes& frame, Recognition& out) const {
  if (!inside_planes(d.object_index, d.T_camera_object, frame)) out.best_below_min_score = std::move(d);
}

void Recognizer::challenge(const Region& region, std::size_t next, std::size_t end, Detection& best, const FrameAndPlanes& frame,
                           Recognition& out) const {
  // Another object may explain the region better (two boxes of similar size): the other objects'
  // next few starting poses are tried, and the higher verification score wins. A doubtful pose
  // (MatchOptions::doubtful_confidence) is challenged by its own object's next poses too.
  const bool doubtful = best.score < options_.match.doubtful_confidence;
  std::vector<std::size_t> tried(db_.objects.size(), 0), which;
  for (std::size_t i = next; i < end; ++i) {
    const std::uint32_t object = region.candidates[i].object;
    if ((object == best.object_index && !doubtful) || tried[object]++ >= options_.match.challenger_views) continue;
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
