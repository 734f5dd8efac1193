// Each stage of recognition alone, on fixed inputs: a simulated Kinect VGA frame of the jug on a
// table at 1 m (and a harder one), the jug's 80-view database, and a thousand-object database for
// matching.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "viewpose/database/matching.hpp"
#include "viewpose/describe/crh.hpp"
#include "viewpose/describe/describe.hpp"
#include "viewpose/pose/icp.hpp"
#include "viewpose/pose/ppf.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/segment/segmentation.hpp"
#include "viewpose/segment/voxel_grid.hpp"
#include "viewpose/simulate/scaled_database.hpp"
#include "viewpose/simulate/scene.hpp"

namespace {

using namespace viewpose;

// Everything the stages take, made once.
struct Inputs {
  ObjectModel jug{1, "jug", make_jug()};
  ViewDatabase db;
  DepthImage depth;       // found at the first match, as most frames are
  DepthImage hard_depth;  // the jug turned so that the right view is the 11th match: 27 hypotheses
  CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  Frame frame;
  PointCloud cluster;  // the jug's cluster, voxelized
  Description description;
  std::vector<Eigen::Vector3f> icp_source;
  Transform T_model_cluster_initial = Transform::Identity();  // the nearest view's first CRH roll
  Transform T_camera_object = Transform::Identity();          // the refined pose

