// The thesis's pipeline with PCL 1.13 and viewpose's, on the same frames in one process, stage by
// stage. Frames: the seed experiment (the built-in jug on a table at 0.75-1.50 m, simulated
// Kinect v1), the database of its 80 views built by viewpose and used by both (its VFHs and CRHs
// are PCL's, tests/describe/test_pcl_fixtures.cpp).
//
// PCL side, with the thesis's parameters: VoxelGrid 3 mm; SACSegmentation (RANSAC plane, 1 cm,
// 1000 iterations) and ExtractIndices while the plane holds at least a fifth of the frame (at
// most 3); EuclideanClusterExtraction 2 cm; then on each cluster NormalEstimation (1.5 cm),
// VFHEstimation, CRHEstimation; the 20 nearest views by chi-squared; CRHAlignment of each; and for
// the first `--hypotheses` (match, roll) pairs IterativeClosestPoint (model at 5 mm onto the
// cluster at 5 mm, 15 mm correspondences, 30 iterations) and GlobalHypothesesVerification of the
// refined models against the scene, all of a cluster's hypotheses in one call as PCL's
// 3d_rec_framework does (resolution and inliers 5 mm, occlusion 1 cm, regularizer 3, without
// clutter detection): the settings that cost PCL least, so that the ratios lean its way. PCL's GHV acceptance is not used to stop (its 1.13 normal
// filter is inverted, pcl-spec.md section 7): every frame runs the same number of hypotheses,
// which is what the per-hypothesis times need.
//
// With --scene FILE --db DATABASE (repeatable --scene), real frames instead: each scene file as
// `viewpose recognize` reads it (PCD/PLY clouds; depth PNGs with --camera and --depth-scale), the
// database's views for both pipelines, each object's model points at 5 mm for PCL's ICP. Each frame
// runs once through each pipeline, PCL with as many hypotheses as viewpose refined and verified in
// that frame (at least 10; --hypotheses N for a fixed number), and the line per frame says how many
// clusters and hypotheses each tried. PCL takes seconds to minutes a frame.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <pcl/features/crh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/vfh.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>
#include <pcl/recognition/crh_alignment.h>
#include <pcl/recognition/hv/hv_go.h>
#include <pcl/registration/icp.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "viewpose/database/matching.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/scene_file.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/segment/voxel_grid.hpp"
#include "viewpose/simulate/scene.hpp"

