// Which regions of a frame are searched: a cluster, its convex parts, what a detection leaves of
// its region, a region grown from a part's pose, fragments joined, a pose kept and the rest
// explained jointly. The search of one region's poses is in search.cpp.
#include "viewpose/recognize/recognizer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <span>

#include "viewpose/core/stopwatch.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/pose/points_on_model.hpp"
#include "viewpose/segment/clusters.hpp"
#include "viewpose/segment/convex_segments.hpp"
#include "viewpose/segment/depth_gaps.hpp"

namespace viewpose {

namespace {

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
    if (beats_best_below_min_score(v.accepted, confidence, out)) {
      Detection below = partial;
      below.verification = v;
      below.score = confidence;
      below.cluster_points = own.size();
      keep_below_min_score(std::move(below), frame, out);
    }
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

}  // namespace viewpose
