// viewpose's point pair feature voting beside OpenCV's implementation of the same method (Drost et
// al. 2010), cv::ppf_match_3d::PPF3DDetector from opencv_contrib's surface_matching (OpenCV 4.6,
// Debian 12). Benchmark only: OpenCV appears in this file and nowhere in the library.
//
// Model: the built-in jug's model points and outward normals, as the view database makes them
// (build_view_database), for both. viewpose: PpfModel (make_ppf_table) with the default
// PpfOptions. OpenCV: PPF3DDetector(relativeSamplingStep 0.05 = viewpose's sample_fraction,
// relativeDistanceStep 0.05, 30 angles = viewpose's angle_bins), trainModel on the points and
// normals as an Nx6 CV_32F Mat.
//
// Scenes (each fixed, or drawn from a fixed std::mt19937 seed): rendered with the simulated Kinect
// v1 (render, depth_to_cloud, estimate_normals_organized), as tests/pose/test_ppf.cpp does:
//   jug_alone_sN     the jug alone, at a random rotation, 0.8-1.2 m in front of the camera
//   jug_hidden       the jug half hidden by a box, beside a can, before a wall (test_ppf.cpp's scene)
//   jug_hidden_sN    the same layout with the jug turned about the vertical by a random angle
// viewpose votes on the scene sampled with ppf_sample at the model's sample_step_m() and
// normal_split_deg(); OpenCV's match() gets the scene's points and normals (Nx6 CV_32F) and samples
// them itself, with relativeSceneSampleStep 1/5 (viewpose's reference_stride 5) and
// relativeSceneDistance 0.05. Its pose clustering gets viewpose's thresholds through setSearchParams
// (a tenth of the diameter, 24 degrees): OpenCV's defaults take the relative sampling step 0.05 as an
// absolute distance and give a rotation threshold of about 30 radians, that is none.
//
// Differences the numbers carry, since OpenCV does not allow otherwise:
//  - OpenCV samples model and scene on a grid of 1/0.05 = 20 cells along each axis of the cloud's own
//    bounding box (samplePCByQuantization): the scene's cells follow the scene's extent, not the
//    model's diameter, and are not cubes; its diameter is the model's bounding-box diagonal, not
//    the largest distance between two points. viewpose samples both on cubes of 0.05 diameters and
//    keeps one point per group of normals more than 30 degrees apart in a cube.
//  - OpenCV takes every 5th sampled scene point as a reference point, with no upper bound; viewpose
//    every 5th, at most 40 (max_reference_points). OpenCV pairs a reference point with every scene
//    point; viewpose only with those within the diameter.
//  - OpenCV returns every pose cluster it made; viewpose the 10 with the most votes.
//  - Both on `--threads` threads (default 1): Debian's libopencv_surface_matching is built without
//    OpenMP, so match() runs on one thread whatever is asked; viewpose's votes use OpenMP.
//
// Normals: viewpose's model normals point outward and its scene normals towards the camera. A
// surface the camera sees faces it, so its outward normal points towards the camera as well: the two
// orientations agree, and both are handed to OpenCV as they are (unit length, non-finite ones left
// out), model and scene alike.
//
// For each scene and method: the training (table) time (viewpose: median of --runs; OpenCV: once,
// as it takes minutes), the matching time (median of --runs, default 3: ppf_sample plus hypotheses
// for viewpose, match() for OpenCV, each sampling its scene), the number of hypotheses, and the
// errors of the best of the first 1 and first 3 hypotheses against the ground truth. "Best" is the hypothesis with the smallest
// max(rotation / 15 degrees, translation / (0.1 diameter)), ICP's reach as test_ppf.cpp uses it;
// "hit" says it is within both.
//
// Usage: viewpose_opencv_ppf_bench [--runs N] [--threads N] [--json FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <omp.h>

#include <opencv2/core.hpp>
#include <opencv2/surface_matching.hpp>
#include <opencv2/surface_matching/ppf_helpers.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/core/object_model.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/describe/normals.hpp"
#include "viewpose/pose/ppf.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