namespace {

using namespace viewpose;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Clock = std::chrono::steady_clock;

double ms(Clock::time_point since) { return std::chrono::duration<double, std::milli>(Clock::now() - since).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

Cloud::Ptr to_pcl(const std::vector<Eigen::Vector3f>& points, int width = 0, int height = 1) {
  Cloud::Ptr c(new Cloud);
  c->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) c->points[i].getVector3fMap() = points[i];
  c->width = width > 0 ? static_cast<std::uint32_t>(width) : static_cast<std::uint32_t>(points.size());
  c->height = static_cast<std::uint32_t>(height);
  c->is_dense = false;
  return c;
}

pcl::PointCloud<pcl::Histogram<90>> crh_cloud(const Crh& crh) {
  pcl::PointCloud<pcl::Histogram<90>> c;
  c.resize(1);
  for (int i = 0; i < 90; ++i) c.points[0].histogram[i] = crh[static_cast<std::size_t>(i)];
  return c;
}

double chi_squared_pcl(const pcl::VFHSignature308& a, const Vfh& b) {
  double sum = 0;
  for (int i = 0; i < 308; ++i) {
    const double s = a.histogram[i] + b[static_cast<std::size_t>(i)];
    if (s > 0) sum += (a.histogram[i] - b[static_cast<std::size_t>(i)]) * (a.histogram[i] - b[static_cast<std::size_t>(i)]) / s;
  }
  return sum;
}

struct PclTimes {
  double frame = 0, segment = 0, normals = 0, describe = 0, match = 0, icp = 0, verify = 0, total = 0;
  int hypotheses = 0, clusters = 0;
};

// The thesis's pipeline on one frame, PCL doing every stage.
// `models_5mm`: each database object's model points at 5 mm, in the object frame.
PclTimes run_pcl(const Frame& frame, const ViewDatabase& db, const std::vector<Cloud::Ptr>& models_5mm, int max_hypotheses) {
  PclTimes t;
  const auto start = Clock::now();
  auto s = Clock::now();
  const Cloud::Ptr scene = to_pcl(frame.cloud.points, frame.cloud.width, frame.cloud.height);
  t.frame = ms(s);

  s = Clock::now();
  Cloud::Ptr voxels(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(scene);
  grid.setLeafSize(0.003f, 0.003f, 0.003f);
  grid.filter(*voxels);
  Cloud::Ptr rest = voxels;
  for (int plane = 0; plane < 3; ++plane) {
    pcl::SACSegmentation<pcl::PointXYZ> sac;
    sac.setOptimizeCoefficients(true);
    sac.setModelType(pcl::SACMODEL_PLANE);
    sac.setMethodType(pcl::SAC_RANSAC);
    sac.setDistanceThreshold(0.01);
    sac.setMaxIterations(1000);
    sac.setInputCloud(rest);
    pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
    pcl::ModelCoefficients coefficients;
    sac.segment(*inliers, coefficients);
    if (inliers->indices.size() < std::max<std::size_t>(1000, voxels->size() / 5)) break;
    pcl::ExtractIndices<pcl::PointXYZ> extract;
    extract.setInputCloud(rest);
    extract.setIndices(inliers);
    extract.setNegative(true);
    Cloud::Ptr next(new Cloud);
    extract.filter(*next);
    rest = next;
  }
  std::vector<pcl::PointIndices> clusters;
  {
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setClusterTolerance(0.02);
    ec.setMinClusterSize(100);
    ec.setMaxClusterSize(1000000);
    ec.setSearchMethod(tree);
    ec.setInputCloud(rest);
    ec.extract(clusters);
  }
  t.segment = ms(s);
  t.clusters = static_cast<int>(clusters.size());

  for (const pcl::PointIndices& indices : clusters) {
    Cloud::Ptr cluster(new Cloud);
    for (int i : indices.indices) cluster->push_back(rest->points[static_cast<std::size_t>(i)]);
    s = Clock::now();
    pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cluster);
    ne.setSearchMethod(tree);
    ne.setRadiusSearch(0.015);
    ne.compute(*normals);
    // Points with too few neighbours get NaN normals, and one NaN makes the CRH all NaN (and no
    // roll is found): keep the points with normals, as viewpose's describe() does.
    Cloud::Ptr kept(new Cloud);
    pcl::PointCloud<pcl::Normal>::Ptr kept_normals(new pcl::PointCloud<pcl::Normal>);
    for (std::size_t i = 0; i < normals->size(); ++i) {
      if (!std::isfinite(normals->points[i].normal_x)) continue;
      kept->push_back(cluster->points[i]);
      kept_normals->push_back(normals->points[i]);
    }
    cluster = kept;
    normals = kept_normals;
    t.normals += ms(s);

    s = Clock::now();
    pcl::VFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> vfh;
    vfh.setInputCloud(cluster);
    vfh.setInputNormals(normals);
    vfh.setSearchMethod(tree);
    pcl::PointCloud<pcl::VFHSignature308> signature;
    vfh.compute(signature);
    Eigen::Vector4f centroid4;
    pcl::compute3DCentroid(*cluster, centroid4);
    pcl::CRHEstimation<pcl::PointXYZ, pcl::Normal, pcl::Histogram<90>> crh;
    crh.setInputCloud(cluster);
    crh.setInputNormals(normals);
    crh.setCentroid(centroid4);
    pcl::PointCloud<pcl::Histogram<90>> scene_crh;
    crh.compute(scene_crh);
    t.describe += ms(s);

    s = Clock::now();
    std::vector<std::pair<double, std::size_t>> nearest;
    for (std::size_t v = 0; v < db.views.size(); ++v) nearest.emplace_back(chi_squared_pcl(signature.points[0], db.views[v].vfh), v);
    const std::size_t k = std::min<std::size_t>(20, nearest.size());
    std::partial_sort(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(k), nearest.end());
    t.match += ms(s);

    Cloud::Ptr target(new Cloud);
    pcl::VoxelGrid<pcl::PointXYZ> thin;
    thin.setInputCloud(cluster);
    thin.setLeafSize(0.005f, 0.005f, 0.005f);
    thin.filter(*target);
    Eigen::Vector3f scene_centroid = centroid4.head<3>();
    std::vector<Cloud::ConstPtr> refined_models;
    for (std::size_t m = 0; m < k && t.hypotheses < max_hypotheses; ++m) {
      const ViewEntry& view = db.views[nearest[m].second];
      s = Clock::now();
      pcl::CRHAlignment<pcl::PointXYZ, 90> alignment;
      Eigen::Vector3f view_centroid = view.centroid;
      alignment.setInputAndTargetCentroids(view_centroid, scene_centroid);
      pcl::PointCloud<pcl::Histogram<90>> view_crh = crh_cloud(view.crh);
      alignment.align(view_crh, scene_crh);
      std::vector<Eigen::Matrix4f, Eigen::aligned_allocator<Eigen::Matrix4f>> rolls;
      alignment.getTransforms(rolls);
      t.describe += ms(s);
      for (const Eigen::Matrix4f& roll : rolls) {
        if (t.hypotheses >= max_hypotheses) break;
        ++t.hypotheses;
        const Eigen::Matrix4f hypothesis = roll * view.T_view_object.matrix().cast<float>();
        s = Clock::now();
        const Cloud::Ptr& model_5mm = models_5mm[view.object];
        Cloud::Ptr source(new Cloud);
        pcl::transformPointCloud(*model_5mm, *source, hypothesis);
        pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
        icp.setInputSource(source);
        icp.setInputTarget(target);
        icp.setMaxCorrespondenceDistance(0.015);
        icp.setTransformationEpsilon(1e-5);
        icp.setMaximumIterations(30);
        Cloud aligned;
        icp.align(aligned);
        const Eigen::Matrix4f refined = icp.getFinalTransformation() * hypothesis;
        t.icp += ms(s);

        Cloud::Ptr placed(new Cloud);
        pcl::transformPointCloud(*model_5mm, *placed, refined);
        refined_models.push_back(placed);
      }
    }
    // All of the cluster's hypotheses verified together, as the 3d_rec_framework does: the scene
    // is prepared once (verifying one at a time, as the thesis describes, prepares it each time).
    if (refined_models.empty()) continue;
    s = Clock::now();
    pcl::GlobalHypothesesVerification<pcl::PointXYZ, pcl::PointXYZ> ghv;
    // Resolution and occlusion threshold are read when the clouds are set: set them first.
    ghv.setResolution(0.005f);
    ghv.setInlierThreshold(0.005f);
    ghv.setOcclusionThreshold(0.01f);
    ghv.setSceneCloud(scene);
    ghv.setRadiusClutter(0.03f);
    ghv.setRegularizer(3.0f);
    ghv.setClutterRegularizer(5.0f);
    ghv.setDetectClutter(false);  // the cheaper setting: the ratios lean PCL's way
    ghv.setRadiusNormals(0.05f);
    try {
      ghv.addModels(refined_models, true);
      ghv.verify();
      std::vector<bool> mask;
      ghv.getMask(mask);
    } catch (const std::exception&) {
      // PCL 1.13's GHV throws (std::length_error) when occlusion reasoning leaves a model no
      // visible point: a rejection, timed like the rest.
    }
    t.verify += ms(s);
  }
  t.total = ms(start);
  return t;
}

std::string file_text(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  return {bytes.begin(), bytes.end()};
}

std::vector<Cloud::Ptr> models_at_5mm(const ViewDatabase& db) {
  std::vector<Cloud::Ptr> models;
  for (const DatabaseObject& o : db.objects) models.push_back(to_pcl(voxel_downsample(PointCloud::from_points(o.model_points), 0.005f).points));
  return models;
}

// Real frames: each scene once through each pipeline; a line per frame, the per-stage ratios, and
// the JSON's "real_frames".
int run_real_frames(const std::vector<std::string>& scenes, const std::string& db_path, const std::string& camera_path,
                    double depth_scale_mm, int hypotheses, const std::string& json_path) {
  const ViewDatabase db = ViewDatabase::load(db_path);
  const std::vector<Cloud::Ptr> models = models_at_5mm(db);
  const Recognizer recognizer(db);
  std::optional<CameraIntrinsics> K;
  if (!camera_path.empty()) {
    const BopCamera camera = parse_bop_camera(file_text(camera_path), camera_path);
    K = camera.K;
    if (depth_scale_mm <= 0) depth_scale_mm = camera.depth_scale_mm;
  }
  if (depth_scale_mm <= 0) depth_scale_mm = 1.0;
  nlohmann::json rows = nlohmann::json::array();
  fmt::print("{} real frame(s), database {} ({} objects, {} views); PCL {} hypotheses a frame\n", scenes.size(), db_path,
             db.objects.size(), db.views.size(), hypotheses > 0 ? std::to_string(hypotheses) : std::string("as many as viewpose tried (at least 10)"));
  fmt::print("{:<44} {:>10} {:>10} {:>8}  {}\n", "frame (whole frame, ms)", "PCL 1.13", "viewpose", "ratio", "PCL: clusters, hypotheses; viewpose: regions, hypotheses, found");
  for (const std::string& path : scenes) {
    const Frame frame = load_scene_file(path, K, depth_scale_mm).frame;
    auto s = Clock::now();
    const Recognition r = recognizer.recognize(frame);
    const double ours = ms(s);
    // PCL refines and verifies as many poses as viewpose did in this frame (at least 10), unless told.
    const int pcl_hypotheses = hypotheses > 0 ? hypotheses : std::max(10, static_cast<int>(r.hypotheses));
    const PclTimes p = run_pcl(frame, db, models, pcl_hypotheses);
    const double theirs = p.frame + p.total;
    const std::string name = std::filesystem::path(path).filename().string();
    fmt::print("{:<44} {:>10.0f} {:>10.1f} {:>7.0f}x  PCL {}, {}; viewpose {}, {}, {}\n", name, theirs, ours, theirs / ours, p.clusters,
               p.hypotheses, r.regions, r.hypotheses, r.detections.size());
    fmt::print("  PCL ms: segmentation {:.0f}, normals {:.0f}, describe {:.0f}, match {:.1f}, ICP {:.0f}, GHV {:.0f}\n", p.segment, p.normals,
               p.describe, p.match, p.icp, p.verify);
    rows.push_back({{"scene", path}, {"pcl_ms", theirs}, {"viewpose_ms", ours}, {"ratio", theirs / ours}, {"pcl_clusters", p.clusters},
                    {"pcl_hypotheses", p.hypotheses}, {"viewpose_regions", r.regions}, {"viewpose_hypotheses", r.hypotheses},
                    {"viewpose_detections", r.detections.size()},
                    {"pcl_stages_ms", {{"segmentation", p.segment}, {"normals", p.normals}, {"describe", p.describe}, {"match", p.match}, {"icp", p.icp}, {"verify", p.verify}}}});
  }
  if (!json_path.empty()) {
    nlohmann::json j = nlohmann::json::object();
    if (std::filesystem::exists(json_path)) j = nlohmann::json::parse(file_text(json_path));
    j["real_frames"][db_path] = rows;
    write_file_atomic(json_path, j.dump(2) + "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  int frames = 8, hypotheses = -1;  // -1: 10 on simulated frames, as many as viewpose tried on real ones
  double depth_scale_mm = 0;
  std::string json_path, db_path, camera_path;
  std::vector<std::string> scene_files;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--frames") frames = std::max(1, std::atoi(argv[i + 1]));
    else if (flag == "--hypotheses") hypotheses = std::max(1, std::atoi(argv[i + 1]));
    else if (flag == "--json") json_path = argv[i + 1];
    else if (flag == "--scene") scene_files.push_back(argv[i + 1]);
    else if (flag == "--db") db_path = argv[i + 1];
    else if (flag == "--camera") camera_path = argv[i + 1];
    else if (flag == "--depth-scale") depth_scale_mm = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: viewpose_pcl_bench [--frames N] [--hypotheses N] [--json FILE]\n"
                           "       viewpose_pcl_bench --db DB.vpdb --scene FILE [--scene FILE ...] [--camera camera.json] [--depth-scale MM] [--hypotheses N] [--json FILE]\n");
      return 2;
    }
  }
  if (!scene_files.empty() || !db_path.empty()) {
    if (scene_files.empty() || db_path.empty()) {
      std::fprintf(stderr, "viewpose_pcl_bench: --scene and --db go together\n");
      return 2;
    }
    return run_real_frames(scene_files, db_path, camera_path, depth_scale_mm, hypotheses, json_path);
  }
  if (hypotheses < 0) hypotheses = 10;
  const ObjectModel jug{1, "jug", make_jug()};
  const ViewDatabase db = build_view_database(std::span(&jug, 1), DatabaseParams{});
  const std::vector<Cloud::Ptr> models = models_at_5mm(db);
  const Recognizer recognizer(db);
  SeedExperimentOptions setup;
  setup.distances_m = {0.75, 1.00, 1.25, 1.50};
  setup.orientations = (frames + 3) / 4;
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const SimDataset scenes = make_seed_experiment(jug, K, setup, 7);