  Inputs() {
    db = build_view_database(std::span(&jug, 1), DatabaseParams{});
    SeedExperimentOptions setup;
    setup.distances_m = {1.0};
    setup.orientations = 4;
    const SimDataset scenes = make_seed_experiment(jug, K, setup, 7);
    depth = simulate_image(scenes, scenes.scenes[0].images[0], SensorModel::kinect_v1(), 1).depth;
    hard_depth = simulate_image(scenes, scenes.scenes[0].images[1], SensorModel::kinect_v1(), 1).depth;
    frame = frame_from_depth(depth, K);
    SegmentOptions so;
    so.voxel_m = db.params.voxel_m;
    const Segmentation seg = segment_scene(frame.cloud, so);
    cluster = cluster_points(seg.points, seg.clusters.at(0));
    description = describe(cluster, db.params.describe);
    icp_source = voxel_downsample(description.cloud, 0.005f).points;
    const Match m = nearest_views(db, description.vfh, 1).at(0);
    const ViewEntry& view = db.views[m.view];
    const float roll = crh_roll_angles(view.crh, description.crh, RollOptions{10, 0.2f, 0.5f}).at(0);
    T_model_cluster_initial =
        (crh_alignment(view.centroid.cast<double>(), description.centroid.cast<double>(), roll) * view.T_view_object).inverse();
    const IcpTarget target(db.objects[0].model_points, db.objects[0].model_normals);
    T_camera_object = icp_point_to_plane(icp_source, target, T_model_cluster_initial).T_target_source.inverse();
  }
};

const Inputs& inputs() {
  static const Inputs in;
  return in;
}

void BM_FrameFromDepth(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) benchmark::DoNotOptimize(frame_from_depth(in.depth, in.K));
}
BENCHMARK(BM_FrameFromDepth)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SegmentFrame(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) benchmark::DoNotOptimize(segment_scene(in.frame.cloud));
}
BENCHMARK(BM_SegmentFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

// The general path: the same points in random order, as an unorganized cloud from a file.
void BM_SegmentUnorganizedCloud(benchmark::State& state) {
  const Inputs& in = inputs();
  std::vector<Eigen::Vector3f> points = in.frame.cloud.points;
  std::shuffle(points.begin(), points.end(), std::mt19937_64(1));
  const PointCloud shuffled = PointCloud::from_points(points);
  for (auto _ : state) benchmark::DoNotOptimize(segment_scene(shuffled));
}
BENCHMARK(BM_SegmentUnorganizedCloud)->Unit(benchmark::kMillisecond)->UseRealTime();

// A simulated room (issue 11's preset): a table among walls, floor and furniture up to 4 m away,
// which leave three to five times the points of a tabletop frame once the planes are gone.
const Frame& room_frame() {
  static const Frame frame = [] {
    const std::vector<ObjectModel> objects = {{1, "jug", make_jug()}, {2, "box", make_named_shape("box")}};
    RoomPresetOptions options;
    options.rooms = 1;
    options.images = 2;
    const SimDataset rooms = make_room_scenes(objects, CameraIntrinsics::kinect_v1(), options, 11);
    return frame_from_depth(simulate_image(rooms, rooms.scenes[0].images[0], SensorModel::kinect_v1(), 1).depth,
                            CameraIntrinsics::kinect_v1());
  }();
  return frame;
}

void BM_SegmentRoomFrame(benchmark::State& state) {
  const Frame& frame = room_frame();
  SegmentTimes times;
  for (auto _ : state) benchmark::DoNotOptimize(segment_scene(frame.cloud, {}, &times));
  const double n = static_cast<double>(state.iterations());
  state.counters["planes_ms"] = times.planes_ms / n;
  state.counters["downsample_ms"] = times.downsample_ms / n;
  state.counters["clusters_ms"] = times.clusters_ms / n;
}
BENCHMARK(BM_SegmentRoomFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

// Euclidean clusters alone, on what a room frame leaves once its planes are removed, voxelized.
void BM_ClustersOfRoomFrame(benchmark::State& state) {
  static const PointCloud points = [] {
    SegmentOptions no_clusters;
    no_clusters.clusters.max_points = 0;
    return segment_scene(room_frame().cloud, no_clusters).points;
  }();
  std::vector<std::uint32_t> all(points.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  state.SetLabel(std::to_string(points.size()) + " points");
  for (auto _ : state) benchmark::DoNotOptimize(euclidean_clusters(points, all));
}
BENCHMARK(BM_ClustersOfRoomFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_NormalsOfCluster(benchmark::State& state) {
  const Inputs& in = inputs();
  state.SetLabel(std::to_string(in.cluster.size()) + " points");
  for (auto _ : state) {
    PointCloud c = PointCloud::from_points(in.cluster.points);
    estimate_normals(c, in.db.params.describe.normals);
    benchmark::DoNotOptimize(c.normals.data());
  }
}
BENCHMARK(BM_NormalsOfCluster)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VfhAndCrh(benchmark::State& state) {
  const Inputs& in = inputs();
  const PointCloud& c = in.description.cloud;
  for (auto _ : state) {
    benchmark::DoNotOptimize(compute_vfh(c.points, c.normals, in.db.params.describe.vfh));
    benchmark::DoNotOptimize(compute_crh(c.normals, in.description.centroid));
  }
}
BENCHMARK(BM_VfhAndCrh)->Unit(benchmark::kMillisecond)->UseRealTime();

// The rolls of the cluster against every view of the jug's database (a real frame's region is
// matched to 20 views of each object: 140 roll searches for a database of seven). Arg 0: PCL's
// peak options (RollOptions{}: 5 peaks at 0.8 of the best); 1: the recognizer's (MatchOptions).
void BM_CrhRollsAllViews(benchmark::State& state) {
  const Inputs& in = inputs();
  const RollOptions options = state.range(0) == 0 ? RollOptions{} : MatchOptions{}.roll;
  for (auto _ : state) {
    for (const ViewEntry& view : in.db.views) benchmark::DoNotOptimize(crh_roll_angles(view.crh, in.description.crh, options));
  }
  state.SetLabel(std::to_string(in.db.views.size()) + " views");
}
BENCHMARK(BM_CrhRollsAllViews)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();

// Matching one cluster against 1000 objects x 80 views: through the index, and exhaustively.
const ViewDatabase& thousand_objects() {
  static const ViewDatabase db = scaled_database(inputs().db, 1000, 3);
  return db;
}

void BM_Match1000Objects(benchmark::State& state) {
  const ViewIndex index(thousand_objects());
  state.SetLabel(std::to_string(index.views()) + " views");
  for (auto _ : state) benchmark::DoNotOptimize(index.nearest(inputs().description.vfh, 20, 120));
}
BENCHMARK(BM_Match1000Objects)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Match1000ObjectsExhaustive(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(nearest_views_per_object(thousand_objects(), inputs().description.vfh, 20));
}
BENCHMARK(BM_Match1000ObjectsExhaustive)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IcpOneHypothesis(benchmark::State& state) {
  const Inputs& in = inputs();
  const IcpTarget target(in.db.objects[0].model_points, in.db.objects[0].model_normals);
  const IcpResult r = icp_point_to_plane(in.icp_source, target, in.T_model_cluster_initial);  // fills the grid's cells
  state.SetLabel(std::to_string(r.iterations) + " iterations");
  for (auto _ : state) benchmark::DoNotOptimize(icp_point_to_plane(in.icp_source, target, in.T_model_cluster_initial));
}
BENCHMARK(BM_IcpOneHypothesis)->Unit(benchmark::kMillisecond)->UseRealTime();

// The screen's short ICP (MatchOptions::prescreen), as the recognizer makes it from the default
// options: the ICP schedule's stages but the last, MatchOptions::prescreen_iterations steps each
// at most, on prescreen_points of the cluster's points, then its fitness at the last stage's
// reach. Arg: the points it takes (100 as shipped; 400, full ICP's).
void BM_IcpScreenOneHypothesis(benchmark::State& state) {
  const Inputs& in = inputs();
  const IcpTarget target(in.db.objects[0].model_points, in.db.objects[0].model_normals);
  IcpOptions screen;
  const float reach = screen.max_correspondence_m.back();
  screen.max_correspondence_m.pop_back();
  screen.max_iterations_per_stage = MatchOptions{}.prescreen_iterations;
  screen.max_source_points = static_cast<std::size_t>(state.range(0));
  screen.min_fitness_after_first_stage = 0;
  const IcpResult r = icp_point_to_plane(in.icp_source, target, in.T_model_cluster_initial, screen);  // fills the grid's cells
  state.SetLabel(std::to_string(r.iterations) + " iterations");
  for (auto _ : state) {
    const IcpResult screened = icp_point_to_plane(in.icp_source, target, in.T_model_cluster_initial, screen);
    benchmark::DoNotOptimize(icp_fitness(in.icp_source, target, screened.T_target_source, reach, screen));
  }
}
BENCHMARK(BM_IcpScreenOneHypothesis)->Arg(static_cast<std::int64_t>(MatchOptions{}.prescreen_points))->Arg(400)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_VerifyOneHypothesis(benchmark::State& state) {
  const Inputs& in = inputs();
  const DatabaseObject& o = in.db.objects[0];
  const VerifyModel model{&o.mesh, o.model_points, in.db.params.voxel_m, closed_mesh_winding(o.mesh), o.model_normals};
  for (auto _ : state) {
    benchmark::DoNotOptimize(verify_pose(model, in.T_camera_object, in.frame.depth, in.K, in.description.cloud.points));
  }
}
BENCHMARK(BM_VerifyOneHypothesis)->Unit(benchmark::kMillisecond)->UseRealTime();

// Point pair features (issue 19): the jug's pair table, and the votes of the jug's cluster.
void BM_PpfBuildJugTable(benchmark::State& state) {
  const Inputs& in = inputs();
  const DatabaseObject& o = in.db.objects[0];
  for (auto _ : state) benchmark::DoNotOptimize(PpfModel(o.model_points, o.model_normals, o.diameter_m));
}
BENCHMARK(BM_PpfBuildJugTable)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PpfHypothesesJugCluster(benchmark::State& state) {
  const Inputs& in = inputs();
  const DatabaseObject& o = in.db.objects[0];
  const PpfModel model(o.model_points, o.model_normals, o.diameter_m);
  const OrientedPoints scene = ppf_sample(in.description.cloud.points, in.description.cloud.normals, model.sample_step_m(),
                                          model.options().normal_split_deg);
  state.SetLabel(std::to_string(scene.size()) + " scene points, " + std::to_string(model.sampled().size()) + " model points, " +
                 std::to_string(model.pairs()) + " pairs");
  for (auto _ : state) benchmark::DoNotOptimize(model.hypotheses(scene));
}
BENCHMARK(BM_PpfHypothesesJugCluster)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RecognizeFrame(benchmark::State& state) {
  const Inputs& in = inputs();
  const Recognizer recognizer(in.db);
  recognizer.recognize(in.frame);  // the first hypothesis builds the object's grid
  for (auto _ : state) benchmark::DoNotOptimize(recognizer.recognize(frame_from_depth(in.depth, in.K)));
}
BENCHMARK(BM_RecognizeFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RecognizeHardFrame(benchmark::State& state) {
  const Inputs& in = inputs();
  const Recognizer recognizer(in.db);
  for (auto _ : state) benchmark::DoNotOptimize(recognizer.recognize(frame_from_depth(in.hard_depth, in.K)));
}
BENCHMARK(BM_RecognizeHardFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BuildDatabaseJug80Views(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) benchmark::DoNotOptimize(build_view_database(std::span(&in.jug, 1), DatabaseParams{}));
}
BENCHMARK(BM_BuildDatabaseJug80Views)->Unit(benchmark::kMillisecond)->UseRealTime();

// ICP on an object seen for the first time: its grid's cells are filled as they are asked for.
void BM_IcpFirstHypothesisOfAnObject(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) {
    const IcpTarget target(in.db.objects[0].model_points, in.db.objects[0].model_normals);
    benchmark::DoNotOptimize(icp_point_to_plane(in.icp_source, target, in.T_model_cluster_initial));
  }
}
BENCHMARK(BM_IcpFirstHypothesisOfAnObject)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