namespace {

using namespace viewpose;
using Clock = std::chrono::steady_clock;

constexpr double kPi = 3.14159265358979323846;

double ms(Clock::time_point since) { return std::chrono::duration<double, std::milli>(Clock::now() - since).count(); }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

double rotation_deg(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / kPi;
}

/// A square of side 2 * half in the z = 0 plane: the wall behind the objects.
TriangleMesh square(float half) {
  TriangleMesh m;
  m.vertices = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

/// A rotation drawn uniformly (a unit quaternion from four normal deviates).
Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

struct Scene {
  std::string name;
  std::string what;
  Transform T_camera_jug = Transform::Identity();
  std::vector<Eigen::Vector3f> points, normals;  // camera frame; normals unit, towards the camera
  double jug_visible = 1;  // share of the jug's unhidden pixels that the frame shows
};

/// Renders `instances` (the jug first), and keeps the points nearer than `max_z` that have a normal.
Scene make_scene(std::string name, std::string what, std::span<const MeshInstance> instances, float max_z) {
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  Scene s;
  s.name = std::move(name);
  s.what = std::move(what);
  s.T_camera_jug = instances[0].T_camera_object;
  const RenderedFrame f = render(instances, K, {});
  std::size_t jug = 0, unhidden = 0;
  for (const std::int32_t i : f.instance) jug += i == 0;
  for (const std::int32_t i : render(instances.first(1), K, {}).instance) unhidden += i == 0;
  s.jug_visible = unhidden ? double(jug) / double(unhidden) : 0;
  PointCloud cloud = depth_to_cloud(f.depth, K);
  estimate_normals_organized(cloud);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.points[i].allFinite() && cloud.points[i].z() < max_z && cloud.normals[i].allFinite() &&
        cloud.normals[i].norm() > 0.5f) {
      s.points.push_back(cloud.points[i]);
      s.normals.push_back(cloud.normals[i].normalized());
    }
  }
  return s;
}

std::vector<Scene> make_scenes(const TriangleMesh& jug) {
  std::vector<Scene> scenes;
  for (const unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> distance(0.8, 1.2), lateral(-0.1, 0.1);
    const Eigen::Matrix3d R = random_rotation(rng);
    const double x = lateral(rng), y = lateral(rng), z = distance(rng);
    const MeshInstance alone[] = {{&jug, make_transform(R, {x, y, z})}};
    scenes.push_back(make_scene(fmt::format("jug_alone_s{}", seed), fmt::format("jug alone, random pose, seed {}", seed), alone, 10.0f));
  }
  const TriangleMesh can = make_can();
  const TriangleMesh box = make_box_mesh({0.3f, 0.12f, 0.08f});
  const TriangleMesh wall = square(2.0f);
  const auto hidden = [&](double yaw, std::string name, std::string what) {
    // Standing (its z up, the camera's -y), turned `yaw` about the vertical; the can touches its
    // side, a long box in front hides its lower part, a wall 1.4 m away behind.
    const Eigen::Matrix3d R =
        (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-kPi / 2, Eigen::Vector3d::UnitX())).toRotationMatrix();
    const MeshInstance all[] = {{&jug, make_transform(R, {-0.05, 0.0, 0.95})},
                                {&can, make_transform(Eigen::Matrix3d::Identity(), {0.09, 0.02, 0.93})},
                                {&box, make_transform(Eigen::Matrix3d::Identity(), {-0.05, 0.1, 0.75})},
                                {&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.4})}};
    // Everything in front of the wall: the jug, the can and the box, as one region.
    scenes.push_back(make_scene(std::move(name), std::move(what), all, 1.3f));
  };
  hidden(0.6, "jug_hidden", "jug half hidden by a box, beside a can (test_ppf.cpp)");
  for (const unsigned seed : {4u, 5u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> yaw(0.0, 2 * kPi);
    hidden(yaw(rng), fmt::format("jug_hidden_s{}", seed), fmt::format("the same, random yaw, seed {}", seed));
  }
  return scenes;
}

cv::Mat to_mat(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals) {
  cv::Mat m(static_cast<int>(points.size()), 6, CV_32F);
  for (std::size_t i = 0; i < points.size(); ++i) {
    float* row = m.ptr<float>(static_cast<int>(i));
    for (int k = 0; k < 3; ++k) row[k] = points[i][k], row[3 + k] = normals[i][k];
  }
  return m;
}

std::size_t opencv_sampled_size(const cv::Mat& cloud, double relative_step) {
  // The bounding box as computeBboxStd makes it (which libopencv_surface_matching does not export).
  cv::Vec2f xr(INFINITY, -INFINITY), yr = xr, zr = xr;
  for (int i = 0; i < cloud.rows; ++i) {
    const float* p = cloud.ptr<float>(i);
    xr = {std::min(xr[0], p[0]), std::max(xr[1], p[0])};
    yr = {std::min(yr[0], p[1]), std::max(yr[1], p[1])};
    zr = {std::min(zr[0], p[2]), std::max(zr[1], p[2])};
  }
  return static_cast<std::size_t>(cv::ppf_match_3d::samplePCByQuantization(cloud, xr, yr, zr, static_cast<float>(relative_step), 0).rows);
}

struct PoseError {
  double rotation_deg = NAN, translation_mm = NAN;
  bool hit = false;
};