  std::map<std::string, std::vector<double>> pcl_ms, ours_ms;
  std::vector<double> pcl_hyp, ours_hyp;
  int done = 0;
  for (std::size_t k = 0; k < static_cast<std::size_t>(setup.orientations) && done < frames; ++k) {
    for (const SimScene& scene : scenes.scenes) {
      if (done >= frames) break;
      const DepthImage depth = simulate_image(scenes, scene.images[k], SensorModel::kinect_v1(), 100 * scene.scene_id + k).depth;
      // Ours: the whole pipeline, depth image to verified poses.
      auto s = Clock::now();
      const Frame frame = frame_from_depth(depth, K);
      const double frame_ms = ms(s);
      const Recognition r = recognizer.recognize(frame);
      const StageTimes& o = r.times;
      ours_ms["segmentation"].push_back(o.downsample_ms + o.segment_ms);
      ours_ms["normals"].push_back(o.normals_ms);
      ours_ms["describe (VFH, CRH, roll)"].push_back(o.vfh_ms + o.crh_ms);
      ours_ms["match"].push_back(o.match_ms);
      ours_ms["ICP per hypothesis"].push_back(o.icp_ms / static_cast<double>(std::max<std::size_t>(1, r.hypotheses)));
      ours_ms["verify per hypothesis"].push_back(o.verify_ms / static_cast<double>(std::max<std::size_t>(1, r.hypotheses)));
      ours_ms["whole frame"].push_back(frame_ms + o.total_ms);
      ours_hyp.push_back(static_cast<double>(r.hypotheses));
      // PCL: the thesis's pipeline.
      const PclTimes p = run_pcl(frame, db, models, hypotheses);
      pcl_ms["segmentation"].push_back(p.segment);
      pcl_ms["normals"].push_back(p.normals);
      pcl_ms["describe (VFH, CRH, roll)"].push_back(p.describe);
      pcl_ms["match"].push_back(p.match);
      pcl_ms["ICP per hypothesis"].push_back(p.icp / std::max(1, p.hypotheses));
      pcl_ms["verify per hypothesis"].push_back(p.verify / std::max(1, p.hypotheses));
      pcl_ms["whole frame"].push_back(p.frame + p.total);
      pcl_hyp.push_back(p.hypotheses);
      ++done;
      std::fprintf(stderr, "\rframe %d of %d", done, frames);
    }
  }
  std::fprintf(stderr, "\n");
  fmt::print("{} frames of the seed experiment (0.75-1.50 m), VGA; PCL {} hypotheses a frame, viewpose {:.0f} (median)\n",
             done, median(pcl_hyp), median(ours_hyp));
  fmt::print("{:<28} {:>12} {:>12} {:>9}\n", "stage (median ms)", "PCL 1.13", "viewpose", "ratio");
  nlohmann::json stages = nlohmann::json::array();
  for (const char* stage : {"segmentation", "normals", "describe (VFH, CRH, roll)", "match", "ICP per hypothesis",
                            "verify per hypothesis", "whole frame"}) {
    const double a = median(pcl_ms[stage]), b = median(ours_ms[stage]);
    fmt::print("{:<28} {:>12.2f} {:>12.3f} {:>8.0f}x\n", stage, a, b, b > 0 ? a / b : 0.0);
    stages.push_back({{"stage", stage}, {"pcl_ms", a}, {"viewpose_ms", b}, {"ratio", b > 0 ? a / b : 0.0}});
  }
  if (!json_path.empty()) {
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    const nlohmann::json j = {{"date", date}, {"frames", done}, {"pcl_hypotheses_per_frame", median(pcl_hyp)},
                              {"viewpose_hypotheses_per_frame", median(ours_hyp)}, {"stages", stages}};
    write_file_atomic(json_path, j.dump(2) + "\n");
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "viewpose_pcl_bench: error: %s\n", e.what());
  return 1;
}
