#include "viewpose/io/recognition_json.hpp"

namespace viewpose {

nlohmann::json verification_json(const Verification& v) {
  return {{"fit_score", v.score},
          {"inlier_fraction", v.inlier_fraction},
          {"conflict_fraction", v.conflict_fraction},
          {"cluster_explained", v.cluster_explained},
          {"cluster_beside", v.cluster_beside},
          {"footprint_explained", v.footprint_explained},
          {"explained_beside_neighbour", v.explained_beside_neighbour},
          {"model_support", v.model_support},
          {"visible_fraction", v.visible_fraction},
          {"unmeasured_fraction", v.unmeasured_fraction},
          {"mean_depth_m", v.mean_depth_m},
          {"inliers", v.inliers},
          {"outline_continuation", v.outline_continuation},
          {"outline", {{"continued", v.outline_continued}, {"stepped", v.outline_stepped}, {"in_front", v.outline_in_front}, {"unknown", v.outline_unknown}}},
          {"model_rms_m", v.model_rms_m},
          {"plane_rms_m", v.plane_rms_m},
          {"model_relief_m", v.model_relief_m}};
}

nlohmann::json detection_json(const Detection& d) {
  const Eigen::Matrix3d R = d.T_camera_object.linear();
  const Eigen::Vector3d t = d.T_camera_object.translation();
  return {{"object_id", d.object_id}, {"object_name", d.object_name},
          {"R", {R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)}},
          {"t_m", {t.x(), t.y(), t.z()}}, {"score", d.score}, {"icp_fitness", d.icp_fitness},
          {"icp_rmse_m", d.icp_rmse_m}, {"match_rank", d.match_rank}, {"roll_deg", d.roll_deg},
          {"cluster_points", d.cluster_points}, {"from_split_cluster", d.from_split_cluster},
          {"runner_up_score", d.runner_up_score},
          {"verification", verification_json(d.verification)}};
}

nlohmann::json recognition_json(const Recognition& r, bool with_times) {
  nlohmann::json dets = nlohmann::json::array();
  for (const Detection& d : r.detections) dets.push_back(detection_json(d));
  nlohmann::json j = {{"detections", dets}, {"cut_short", r.cut_short}, {"clusters", r.clusters},
                      {"split_clusters", r.split_clusters}, {"regions", r.regions}, {"parts_unreached", r.parts_unreached}, {"hypotheses", r.hypotheses}, {"repeats", r.repeats}, {"screened", r.screened}, {"screened_out", r.screened_out}, {"screened_merged", r.screened_merged}, {"icp_steps", r.icp_steps},
                      {"dropped_as_explained", r.dropped_as_explained}, {"dropped_inside_planes", r.dropped_inside_planes},
                      {"lifted_out_of_planes", r.lifted_out_of_planes},
                      {"joined_regions", r.joined_regions}, {"grown_regions", r.grown_regions},
                      {"voted_regions", r.voted_regions}};
  if (r.best_below_min_score) j["best_below_min_score"] = detection_json(*r.best_below_min_score);
  if (with_times) {
    const StageTimes& t = r.times;
    j["times_ms"] = {{"downsample", t.downsample_ms}, {"segment", t.segment_ms}, {"normals", t.normals_ms},
                     {"vfh", t.vfh_ms}, {"match", t.match_ms}, {"crh", t.crh_ms}, {"icp", t.icp_ms},
                     {"verify", t.verify_ms}, {"split", t.split_ms}, {"total", t.total_ms}};
  }
  return j;
}

}  // namespace viewpose