/// The best of the first `n` poses (smallest max(rotation / 15 deg, translation / (0.1 diameter))).
PoseError best_of(const std::vector<Transform>& poses, const Transform& truth, std::size_t n, double diameter_m) {
  PoseError best;
  double score = INFINITY;
  for (std::size_t i = 0; i < std::min(n, poses.size()); ++i) {
    const double r = rotation_deg(poses[i], truth), t = (poses[i].translation() - truth.translation()).norm();
    const double s = std::max(r / 15.0, t / (0.1 * diameter_m));
    if (s < score) score = s, best = {r, t * 1000.0, s <= 1.0};
  }
  return best;
}

struct Row {
  std::string scene, method;
  double train_ms = 0, match_ms = 0;
  std::size_t scene_points = 0, sampled_scene_points = 0, hypotheses = 0;
  PoseError top1, top3;
};

nlohmann::json to_json(const PoseError& e) {
  return {{"rotation_deg", std::isfinite(e.rotation_deg) ? nlohmann::json(e.rotation_deg) : nlohmann::json()},
          {"translation_mm", std::isfinite(e.translation_mm) ? nlohmann::json(e.translation_mm) : nlohmann::json()},
          {"within_icp_reach", e.hit}};
}

std::string fmt_error(const PoseError& e) {
  if (!std::isfinite(e.rotation_deg)) return "-";
  return fmt::format("{:6.1f} deg {:6.1f} mm{}", e.rotation_deg, e.translation_mm, e.hit ? "*" : " ");
}

