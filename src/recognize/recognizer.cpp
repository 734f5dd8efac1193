#include "viewpose/recognize/recognizer.hpp"

#include "viewpose/core/stopwatch.hpp"
#include <cmath>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/database/matching.hpp"
#include "viewpose/segment/voxel_grid.hpp"

namespace viewpose {

Recognizer::Recognizer(const ViewDatabase& db, RecognizerOptions options) : db_(db), options_(std::move(options)) {
  if (db.views.empty()) throw Error("recognize: the view database holds no views");
  for (const DatabaseObject& o : db.objects) {
    targets_.push_back(std::make_unique<IcpTarget>(o.model_points, o.model_normals));
    largest_diameter_m_ = std::max(largest_diameter_m_, o.diameter_m);
  }
  // Scenes are described at the database's resolution, so that their VFHs are comparable.
  options_.segment.voxel_m = db.params.voxel_m;
}

Recognizer::~Recognizer() = default;

Recognition Recognizer::recognize(const Frame& frame) const {
  const auto start = Clock::now();
  Recognition out;
  SegmentTimes seg_times;
  const Segmentation seg = segment_scene(frame.cloud, options_.segment, &seg_times);
  out.times.downsample_ms = seg_times.downsample_ms;
  out.times.segment_ms = seg_times.planes_ms + seg_times.clusters_ms;
  out.clusters = seg.clusters.size();
  for (const Cluster& cluster : seg.clusters) {
    PointCloud points = cluster_points(seg.points, cluster);
    if (bounding_box(points.points).diagonal() > options_.max_cluster_size_factor * largest_diameter_m_) continue;
    DescribeTimes dt;
    const Description d = describe(points, db_.params.describe, &dt);
    out.times.normals_ms += dt.normals_ms;
    out.times.vfh_ms += dt.vfh_ms;
    out.times.crh_ms += dt.crh_ms;
    if (d.cloud.size() < 3) continue;
    auto t = Clock::now();
    const std::vector<Match> matches = nearest_views_per_object(db_, d.vfh, options_.matches);
    out.times.match_ms += ms_since(t);
    const std::vector<Eigen::Vector3f> icp_source = voxel_downsample(d.cloud, options_.icp_voxel_m).points;

    std::optional<Detection> best;
    std::uint32_t best_object = 0;  // index into db_.objects of the best detection
    for (std::size_t rank = 0; rank < matches.size() && !(best && !options_.keep_best); ++rank) {
      const ViewEntry& view = db_.views[matches[rank].view];
      const DatabaseObject& object = db_.objects[view.object];
      t = Clock::now();
      const std::vector<float> rolls = crh_roll_angles(view.crh, d.crh, options_.roll);
      out.times.crh_ms += ms_since(t);
      for (const float roll : rolls) {
        const Transform T0 = crh_alignment(view.centroid.cast<double>(), d.centroid.cast<double>(), roll) * view.T_view_object;
        t = Clock::now();
        const IcpResult icp = icp_point_to_plane(icp_source, *targets_[view.object], T0.inverse(), options_.icp);
        out.times.icp_ms += ms_since(t);
        ++out.hypotheses;
        if (icp.fitness < options_.icp.min_fitness_after_first_stage) continue;  // ICP lost the object
        const Transform T = icp.T_target_source.inverse();
        t = Clock::now();
        const Verification v = verify_pose({&object.mesh, object.model_points, db_.params.voxel_m}, T, frame.depth, frame.K,
                                           d.cloud.points, options_.verify);
        out.times.verify_ms += ms_since(t);
        if (!v.accepted || (best && best->score >= v.score)) continue;
        Detection det;
        det.object_id = object.id;
        det.object_name = object.name;
        det.T_camera_object = T;
        det.score = v.score;
        det.icp_fitness = icp.fitness;
        det.icp_rmse_m = icp.inlier_rmse;
        det.match_rank = static_cast<int>(rank);
        det.roll_deg = roll;
        det.cluster_points = d.cloud.size();
        det.verification = v;
        best = det;
        best_object = view.object;
        if (!options_.keep_best) break;
      }
    }
    if (best && options_.try_half_turns) {
      // The same pose turned about the object's own axes, each refined and verified.
      const DatabaseObject* object = &db_.objects[best_object];
      const std::uint32_t object_index = best_object;
      const BoundingBox box = bounding_box(object->model_points);
      const Eigen::Vector3d centre = (0.5f * (box.min + box.max)).cast<double>();
      Detection chosen = *best;
      double runner_up = 0;
      for (int axis = 0; axis < 3; ++axis) {
        // Half a turn about the axis through the box centre, in the object frame.
        const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
        const Transform turn = make_transform(R, centre - R * centre);
        t = Clock::now();
        const IcpResult icp = icp_point_to_plane(icp_source, *targets_[object_index], (best->T_camera_object * turn).inverse(), options_.icp);
        out.times.icp_ms += ms_since(t);
        const Transform T = icp.T_target_source.inverse();
        t = Clock::now();
        const Verification v = verify_pose({&object->mesh, object->model_points, db_.params.voxel_m}, T, frame.depth,
                                           frame.K, d.cloud.points, options_.verify);
        out.times.verify_ms += ms_since(t);
        ++out.hypotheses;
        if (!v.accepted) continue;
        if (v.score > chosen.score) {
          runner_up = std::max(runner_up, chosen.score);
          chosen.T_camera_object = T;
          chosen.score = v.score;
          chosen.icp_fitness = icp.fitness;
          chosen.icp_rmse_m = icp.inlier_rmse;
          chosen.verification = v;
        } else {
          runner_up = std::max(runner_up, v.score);
        }
      }
      chosen.runner_up_score = runner_up;
      best = chosen;
    }
    if (best) out.detections.push_back(*best);
  }
  out.times.total_ms = ms_since(start);
  return out;
}

}  // namespace viewpose