int run(int argc, char** argv) {
  int runs = 3, threads = 1;
  std::string json_path;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(fmt::format("{} needs a value", a));
      return argv[++i];
    };
    if (a == "--runs") runs = std::max(1, std::stoi(value()));
    else if (a == "--threads") threads = std::max(1, std::stoi(value()));
    else if (a == "--json") json_path = value();
    else if (a == "-h" || a == "--help") {
      std::puts("usage: viewpose_opencv_ppf_bench [--runs N (3)] [--threads N (1)] [--json FILE]");
      return 0;
    } else {
      throw std::runtime_error(fmt::format("unknown argument '{}' (--runs, --threads, --json)", a));
    }
  }
  omp_set_num_threads(threads);
  cv::setNumThreads(threads);

  const ObjectModel jug_model{1, "jug", make_jug()};
  const ViewDatabase db = build_view_database(std::span(&jug_model, 1), DatabaseParams{});
  const DatabaseObject& o = db.objects[0];
  const PpfOptions options;  // viewpose's defaults
  constexpr double kRelativeSampling = 0.05, kRelativeDistance = 0.05, kAngles = 30;
  constexpr double kSceneSampleStep = 1.0 / 5.0, kSceneDistance = 0.05;
  const cv::Mat model_mat = to_mat(o.model_points, o.model_normals);

  // Training: the table of each, --runs times.
  std::vector<double> vp_train, cv_train;
  std::unique_ptr<PpfModel> model;
  std::unique_ptr<cv::ppf_match_3d::PPF3DDetector> detector;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Clock::now();
    model = std::make_unique<PpfModel>(o.model_points, o.model_normals, o.diameter_m, options);
    vp_train.push_back(ms(t0));
  }
  {  // Once: OpenCV's table of the jug takes minutes (its hash buckets are lists).
    const auto t0 = Clock::now();
    detector = std::make_unique<cv::ppf_match_3d::PPF3DDetector>(kRelativeSampling, kRelativeDistance, kAngles);
    detector->trainModel(model_mat);
    cv_train.push_back(ms(t0));
  }
  detector->setSearchParams(options.cluster_distance_fraction * o.diameter_m, options.cluster_angle_deg * kPi / 180.0, false);
  const std::size_t cv_model_sampled = opencv_sampled_size(model_mat, kRelativeSampling);
  Eigen::Vector3f lo = o.model_points[0], hi = lo;
  for (const auto& p : o.model_points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);

  fmt::print("viewpose point pair votes beside OpenCV {} PPF3DDetector; {} runs, {} thread(s)\n", CV_VERSION, runs, threads);
  fmt::print("model: jug, {} points; viewpose: diameter {:.1f} mm, step {:.1f} mm, {} sampled points, {} pairs; "
             "OpenCV: bounding-box diagonal {:.1f} mm, {} sampled points\n",
             o.model_points.size(), o.diameter_m * 1000, model->sample_step_m() * 1000, model->sampled().size(), model->pairs(),
             (hi - lo).norm() * 1000, cv_model_sampled);
  fmt::print("training (table): viewpose {:.1f} ms (median of {}), OpenCV {:.1f} ms (once)\n\n", median(vp_train), runs, median(cv_train));

  std::vector<Row> rows;
  for (const Scene& s : make_scenes(o.mesh)) {
    Row vp{s.name, "viewpose", median(vp_train), 0, s.points.size(), 0, 0, {}, {}};
    Row cvr{s.name, "opencv", median(cv_train), 0, s.points.size(), 0, 0, {}, {}};
    std::vector<double> vp_ms, cv_ms;
    std::vector<Transform> vp_poses, cv_poses;
    const cv::Mat scene_mat = to_mat(s.points, s.normals);
    for (int r = 0; r < runs; ++r) {
      auto t0 = Clock::now();
      const OrientedPoints sampled = ppf_sample(s.points, s.normals, model->sample_step_m(), model->normal_split_deg());
      const std::vector<PpfHypothesis> h = model->hypotheses(sampled);
      vp_ms.push_back(ms(t0));
      vp.sampled_scene_points = sampled.size();
      vp_poses.clear();
      for (const PpfHypothesis& x : h) vp_poses.push_back(x.T_camera_object);

      std::vector<cv::ppf_match_3d::Pose3DPtr> results;
      t0 = Clock::now();
      detector->match(scene_mat, results, kSceneSampleStep, kSceneDistance);
      cv_ms.push_back(ms(t0));
      cv_poses.clear();
      for (const auto& p : results) {
        Eigen::Matrix4d m;
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) m(i, j) = p->pose(i, j);
        Transform T = Transform::Identity();
        T.linear() = Eigen::Quaterniond(m.topLeftCorner<3, 3>()).normalized().toRotationMatrix();  // clustered poses average quaternions
        T.translation() = m.topRightCorner<3, 1>();
        cv_poses.push_back(T);
      }
    }
    cvr.sampled_scene_points = opencv_sampled_size(scene_mat, kSceneDistance);
    vp.match_ms = median(vp_ms), cvr.match_ms = median(cv_ms);
    vp.hypotheses = vp_poses.size(), cvr.hypotheses = cv_poses.size();
    vp.top1 = best_of(vp_poses, s.T_camera_jug, 1, o.diameter_m), vp.top3 = best_of(vp_poses, s.T_camera_jug, 3, o.diameter_m);
    cvr.top1 = best_of(cv_poses, s.T_camera_jug, 1, o.diameter_m), cvr.top3 = best_of(cv_poses, s.T_camera_jug, 3, o.diameter_m);
    fmt::print("{}: {} ({} points, {:.1f}% of the jug's pixels visible)\n", s.name, s.what, s.points.size(), 100 * s.jug_visible);
    rows.push_back(vp), rows.push_back(cvr);
  }

  fmt::print("\n{:<14} {:<9} {:>9} {:>9} {:>7} {:>5} {:>19} {:>19}\n", "scene", "method", "train ms", "match ms", "sampled",
             "hyps", "best of 1", "best of 3");
  for (const Row& r : rows)
    fmt::print("{:<14} {:<9} {:9.1f} {:9.1f} {:7} {:5} {:>19} {:>19}\n", r.scene, r.method, r.train_ms, r.match_ms,
               r.sampled_scene_points, r.hypotheses, fmt_error(r.top1), fmt_error(r.top3));
  fmt::print("(* within ICP's reach: 15 degrees and a tenth of the diameter, {:.0f} mm)\n", 100 * o.diameter_m);

  if (!json_path.empty()) {
    nlohmann::json j;
    j["opencv_version"] = CV_VERSION;
    j["runs"] = runs;
    j["opencv_train_runs"] = 1;
    j["threads"] = threads;
    j["model"] = {{"name", "jug"},
                  {"points", o.model_points.size()},
                  {"viewpose_diameter_m", o.diameter_m},
                  {"viewpose_sample_step_m", model->sample_step_m()},
                  {"viewpose_sampled_points", model->sampled().size()},
                  {"viewpose_pairs", model->pairs()},
                  {"opencv_bbox_diagonal_m", (hi - lo).norm()},
                  {"opencv_sampled_points", cv_model_sampled}};
    j["opencv_parameters"] = {{"relative_sampling_step", kRelativeSampling},
                              {"relative_distance_step", kRelativeDistance},
                              {"num_angles", kAngles},
                              {"relative_scene_sample_step", kSceneSampleStep},
                              {"relative_scene_distance", kSceneDistance},
                              {"position_threshold_m", options.cluster_distance_fraction * o.diameter_m},
                              {"rotation_threshold_deg", options.cluster_angle_deg}};
    j["rows"] = nlohmann::json::array();
    for (const Row& r : rows)
      j["rows"].push_back({{"scene", r.scene},
                           {"method", r.method},
                           {"train_ms", r.train_ms},
                           {"match_ms_median", r.match_ms},
                           {"scene_points", r.scene_points},
                           {"sampled_scene_points", r.sampled_scene_points},
                           {"hypotheses", r.hypotheses},
                           {"best_of_1", to_json(r.top1)},
                           {"best_of_3", to_json(r.top3)}});
    write_file_atomic(json_path, j.dump(2) + "\n");  // (no half file if the run fails)
    fmt::print("wrote {}\n", json_path);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "viewpose_opencv_ppf_bench: %s\n", e.what());
    return 1;
  }
}
