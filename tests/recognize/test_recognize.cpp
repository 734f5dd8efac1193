// End-to-end recognition on simulated frames with ground truth (issue 5's acceptance), and on the
// real Xtion frames of ../shared/data/ycbv_real_sample.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <numbers>

#include "test_support.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"
#include "viewpose/recognize/candidate_order.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

const ViewDatabase& jug_and_can_db() {
  static const ViewDatabase db = [] {
    const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {2, "can", make_can()}};
    return build_view_database(models, DatabaseParams{});
  }();
  return db;
}

const ViewDatabase& jug_db() {
  static const ViewDatabase db = [] {
    const ObjectModel jug{1, "jug", make_jug()};
    return build_view_database(std::span(&jug, 1), DatabaseParams{});
  }();
  return db;
}

// Image `image` of the seed experiment's jug at 1 m in `orientations` orientations (seed 21).
Frame jug_at_one_metre(int orientations, std::size_t image, const SensorModel& sensor, std::uint64_t noise_seed) {
  SeedExperimentOptions setup;
  setup.distances_m = {1.0};
  setup.orientations = orientations;
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", make_jug()}, K, setup, 21);
  return frame_from_depth(simulate_image(ds, ds.scenes[0].images[image], sensor, noise_seed).depth, K);
}

TEST(Recognize, NoiseFreeJugAtOneMetreWithinFiveMillimetresAndTwoDegrees) {
  const Recognizer recognizer(jug_db());
  SeedExperimentOptions setup;
  setup.distances_m = {1.0};
  setup.orientations = 3;
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", make_jug()}, K, setup, 21);
  for (const SimImage& image : ds.scenes[0].images) {
    const SimulatedFrame f = simulate_image(ds, image, SensorModel::ideal(), 1);
    const Recognition r = recognizer.recognize(frame_from_depth(f.depth, K));
    ASSERT_EQ(r.detections.size(), 1u);
    const Detection& d = r.detections[0];
    EXPECT_EQ(d.object_id, 1);
    EXPECT_LT((d.T_camera_object.translation() - f.gt[0].T_camera_object.translation()).norm(), 0.005);
    EXPECT_LT(rotation_difference_deg(d.T_camera_object.linear(), f.gt[0].T_camera_object.linear()), 2.0);
    EXPECT_GT(d.score, 0.9);
  }
}

TEST(Recognize, APoseThatScoresBelowTheBoundIsNoDetectionButIsToldAsTheNearest) {
  const Frame frame = jug_at_one_metre(3, 0, SensorModel::ideal(), 1);
  const Recognition found = Recognizer(jug_db()).recognize(frame);
  ASSERT_EQ(found.detections.size(), 1u);
  const Detection& d = found.detections[0];
  // No pose is certain: with a bound of 1 nothing is a detection, and the most confident pose the
  // search verified is told instead, in the same place (the found one may have been turned after it
  // passed: the pose before is a good one too).
  RecognizerOptions options;
  options.accept.min_confidence = 1.0;
  const Recognition below = Recognizer(jug_db(), options).recognize(frame);
  EXPECT_TRUE(below.detections.empty());
  ASSERT_TRUE(below.best_below_min_score.has_value());
  const Detection& b = *below.best_below_min_score;
  EXPECT_EQ(b.object_id, 1);
  EXPECT_GT(b.score, 0.5);
  EXPECT_LT(b.score, 1.0);
  EXPECT_TRUE(b.verification.accepted);
  EXPECT_LT((b.T_camera_object.translation() - d.T_camera_object.translation()).norm(), 0.005);
  EXPECT_LT(rotation_difference_deg(b.T_camera_object.linear(), d.T_camera_object.linear()), 2.0);
  // Only what verification passed is told: with one of its bounds out of reach, nothing.
  options.verify.min_inlier_fraction = 1.1;
  EXPECT_FALSE(Recognizer(jug_db(), options).recognize(frame).best_below_min_score.has_value());
}

TEST(Recognize, ARecognizerKeepsTheDatabaseItIsGivenOrShares) {
  // `Recognizer r(ViewDatabase::load(path))` once kept a reference to the temporary: the database it
  // is handed (moved in, or shared) must live as long as the recognizer, and give the same answer.
  const Frame frame = jug_at_one_metre(1, 0, SensorModel::ideal(), 1);
  const Recognition borrowed = Recognizer(jug_db()).recognize(frame);
  ASSERT_EQ(borrowed.detections.size(), 1u);

  const test::TempDir dir;
  jug_db().save(dir / "jug.vpdb");
  const Recognizer owning(ViewDatabase::load(dir / "jug.vpdb"));
  EXPECT_NE(&owning.database(), &jug_db());
  auto shared = std::make_shared<const ViewDatabase>(ViewDatabase::load(dir / "jug.vpdb"));
  const Recognizer sharing(shared);
  shared.reset();  // the recognizer's copy of the pointer keeps it
  for (const Recognizer* r : {&owning, &sharing}) {
    const Recognition again = r->recognize(frame);
    ASSERT_EQ(again.detections.size(), 1u);
    EXPECT_TRUE(again.detections[0].T_camera_object.isApprox(borrowed.detections[0].T_camera_object, 1e-9));
    EXPECT_EQ(again.detections[0].score, borrowed.detections[0].score);
  }
  EXPECT_THROW(Recognizer(std::shared_ptr<const ViewDatabase>()), Error);
}

TEST(Recognize, OptionsAreGivenByStageAndTheDatabaseFixesTheVoxelSize) {
  const Recognizer r(jug_db(), {.accept = {.min_confidence = 0.5}, .run = {.deadline_ms = 30}});
  EXPECT_EQ(r.options().accept.min_confidence, 0.5);
  EXPECT_EQ(r.options().run.deadline_ms, 30);
  EXPECT_EQ(r.options().match.per_object, MatchOptions{}.per_object);  // the rest as by default
  EXPECT_EQ(r.options().segment.voxel_m, jug_db().params.voxel_m);
  // A scene described at another voxel size than the views would match none of them.
  RecognizerOptions coarser;
  coarser.segment.voxel_m = 2 * jug_db().params.voxel_m;
  EXPECT_THROW(Recognizer(jug_db(), coarser), Error);
  // A share of a model inside a plane outside 0-1 (a negative one would drop every detection on a
  // table; NaN would turn the test off unsaid).
  for (const double share : {-0.1, 1.5, std::nan("")}) {
    RecognizerOptions bad;
    bad.accept.max_share_inside_planes = share;
    EXPECT_THROW(Recognizer(jug_db(), bad), Error) << share;
  }
  // A reach to grow a part's pose by that is negative, NaN or past a metre (a unit mistake).
  for (const float reach : {-0.01f, 20.0f, std::nanf("")}) {
    RecognizerOptions bad;
    bad.split.grow_reach_m = reach;
    EXPECT_THROW(Recognizer(jug_db(), bad), Error) << reach;
  }
  // Screened poses merged within a negative or NaN rotation or share (NaN would merge none unsaid).
  for (const double bound : {-1.0, std::nan("")}) {
    RecognizerOptions bad_rotation, bad_share;
    bad_rotation.match.merge_rotation_deg = bound;
    bad_share.match.merge_share = bound;
    EXPECT_THROW(Recognizer(jug_db(), bad_rotation), Error) << bound;
    EXPECT_THROW(Recognizer(jug_db(), bad_share), Error) << bound;
  }
}

TEST(Recognize, ADeadlineCutsTheFrameShortAndSaysSo) {
  const Frame frame = jug_at_one_metre(2, 1, SensorModel::kinect_v1(), 3);
  const Recognition full = Recognizer(jug_db()).recognize(frame);
  ASSERT_EQ(full.detections.size(), 1u);
  EXPECT_FALSE(full.cut_short);
  RecognizerOptions generous;
  generous.run.deadline_ms = 60'000;  // never reached: the same answer
  const Recognition in_time = Recognizer(jug_db(), generous).recognize(frame);
  EXPECT_FALSE(in_time.cut_short);
  ASSERT_EQ(in_time.detections.size(), 1u);
  EXPECT_TRUE(in_time.detections[0].T_camera_object.isApprox(full.detections[0].T_camera_object));
  EXPECT_EQ(in_time.hypotheses, full.hypotheses);
  // Gone before the first cluster is looked at: nothing tried, nothing claimed, and flagged.
  RecognizerOptions tight;
  tight.run.deadline_ms = 1e-6;
  const Recognition late = Recognizer(jug_db(), tight).recognize(frame);
  EXPECT_TRUE(late.cut_short);
  EXPECT_TRUE(late.detections.empty());
  EXPECT_EQ(late.hypotheses, 0u);
  EXPECT_EQ(late.clusters, full.clusters) << "segmentation itself always runs";
}

TEST(Recognize, TheSameFrameGivesTheSameResultOnOneThreadAndOnTwo) {
  // Frames whose right view is far down the matches (a view's rolls refined side by side) and one
  // with two objects: detections, scores and hypothesis counts must not depend on the threads.
  const Recognizer recognizer(jug_and_can_db());
  SeedExperimentOptions setup;
  setup.distances_m = {1.0};
  setup.orientations = 4;
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", make_jug()}, K, setup, 7);
  const int threads = thread_count();
  for (std::size_t k = 0; k < ds.scenes[0].images.size(); ++k) {
    SCOPED_TRACE(k);
    const Frame frame = frame_from_depth(simulate_image(ds, ds.scenes[0].images[k], SensorModel::kinect_v1(), 1).depth, K);
    set_thread_count(1);
    const Recognition one = recognizer.recognize(frame);
    set_thread_count(2);
    const Recognition two = recognizer.recognize(frame);
    set_thread_count(threads);
    ASSERT_EQ(one.detections.size(), two.detections.size());
    EXPECT_EQ(one.hypotheses, two.hypotheses);
    EXPECT_EQ(one.regions, two.regions);
    for (std::size_t i = 0; i < one.detections.size(); ++i) {
      EXPECT_EQ(one.detections[i].object_id, two.detections[i].object_id);
      EXPECT_TRUE(one.detections[i].T_camera_object.matrix() == two.detections[i].T_camera_object.matrix());
      EXPECT_EQ(one.detections[i].score, two.detections[i].score);
      EXPECT_EQ(one.detections[i].runner_up_score, two.detections[i].runner_up_score);
    }
  }
}

// The same search gives the same record: counts, detections, poses and scores, bit for bit.
void expect_same_recognition(const Recognition& a, const Recognition& b) {
  EXPECT_EQ(a.clusters, b.clusters);
  EXPECT_EQ(a.regions, b.regions);
  EXPECT_EQ(a.hypotheses, b.hypotheses);
  EXPECT_EQ(a.screened, b.screened);
  EXPECT_EQ(a.screened_out, b.screened_out);
  EXPECT_EQ(a.screened_merged, b.screened_merged);
  EXPECT_EQ(a.icp_steps, b.icp_steps);
  EXPECT_EQ(a.split_clusters, b.split_clusters);
  EXPECT_EQ(a.dropped_as_explained, b.dropped_as_explained);
  EXPECT_EQ(a.dropped_inside_planes, b.dropped_inside_planes);
  EXPECT_EQ(a.lifted_out_of_planes, b.lifted_out_of_planes);
  EXPECT_EQ(a.joined_regions, b.joined_regions);
  EXPECT_EQ(a.grown_regions, b.grown_regions);
  EXPECT_EQ(a.voted_regions, b.voted_regions);
  ASSERT_EQ(a.detections.size(), b.detections.size());
  for (std::size_t i = 0; i < a.detections.size(); ++i) {
    EXPECT_EQ(a.detections[i].object_id, b.detections[i].object_id);
    EXPECT_TRUE(a.detections[i].T_camera_object.matrix() == b.detections[i].T_camera_object.matrix());
    EXPECT_EQ(a.detections[i].score, b.detections[i].score);
  }
  ASSERT_EQ(a.best_below_min_score.has_value(), b.best_below_min_score.has_value());
  if (a.best_below_min_score) {
    EXPECT_EQ(a.best_below_min_score->object_id, b.best_below_min_score->object_id);
    EXPECT_TRUE(a.best_below_min_score->T_camera_object.matrix() == b.best_below_min_score->T_camera_object.matrix());
    EXPECT_EQ(a.best_below_min_score->score, b.best_below_min_score->score);
  }
}

// Room frames with the jug and a box among unknown things, walls behind: many clusters, some
// split, some with a detection and its remainder.
const std::vector<ObjectModel>& room_objects() {
  static const std::vector<ObjectModel> objects = {{1, "jug", make_jug()}, {2, "box", make_named_shape("box")}};
  return objects;
}
const ViewDatabase& room_db() {
  static const ViewDatabase db = build_view_database(room_objects(), DatabaseParams{});
  return db;
}
std::vector<Frame> room_frames() {
  RoomPresetOptions setup;
  setup.images = 2;
  const SimDataset ds = make_room_scenes(room_objects(), K, setup, 12);
  std::vector<Frame> frames;
  for (const SimScene& scene : ds.scenes)
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      frames.push_back(frame_from_depth(simulate_image(ds, scene.images[k], SensorModel::kinect_v1(), 200 + k).depth, K));
    }
  return frames;
}

TEST(Recognize, ClustersSearchedSideBySideGiveWhatOneAfterAnotherGives) {
  // The clusters searched side by side, one per thread, must give the detections, scores and
  // counts of searching them one after another on one thread.
  RecognizerOptions in_turn;
  in_turn.run.parallel_clusters = false;
  const Recognizer side_by_side(room_db()), one_after_another(room_db(), in_turn);
  const int threads = thread_count();
  std::size_t clusters = 0, detections = 0, frames = 0, told_below = 0;
  for (const Frame& frame : room_frames()) {
    SCOPED_TRACE(frames++);
    set_thread_count(1);
    const Recognition a = one_after_another.recognize(frame);
    set_thread_count(2);
    const Recognition b = side_by_side.recognize(frame);
    set_thread_count(threads);
    clusters += b.clusters;
    detections += b.detections.size();
    told_below += b.best_below_min_score.has_value() ? 1 : 0;
    expect_same_recognition(a, b);
  }
  EXPECT_GT(clusters, 2 * frames) << "frames of several clusters";
  EXPECT_GT(detections, 0u);
  EXPECT_GT(told_below, 0u) << "frames with a pose below the bound, merged from the clusters searched apart";
}

TEST(Recognize, OneRecognizerCalledFromTheCallersThreadsAtOnceGivesWhatEachFrameGivesAlone) {
  // A robot's program recognizes frames of several cameras at once with one recognizer: from its
  // own OpenMP loop (our parallel regions then open inside its threads, on one thread each unless
  // it enables nesting) or from threads of its own.
  // Each call must give what the frame gives alone, whatever runs beside it; the recognizers are
  // new, so their objects are first prepared by calls racing each other.
  const std::vector<Frame> frames = room_frames();
  ASSERT_GE(frames.size(), 2u);
  std::vector<Recognition> alone;
  {
    const Recognizer recognizer(room_db());
    for (const Frame& frame : frames) alone.push_back(recognizer.recognize(frame));
  }
  std::size_t detections = 0;
  for (const Recognition& r : alone) detections += r.detections.size();
  EXPECT_GT(detections, 0u);
  const auto n = static_cast<std::ptrdiff_t>(frames.size());
  {
    const Recognizer recognizer(room_db());
    std::vector<Recognition> in_loop(frames.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(2)
    for (std::ptrdiff_t k = 0; k < n; ++k) in_loop[static_cast<std::size_t>(k)] = recognizer.recognize(frames[static_cast<std::size_t>(k)]);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      SCOPED_TRACE("caller's OpenMP loop, frame " + std::to_string(k));
      expect_same_recognition(alone[k], in_loop[k]);
    }
  }
  {
    const Recognizer recognizer(room_db());
    std::vector<Recognition> on_threads(frames.size());
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      threads.emplace_back([&, k] { on_threads[k] = recognizer.recognize(frames[k]); });
    }
    for (std::thread& t : threads) t.join();
    for (std::size_t k = 0; k < frames.size(); ++k) {
      SCOPED_TRACE("caller's std::thread, frame " + std::to_string(k));
      expect_same_recognition(alone[k], on_threads[k]);
    }
  }
}

TEST(Recognize, WhatTheDatabaseStoresPreparedGivesWhatTheRecognizerWouldPrepare) {
  // The database's drawing meshes and filled ICP grids, against a copy without them whose
  // recognizer makes its own (grids filled as ICP asks): the same search, the same results.
  ViewDatabase bare = room_db();
  for (DatabaseObject& o : bare.objects) {
    ASSERT_FALSE(o.nearest_cells.empty());
    ASSERT_FALSE(o.drawn_mesh.triangles.empty());
    o.nearest_cells.clear();
    o.drawn_mesh = {};
  }
  // The defaults the database's data is made with are the recognizer's, so that it is used.
  EXPECT_EQ(DatabaseParams{}.drawn_mesh_error_m, RecognizerOptions{}.verify_mesh_error_m);
  EXPECT_EQ(DatabaseParams{}.grid_cell_m, IcpOptions{}.grid_cell_m);
  EXPECT_EQ(DatabaseParams{}.grid_margin_m, IcpOptions{}.reach_m());
  RecognizerOptions lazy;
  lazy.run.prepare_objects_up_to = 0;
  // Other ICP cells and drawing error than the database's: its data is not used, and not refused.
  RecognizerOptions other;
  other.icp.grid_cell_m = 0.004f;
  other.verify_mesh_error_m = 0.003f;
  // ... and a stored grid that is wrong (every cell holding the model's first point) and a drawing
  // mesh of one triangle: were the stored data not what the recognizer uses, nothing would change.
  ViewDatabase wrong = room_db();
  for (DatabaseObject& o : wrong.objects) {
    std::fill(o.nearest_cells.begin(), o.nearest_cells.end(), 1u);
    o.drawn_mesh.triangles.resize(1);
  }
  const Recognizer stored(room_db()), made(bare, lazy), stored_other(room_db(), other), made_other(bare, other),
      misled(wrong);
  std::size_t detections = 0, frames = 0, misled_detections = 0;
  for (const Frame& frame : room_frames()) {
    SCOPED_TRACE(frames++);
    const Recognition a = made.recognize(frame);
    const Recognition b = stored.recognize(frame);
    detections += b.detections.size();
    expect_same_recognition(a, b);
    expect_same_recognition(made_other.recognize(frame), stored_other.recognize(frame));
    misled_detections += misled.recognize(frame).detections.size();
  }
  EXPECT_GT(detections, 0u);
  EXPECT_EQ(misled_detections, 0u) << "the stored grid and drawing mesh are the ones used";
}

TEST(Recognize, NoisySeedExperimentSubsetMeetsAddSWithoutFalsePositives) {
  const ViewDatabase& db = jug_db();
  const Recognizer recognizer(db);
  SeedExperimentOptions setup;
  setup.orientations = 3;  // x 5 distances, 0.75 to 2.00 m
  const TriangleMesh jug = make_jug();
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", jug}, K, setup, 33);
  const double threshold = 0.1 * db.objects[0].diameter_m;
  int frames = 0, correct = 0, false_positives = 0;
  for (const SimScene& scene : ds.scenes) {
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      const SimulatedFrame f = simulate_image(ds, scene.images[k], SensorModel::kinect_v1(), 7 * scene.scene_id + k);
      const Recognition r = recognizer.recognize(frame_from_depth(f.depth, K));
      ++frames;
      ASSERT_LE(r.detections.size(), 1u);
      if (r.detections.empty()) continue;
      const double e = add_s_error(r.detections[0].T_camera_object, f.gt[0].T_camera_object, jug.vertices);
      if (e < threshold) ++correct;
      else ++false_positives;
    }
  }
  EXPECT_GE(correct, frames * 9 / 10) << correct << " of " << frames;
  EXPECT_EQ(false_positives, 0);
}

TEST(Regression, SeedExperimentEightOrientationsKeepsItsScores) {
  // Issue 6's regression check: 8 orientations x 5 distances (0.75 to 2.00 m), noisy. Measured at
  // commit time: ADD-S 40 of 40, ADD 40 of 40 (37 before conflicts were held to 5 %), no false
  // positive (docs/RESULTS.md has the full run). The thresholds sit just below, so a change that
  // loses accuracy fails.
  const ViewDatabase& db = jug_db();
  const Recognizer recognizer(db);
  SeedExperimentOptions setup;
  setup.orientations = 8;
  const TriangleMesh jug = make_jug();
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", jug}, K, setup, 1);
  const double threshold = 0.1 * db.objects[0].diameter_m;
  int frames = 0, add_s = 0, add = 0, false_positives = 0;
  for (const SimScene& scene : ds.scenes) {
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      const SimulatedFrame f = simulate_image(ds, scene.images[k], SensorModel::kinect_v1(), 1000 * scene.scene_id + k);
      const Recognition r = recognizer.recognize(frame_from_depth(f.depth, K));
      ++frames;
      for (const Detection& d : r.detections) {
        const bool right = add_s_error(d.T_camera_object, f.gt[0].T_camera_object, jug.vertices) < threshold;
        add_s += right;
        false_positives += !right;
        add += add_error(d.T_camera_object, f.gt[0].T_camera_object, jug.vertices) < threshold;
      }
    }
  }
  ASSERT_EQ(frames, 40);
  EXPECT_GE(add_s, 39);
  EXPECT_GE(add, 39);
  EXPECT_EQ(false_positives, 0);
}

// A can and a mug on the table at 1 m, neither of them in jug_db().
SimulatedFrame can_and_mug_frame() {
  SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", make_jug()}, K, {{1.0}, 1, 0.45, 18.0}, 1);
  ds.objects = {{7, "can", make_can()}, {8, "mug", make_mug()}};
  const Transform& T = ds.scenes[0].images[0].objects[0].T_camera_object;
  const Transform left = T * make_transform(Eigen::Matrix3d::Identity(), {-0.12, 0, -0.09});
  const Transform right = T * make_transform(Eigen::Matrix3d::Identity(), {0.12, 0, -0.1});
  return simulate_image(ds, SimImage{{{0, left}, {1, right}}}, SensorModel::kinect_v1(), 5);
}

TEST(Recognize, FrameWithNoKnownObjectGivesNoDetection) {
  // A can and a mug on the table, but a database of the jug only.
  const SimulatedFrame f = can_and_mug_frame();
  ASSERT_GT(f.gt_info[0].px_count_visib, 500);
  ASSERT_GT(f.gt_info[1].px_count_visib, 500);
  const Recognition r = Recognizer(jug_db()).recognize(frame_from_depth(f.depth, K));
  EXPECT_GE(r.clusters, 2u);
  EXPECT_TRUE(r.detections.empty()) << r.detections.size() << " detections, first " << r.detections[0].object_name;
}

TEST(Recognize, ARegionOfNothingKnownCostsAtMostItsBudget) {
  // Where nothing passes, every starting pose given is refined and verified: the budget bounds the
  // work per region (each batch may add the three half turns of a pose that nearly passed), where
  // the thesis's exhaustive search tries every roll of every matched view.
  const Frame frame = frame_from_depth(can_and_mug_frame().depth, K);
  RecognizerOptions exhaustive;
  exhaustive.match.max_hypotheses = 0;
  const Recognition all = Recognizer(jug_db(), exhaustive).recognize(frame);
  EXPECT_TRUE(all.detections.empty());
  for (const std::size_t budget : {std::size_t{4}, std::size_t{12}}) {
    SCOPED_TRACE(budget);
    RecognizerOptions o;
    o.match.max_hypotheses = budget;
    const Recognition r = Recognizer(jug_db(), o).recognize(frame);
    EXPECT_TRUE(r.detections.empty());
    ASSERT_GT(r.regions, 0u);
    const std::size_t batches = (budget + o.run.batch - 1) / o.run.batch;
    // One budget for each cluster whole, and one for the convex parts of each it splits.
    EXPECT_LE(r.hypotheses, (r.clusters + r.split_clusters) * (budget + 3 * batches));
    EXPECT_LE(r.clusters + r.split_clusters, r.regions);
    EXPECT_GE(r.hypotheses, r.regions) << "every region tries something";
    EXPECT_LT(r.hypotheses, all.hypotheses / 2) << "exhaustive: " << all.hypotheses << " over " << all.regions << " regions";
  }
}

TEST(Recognize, TheBudgetFindsWhatTheExhaustiveSearchFinds) {
  // The jug alone, and the jug beside the can, over several orientations: the first few starting
  // poses by coarse fit hold one that passes, so a budget of 12 gives the exhaustive search's
  // objects, each within ADD-S 10 % of the truth, with a fraction of its work.
  const ViewDatabase& db = jug_and_can_db();
  RecognizerOptions exhaustive, budget;
  exhaustive.match.max_hypotheses = 0;
  budget.match.max_hypotheses = 12;
  const Recognizer all(db, exhaustive), some(db, budget);
  const TriangleMesh jug = make_jug();
  SeedExperimentOptions setup;
  setup.distances_m = {1.0, 1.5};
  setup.orientations = 3;
  const SimDataset ds = make_seed_experiment(ObjectModel{1, "jug", jug}, K, setup, 12);
  std::size_t work_all = 0, work_some = 0;
  for (const SimScene& scene : ds.scenes)
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      const SimulatedFrame f = simulate_image(ds, scene.images[k], SensorModel::kinect_v1(), 40 + k);
      const Frame frame = frame_from_depth(f.depth, K);
      const Recognition a = all.recognize(frame), b = some.recognize(frame);
      ASSERT_EQ(a.detections.size(), 1u);
      ASSERT_EQ(b.detections.size(), 1u) << scene.description << ", image " << k;
      EXPECT_EQ(b.detections[0].object_id, 1);
      EXPECT_LT(add_s_error(b.detections[0].T_camera_object, f.gt[0].T_camera_object, jug.vertices), 0.1 * mesh_diameter(jug));
      work_all += a.hypotheses;
      work_some += b.hypotheses;
    }
  EXPECT_LE(work_some, work_all);
}

TEST(Recognize, TheShortIcpScreenFindsWhatCoarseFitOrderMissesWithinTheBudget) {
  // Simulated rooms (the jug and a box among unknown things, touching and hidden, walls behind):
  // the right starting pose of a jug whose CRH roll is off fits poorly at the start and ranks late
  // by coarse fit. Within the same budget of full refinements, the order the short ICP's screen
  // gives (where each pose leads) finds objects that coarse fit order does not reach; the screen is
  // counted.
#ifdef VIEWPOSE_SANITIZER_BUILD
  // Forty rooms frames take five minutes and more there; the screen's code runs in the other tests.
  GTEST_SKIP() << "skipped under the sanitizers: a measurement of search order, not of memory or threads";
#endif
  const std::vector<ObjectModel> objects = {{1, "jug", make_jug()}, {2, "box", make_named_shape("box")}};
  static const ViewDatabase db = build_view_database(objects, DatabaseParams{});
  RecognizerOptions screened, unscreened, never_quick;
  unscreened.match.prescreen = 0;
  // Verification's quick test off, on the screen's poses as in verification, and no pose merged
  // with another the screen led to the same place: every pose whose turn comes is refined in full.
  never_quick.verify.quick_max_seen_through = 1;
  never_quick.match.merge_rotation_deg = 0;
  const Recognizer with(db, screened), without(db, unscreened), all_refined(db, never_quick);
  RoomPresetOptions setup;
  setup.images = 20;
  const SimDataset ds = make_room_scenes(objects, K, setup, 11);
  int found_with = 0, found_without = 0, lost = 0, found_all_refined = 0;
  std::size_t poses_screened = 0, screened_out = 0, refined = 0, refined_all = 0;
  const auto found = [&](const Recognition& r, const GroundTruthPose& gt) {
    const TriangleMesh& mesh = objects[static_cast<std::size_t>(gt.obj_id - 1)].mesh;
    return std::any_of(r.detections.begin(), r.detections.end(), [&](const Detection& d) {
      return d.object_id == gt.obj_id && add_s_error(d.T_camera_object, gt.T_camera_object, mesh.vertices) < 0.1 * mesh_diameter(mesh);
    });
  };
  for (const SimScene& scene : ds.scenes)
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      const SimulatedFrame f = simulate_image(ds, scene.images[k], SensorModel::kinect_v1(), 100 + k);
      const Frame frame = frame_from_depth(f.depth, K);
      const Recognition a = with.recognize(frame), b = without.recognize(frame), c = all_refined.recognize(frame);
      for (const GroundTruthPose& gt : f.gt) {
        found_with += found(a, gt) ? 1 : 0;
        found_without += found(b, gt) ? 1 : 0;
        found_all_refined += found(c, gt) ? 1 : 0;
        lost += found(b, gt) && !found(a, gt) ? 1 : 0;
      }
      poses_screened += a.screened;
      screened_out += a.screened_out;
      refined += a.hypotheses;
      refined_all += c.hypotheses;
      EXPECT_EQ(b.screened, 0u);
      EXPECT_EQ(b.screened_out, 0u);
      EXPECT_EQ(c.screened_out, 0u);
      EXPECT_EQ(c.screened_merged, 0u);
      EXPECT_LE(a.screened_out + a.screened_merged, a.screened);
    }
  EXPECT_GT(poses_screened, 0u);
  // The poses the quick test refuses where the screen led them would not have passed, nor those
  // led where one was refined already: the same objects are found with at least 15 % fewer full
  // refinements (measured: 23 % fewer with the quick test alone, 29 % with merging too).
  EXPECT_EQ(found_with, found_all_refined);
  EXPECT_GT(screened_out, 0u);
  EXPECT_LT(static_cast<double>(refined), 0.85 * static_cast<double>(refined_all));
  std::printf("%zu poses refined in full, %zu with the quick test off; %zu refused after the screen\n", refined, refined_all, screened_out);
  // Measured: 23 and 19 of the rooms' objects, none lost (GCC -O2); 23 and 20, one lost (clang
  // -O1, whose arithmetic differs in the last bits): what counts is the net gain.
  EXPECT_GE(found_with, found_without + 2);
  EXPECT_LE(lost, 1);
  std::printf("found %d screened, %d by coarse fit order, %d of those lost; %zu poses screened\n", found_with, found_without, lost, poses_screened);
}

TEST(Recognize, PosesRefinedOntoOnesAlreadyRefusedAreNotVerifiedAgain) {
  // Where nothing is known, every view of every match is refined, and many land on the same few
  // poses: those are refused once. Verifying them all again must find nothing more.
  // (Verification's quick test off: where the screen led them, it refuses most of these poses
  // before they are refined at all. Each cluster searched alone with its whole budget and then in
  // its parts with another, SplitOptions::whole_with_parts off: with one budget for both, as few as
  // 32 poses are refined, and built with clang none of them repeated another. Screened poses led
  // to one place are not merged, MatchOptions::merge_rotation_deg 0: merged, most of these poses
  // are never refined.)
  const Frame frame = frame_from_depth(can_and_mug_frame().depth, K);
  RecognizerOptions skip, every;
  skip.verify.quick_max_seen_through = every.verify.quick_max_seen_through = 1;
  skip.match.merge_rotation_deg = every.match.merge_rotation_deg = 0;
  skip.split.whole_with_parts = every.split.whole_with_parts = false;
  every.match.refused_rotation_deg = 0;
  const Recognition skipping = Recognizer(jug_db(), skip).recognize(frame), verifying = Recognizer(jug_db(), every).recognize(frame);
  EXPECT_TRUE(skipping.detections.empty());
  EXPECT_TRUE(verifying.detections.empty());
  EXPECT_EQ(verifying.repeats, 0u);
  EXPECT_GT(skipping.repeats, 0u) << "of " << skipping.hypotheses;
  EXPECT_EQ(skipping.hypotheses, verifying.hypotheses) << "the same poses are refined";
}

// The jug 1 m away on the table (the seed experiment's first frame), and a dataset whose objects
// are the jug (index 0) and a can (index 1). `can_at(x)`: the can standing on the same table, x
// metres along the jug's own x axis from the jug's centre (the jug stands upright, z up).
struct JugAndCan {
  SimDataset ds;
  Transform jug_pose;
  double can_lift = 0;  // the can's origin above the jug's, so that both stand on the table
  Transform can_at(double x) const { return jug_pose * make_transform(Eigen::Matrix3d::Identity(), {x, 0.0, can_lift}); }
};

JugAndCan jug_and_can_scene() {
  JugAndCan s;
  s.ds = make_seed_experiment(ObjectModel{1, "jug", make_jug()}, K, {{1.0}, 1, 0.45, 18.0}, 1);
  s.ds.objects = {{1, "jug", make_jug()}, {2, "can", make_can()}};
  s.jug_pose = s.ds.scenes[0].images[0].objects[0].T_camera_object;
  s.can_lift = static_cast<double>(bounding_box(make_jug()).min.z() - bounding_box(make_can()).min.z());
  return s;
}

// Both the jug (ground truth 0) and the can (1) detected, each within ADD-S 10 % of its diameter.
void expect_jug_and_can_found(const Recognition& r, const SimulatedFrame& f) {
  ASSERT_EQ(r.detections.size(), 2u);
  for (const Detection& d : r.detections) {
    const int truth = d.object_id == 1 ? 0 : 1;
    const TriangleMesh mesh = d.object_id == 1 ? make_jug() : make_can();
    EXPECT_LT(add_s_error(d.T_camera_object, f.gt[static_cast<std::size_t>(truth)].T_camera_object, mesh.vertices),
              0.1 * mesh_diameter(mesh)) << d.object_name;
  }
  EXPECT_NE(r.detections[0].object_id, r.detections[1].object_id);
}

TEST(Recognize, TwoObjectFrameGivesBothWithTheRightIds) {
  const ViewDatabase& db = jug_and_can_db();
  const JugAndCan scene = jug_and_can_scene();  // the can 25 cm to the jug's side
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {1, scene.can_at(0.25)}}}, SensorModel::kinect_v1(), 9);
  const Recognition r = Recognizer(db).recognize(frame_from_depth(f.depth, K));
  ASSERT_EQ(r.detections.size(), 2u);
  expect_jug_and_can_found(r, f);
}

TEST(Recognize, VotePosesAreTriedObjectByObject) {
  // Each object's k-th pose before any object's (k+1)-th, and otherwise the order given: a large
  // object's many well-fitting poses do not push a small object's best past the budget.
  struct Pose {
    std::uint32_t object;
    char name;
  };
  std::vector<Pose> poses = {{3, 'a'}, {3, 'b'}, {11, 'c'}, {9, 'd'}, {3, 'e'}, {11, 'f'}, {11, 'g'}};
  interleave_by_object(poses.begin(), poses.end());
  std::string order;
  for (const Pose& p : poses) order += p.name;
  EXPECT_EQ(order, "acdbfeg");
  std::vector<Pose> none;
  interleave_by_object(none.begin(), none.end());
  // Part of a list: the rest stays where it was.
  std::vector<Pose> part = {{1, 'x'}, {2, 'y'}, {2, 'z'}, {2, 'w'}, {1, 'v'}};
  interleave_by_object(part.begin() + 1, part.end());
  order.clear();
  for (const Pose& p : part) order += p.name;
  EXPECT_EQ(order, "xyvzw");
}

TEST(Recognize, PointPairVotesAloneOrBesideTheViewsFindBothObjects) {
  // The frame above with starting poses from point pair votes alone (no view's VFH or roll), and
  // from both sources ranked together: the same two objects, each at its pose.
  const ViewDatabase& db = jug_and_can_db();
  const JugAndCan scene = jug_and_can_scene();
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {1, scene.can_at(0.25)}}}, SensorModel::kinect_v1(), 9);
  const Frame frame = frame_from_depth(f.depth, K);
  RecognizerOptions votes, both;
  votes.match.source = PoseSource::ppf;
  both.match.source = PoseSource::both;
  const Recognition r = Recognizer(db, votes).recognize(frame);
  expect_jug_and_can_found(r, f);
  for (const Detection& d : r.detections) EXPECT_EQ(d.match_rank, -1) << d.object_name << ": a pose from votes has no view";
  expect_jug_and_can_found(Recognizer(db, both).recognize(frame), f);
  // Bad pair options are refused when the recognizer is made, in one line, not in a region later.
  RecognizerOptions bad = votes;
  bad.match.ppf.angle_bins = 11;  // (does not divide 13440)
  bad.run.prepare_objects_up_to = 0;  // (the tables would be made on first use)
  EXPECT_THROW(Recognizer(db, bad), Error);
  // The sources' names, as the command line and the Python module take them.
  for (const PoseSource source : {PoseSource::vfh, PoseSource::ppf, PoseSource::both, PoseSource::touching}) {
    EXPECT_EQ(pose_source_from_name(pose_source_name(source)), source);
  }
  test::expect_error([] { pose_source_from_name("PPF"); }, "source: \"PPF\" is none of vfh, ppf, both, touching");
}

TEST(Recognize, PairTablesLeftOnDiskAreReadForTheFirstVoteOrMadeWhereTheFileIsGone) {
  // A database loaded without its pair tables (as `recognize` of one file loads it): the votes
  // read them from the file; with the file gone since, they are made from the models. Either way
  // the same tables, so the same poses as with the tables loaded whole.
  const ViewDatabase& db = jug_and_can_db();
  const JugAndCan scene = jug_and_can_scene();
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {1, scene.can_at(0.25)}}}, SensorModel::kinect_v1(), 9);
  const Frame frame = frame_from_depth(f.depth, K);
  RecognizerOptions votes;
  votes.match.source = PoseSource::ppf;
  const Recognition whole = Recognizer(db, votes).recognize(frame);
  expect_jug_and_can_found(whole, f);
  const test::TempDir dir;
  db.save(dir / "db.vpdb");
  // Left on disk only for one frame with votes only after a detection; read whole otherwise.
  const RecognizerOptions touching;
  EXPECT_FALSE(database_load_options(touching, FramesToServe::one).pair_tables);
  EXPECT_TRUE(database_load_options(touching, FramesToServe::many).pair_tables);
  EXPECT_TRUE(database_load_options(votes, FramesToServe::one).pair_tables);
  const ViewDatabase lazy = ViewDatabase::load(dir / "db.vpdb", {.pair_tables = false});
  ASSERT_TRUE(lazy.pair_tables_on_disk);
  ASSERT_FALSE(lazy.objects[0].pair_table);
  const auto same_poses = [&](const Recognition& r, const char* how) {
    ASSERT_EQ(r.detections.size(), whole.detections.size()) << how;
    for (std::size_t i = 0; i < r.detections.size(); ++i) {
      EXPECT_EQ(r.detections[i].object_id, whole.detections[i].object_id) << how;
      EXPECT_TRUE(r.detections[i].T_camera_object.isApprox(whole.detections[i].T_camera_object, 1e-12)) << how;
    }
  };
  same_poses(Recognizer(lazy, votes).recognize(frame), "read from the file");
  std::filesystem::remove(dir / "db.vpdb");
  same_poses(Recognizer(lazy, votes).recognize(frame), "made from the models");
}

TEST(Recognize, ObjectsTooSmallForAClusterAreSkippedWithTheSameResult) {
  // A large box (no object of the database) beside the jug, and a database of the jug and a can:
  // the can is too small to explain the box's cluster, so its views are not tried there. Skipping
  // them must change nothing but the work.
  const ViewDatabase& db = jug_and_can_db();
  JugAndCan scene = jug_and_can_scene();
  scene.ds.objects.push_back({3, "box", make_box_mesh({0.30f, 0.25f, 0.20f})});
  const double lift = static_cast<double>(bounding_box(make_jug()).min.z()) + 0.10;
  const Transform box_pose = scene.jug_pose * make_transform(Eigen::Matrix3d::Identity(), {0.35, 0.0, lift});
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {2, box_pose}}}, SensorModel::kinect_v1(), 3);
  const Frame frame = frame_from_depth(f.depth, K);
  // Every starting pose tried (no budget), so that the work skipped shows in the poses tried.
  RecognizerOptions skip, all;
  skip.match.max_hypotheses = all.match.max_hypotheses = 0;
  all.match.skip_objects_too_small = false;
  const Recognition skipping = Recognizer(db, skip).recognize(frame), trying = Recognizer(db, all).recognize(frame);
  EXPECT_LT(skipping.hypotheses, trying.hypotheses);
  ASSERT_EQ(skipping.detections.size(), trying.detections.size());
  ASSERT_EQ(skipping.detections.size(), 1u);
  EXPECT_EQ(skipping.detections[0].object_id, 1);
  EXPECT_TRUE(skipping.detections[0].T_camera_object.matrix() == trying.detections[0].T_camera_object.matrix());
  EXPECT_EQ(skipping.detections[0].score, trying.detections[0].score);
}

TEST(Recognize, ViewsShowingFarMoreThanARegionAreSkippedWithTheSameResult) {
  // The jug and two small unknown boxes (4 and 5 cm) on the table, and a database of the jug: each
  // box's region is a small fraction of any jug view's surface, too little to pass verification,
  // so those views are not tried there. Skipping them must change nothing but the work.
  const ViewDatabase& db = jug_db();
  JugAndCan scene = jug_and_can_scene();
  scene.ds.objects.push_back({3, "small box", make_box_mesh({0.04f, 0.04f, 0.03f})});
  scene.ds.objects.push_back({4, "other box", make_box_mesh({0.05f, 0.03f, 0.04f})});
  const double lift = static_cast<double>(bounding_box(make_jug()).min.z());
  const Transform a = scene.jug_pose * make_transform(Eigen::Matrix3d::Identity(), {0.25, 0.0, lift + 0.015});
  const Transform b = scene.jug_pose * make_transform(Eigen::Matrix3d::Identity(), {-0.25, 0.05, lift + 0.02});
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {2, a}, {3, b}}}, SensorModel::kinect_v1(), 4);
  ASSERT_GT(f.gt_info[1].px_count_visib, 300);
  ASSERT_GT(f.gt_info[2].px_count_visib, 300);
  const Frame frame = frame_from_depth(f.depth, K);
  RecognizerOptions all;
  all.match.min_region_to_view = 0;
  const Recognition skipping = Recognizer(db).recognize(frame), trying = Recognizer(db, all).recognize(frame);
  EXPECT_GE(trying.regions, 3u);
  EXPECT_LT(skipping.hypotheses, trying.hypotheses);
  ASSERT_EQ(skipping.detections.size(), 1u);
  ASSERT_EQ(trying.detections.size(), 1u);
  EXPECT_TRUE(skipping.detections[0].T_camera_object.matrix() == trying.detections[0].T_camera_object.matrix());
  EXPECT_EQ(skipping.detections[0].score, trying.detections[0].score);
}

TEST(Recognize, TouchingObjectsAreBothFound) {
  // The same two objects, the can now standing against the jug's side (3 mm into it, so that the
  // sensor's points join them): one Euclidean cluster. The jug explains enough of it to pass, and
  // the can is lost, unless the jug's points are explained away and the rest recognized again.
  const ViewDatabase& db = jug_and_can_db();
  const JugAndCan scene = jug_and_can_scene();
  const double beside = static_cast<double>(bounding_box(make_jug()).max.x()) + 0.033 - 0.003;
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {1, scene.can_at(beside)}}}, SensorModel::kinect_v1(), 9);
  const Frame frame = frame_from_depth(f.depth, K);
  // The can, small and half against the jug, is right with a confidence of 0.90, just below the
  // default threshold fit for 98 % precision (0.917; docs/CONFIDENCE.md): what is tested here is
  // the splitting, at a threshold that takes it.
  RecognizerOptions no_split, split;
  no_split.split.enabled = false;
  no_split.accept.min_confidence = split.accept.min_confidence = 0.85;
  EXPECT_LE(Recognizer(db, no_split).recognize(frame).detections.size(), 1u);
  const Recognition r = Recognizer(db, split).recognize(frame);
  ASSERT_EQ(r.detections.size(), 2u);
  EXPECT_TRUE(r.detections[0].from_split_cluster || r.detections[1].from_split_cluster);
  expect_jug_and_can_found(r, f);
}

// Five cans in a row (no object of jug_db), each 3 mm into the next so that the sensor's points join
// them: one cluster, in which nothing passes, with a convex part for each can.
SimulatedFrame five_cans_in_a_row() {
  const JugAndCan scene = jug_and_can_scene();
  // Every other can set back by 4 cm: side by side in one line their fronts would make one convex
  // surface, whose creases the camera sees edge-on.
  const double back = 0.04, step = std::sqrt(4 * 0.033 * 0.033 - back * back) - 0.003;
  SimImage image;
  for (int k = -2; k <= 2; ++k) {
    const Eigen::Vector3d at{k * step, k % 2 == 0 ? 0.0 : back, scene.can_lift};
    image.objects.push_back({1, scene.jug_pose * make_transform(Eigen::Matrix3d::Identity(), at)});
  }
  return simulate_image(scene.ds, image, SensorModel::kinect_v1(), 5);
}

TEST(Recognize, PartsTheSearchNeverReachesAreNotDescribed) {
  // The five cans' cluster: after its own first batch it goes on with its parts in one budget, a
  // batch each, the whole cluster's first and then the parts' largest first: three regions spend
  // it, and the other parts are never reached. Those are neither described nor screened.
  const ViewDatabase& db = jug_db();
  const SimulatedFrame f = five_cans_in_a_row();
  const Recognition r = Recognizer(db).recognize(frame_from_depth(f.depth, K));
  EXPECT_TRUE(r.detections.empty());
  EXPECT_GE(r.split_clusters, 1u);
  EXPECT_GE(r.parts_unreached, 1u);
  RecognizerOptions every;
  every.match.max_hypotheses = 0;  // every starting pose of every part tried: each part described
  const Recognition all = Recognizer(db, every).recognize(frame_from_depth(f.depth, K));
  EXPECT_TRUE(all.detections.empty());
  EXPECT_EQ(all.parts_unreached, 0u);
  EXPECT_EQ(r.regions + r.parts_unreached, all.regions);
}

TEST(Recognize, AClusterWhoseFirstBatchFailsGoesOnWithItsPartsInOneBudget) {
  // The five cans' cluster, nothing known in it. Searched on alone after its first batch and then
  // in its parts, it spent two budgets; going on together with its parts, its first batch and one.
  const ViewDatabase& db = jug_db();
  const Frame frame = frame_from_depth(five_cans_in_a_row().depth, K);
  RecognizerOptions together, apart;
  apart.split.whole_with_parts = false;
  ASSERT_TRUE(together.split.whole_with_parts) << "the default";
  const Recognition t = Recognizer(db, together).recognize(frame), a = Recognizer(db, apart).recognize(frame);
  EXPECT_TRUE(t.detections.empty());
  EXPECT_TRUE(a.detections.empty());
  ASSERT_EQ(t.clusters, 1u);
  EXPECT_EQ(t.split_clusters, 1u);
  EXPECT_EQ(a.split_clusters, 1u);
  // The budget spent: poses refined, and poses the screen refused or merged where it led them (each
  // spends its share unrefined). Each batch may add the three half turns of a pose that nearly passed.
  const auto spent = [](const Recognition& r) { return r.hypotheses + r.screened_out + r.screened_merged; };
  const std::size_t budget = together.match.max_hypotheses, batch = together.run.batch;
  const std::size_t batches = 1 + (budget + batch - 1) / batch;
  EXPECT_GE(spent(t), batch + budget) << "its first batch, then one budget with its parts";
  EXPECT_LE(spent(t), batch + budget + 3 * batches);
  EXPECT_GE(spent(a), 2 * budget) << "alone, then its parts";
  EXPECT_LT(spent(t), spent(a));
  EXPECT_LT(t.screened, a.screened);
  // The whole cluster's untried poses go on first among the regions: of the first round, in which
  // each region tries a batch, one place is theirs, and one part fewer is reached than when the
  // parts had a budget of their own.
  EXPECT_EQ(t.parts_unreached, a.parts_unreached + 1);
}

// The same objects detected, in the same order, each within 2 mm and 2 degrees of the other's pose.
void expect_same_poses(const Recognition& a, const Recognition& b) {
  ASSERT_EQ(a.detections.size(), b.detections.size());
  for (std::size_t i = 0; i < a.detections.size(); ++i) {
    const Transform& T = a.detections[i].T_camera_object;
    const Transform& U = b.detections[i].T_camera_object;
    EXPECT_EQ(a.detections[i].object_id, b.detections[i].object_id);
    EXPECT_LT((T.translation() - U.translation()).norm(), 0.002);
    EXPECT_LT(rotation_difference_deg(T.linear(), U.linear()), 2.0);
  }
}

TEST(Recognize, APlaceTheScreenLedManyPosesToIsRefinedOnce) {
  // Many starting poses of a region lead to one place (MatchOptions::merge_rotation_deg). Where
  // nothing is known (the five cans against the jug), each place is refined once: fewer poses
  // refined than with merging off, each merged one counted and spending its share of the budget.
  // Where objects are found, the same are found at the same poses.
  const ViewDatabase& db = jug_db();
  RecognizerOptions merged, apart;
  apart.match.merge_rotation_deg = 0;
  ASSERT_GT(merged.match.merge_rotation_deg, 0) << "the default";
  const Recognizer with(db, merged), without(db, apart);
  const Frame cans = frame_from_depth(five_cans_in_a_row().depth, K);
  const Recognition m = with.recognize(cans), a = without.recognize(cans);
  EXPECT_TRUE(m.detections.empty());
  EXPECT_TRUE(a.detections.empty());
  EXPECT_GT(m.screened_merged, 0u);
  EXPECT_EQ(a.screened_merged, 0u);
  EXPECT_LE(m.screened_out + m.screened_merged, m.screened);
  EXPECT_LT(m.hypotheses, a.hypotheses);
  // The same budget spent either way, to within the half turns a batch may add (three each).
  const auto spent = [](const Recognition& r) { return r.hypotheses + r.screened_out + r.screened_merged; };
  const std::size_t batches = 2 * (1 + (merged.match.max_hypotheses + merged.run.batch - 1) / merged.run.batch);
  EXPECT_LE(spent(m), spent(a) + 3 * batches);
  EXPECT_GE(spent(m) + 3 * batches, spent(a));
  std::printf("five cans: %zu poses refined, %zu merged; %zu refined with merging off\n", m.hypotheses, m.screened_merged, a.hypotheses);
  // Rooms (the jug and the box among furniture, ICP screened in most regions): the same objects at
  // the same poses.
  const Recognizer room_with(room_db(), merged), room_without(room_db(), apart);
  std::size_t found = 0, merged_in_rooms = 0, frames = 0;
  for (const Frame& frame : room_frames()) {
    SCOPED_TRACE(frames++);
    const Recognition mr = room_with.recognize(frame), ar = room_without.recognize(frame);
    merged_in_rooms += mr.screened_merged;
    expect_same_poses(mr, ar);
    found += mr.detections.size();
  }
  EXPECT_GT(found, 0u);
  EXPECT_GT(merged_in_rooms, 0u);
  std::printf("rooms: %zu found, %zu poses merged\n", found, merged_in_rooms);
}

TEST(Recognize, AScreenedPoseIsRefinedFromWhereTheScreenLedIt) {
  // A screened pose's full ICP starts where the screen led it, without the schedule's first stage
  // (MatchOptions::refine_from_screen): fewer ICP steps a refinement than from its starting pose
  // with the whole schedule, and the same objects at the same poses (rooms: most regions are
  // screened).
  RecognizerOptions from_screen, from_start;
  from_start.match.refine_from_screen = false;
  ASSERT_TRUE(from_screen.match.refine_from_screen) << "the default";
  const Recognizer with(room_db(), from_screen), without(room_db(), from_start);
  std::size_t steps_with = 0, steps_without = 0, refined_with = 0, refined_without = 0, found = 0, frames = 0;
  for (const Frame& frame : room_frames()) {
    SCOPED_TRACE(frames++);
    const Recognition s = with.recognize(frame), t = without.recognize(frame);
    EXPECT_GE(s.icp_steps, s.hypotheses);
    steps_with += s.icp_steps, refined_with += s.hypotheses;
    steps_without += t.icp_steps, refined_without += t.hypotheses;
    expect_same_poses(s, t);
    found += s.detections.size();
  }
  EXPECT_GT(found, 0u);
  ASSERT_GT(refined_with, 0u);
  ASSERT_GT(refined_without, 0u);
  const double per_pose_with = static_cast<double>(steps_with) / static_cast<double>(refined_with);
  const double per_pose_without = static_cast<double>(steps_without) / static_cast<double>(refined_without);
  std::printf("ICP steps a refinement: %.1f from where the screen led, %.1f from the starting pose\n", per_pose_with, per_pose_without);
  EXPECT_LT(per_pose_with, 0.95 * per_pose_without);
}

TEST(Recognize, APoseThatPassesInTheFirstBatchIsStillChallengedByTheOtherObjects) {
  // The jug alone, a jug a tenth larger in the database too (its views match the cluster as well).
  // The cluster's first batch is searched alone, capped at one batch (SplitOptions::whole_with_parts);
  // the larger jug's next poses in the budget's range must still challenge the pose that passes
  // there (MatchOptions::challenger_views): more poses spent than without challengers, and the
  // right jug found. (At these noise seeds the jug passes in its first batch: with the challengers'
  // range cut to that batch, as 01d422e had it, every image fails here.)
  static const ViewDatabase db = [] {
    TriangleMesh larger = make_jug();
    for (auto& v : larger.vertices) v *= 1.1f;
    const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {2, "larger jug", larger}};
    return build_view_database(models, DatabaseParams{});
  }();
  RecognizerOptions challenged, unchallenged;
  unchallenged.match.challenger_views = 0;
  ASSERT_GT(challenged.match.challenger_views, 0u) << "the default";
  const Recognizer with(db, challenged), without(db, unchallenged);
  for (std::size_t image = 0; image < 3; ++image) {
    const Frame frame = jug_at_one_metre(3, image, SensorModel::kinect_v1(), 70 + image);
    const Recognition c = with.recognize(frame), u = without.recognize(frame);
    ASSERT_EQ(c.detections.size(), 1u) << "image " << image;
    ASSERT_EQ(u.detections.size(), 1u) << "image " << image;
    EXPECT_EQ(c.detections[0].object_id, 1) << "image " << image;
    EXPECT_GT(c.hypotheses + c.screened_out + c.screened_merged, u.hypotheses + u.screened_out + u.screened_merged) << "image " << image;
  }
}

TEST(Recognize, AnObjectTallerThanARiserBesideItIsNotTakenToStandInsideTheRiser) {
  // The jug on the table beside a box 0.5 m square and a third of its height (a riser: its top is
  // a plane the segmentation removes). The jug's lower part lies below the riser's plane, and the
  // camera sees the jug's own front at the riser's height: on the plane, but not where the riser
  // is. Judged against the unbounded plane, the right pose was dropped as lying inside the riser
  // in three of these four placements (AcceptOptions::max_share_inside_planes).
  const ViewDatabase& db = jug_db();
  const BoundingBox jug = bounding_box(make_jug());
  const auto height = static_cast<float>(0.3 * (jug.max.z() - jug.min.z()));
  const double apart = 0.25 + 0.5 * static_cast<double>(jug.max.x() - jug.min.x()) + 0.02;  // 2 cm between them
  for (const Eigen::Vector3d& side : {Eigen::Vector3d(apart, 0, 0), Eigen::Vector3d(-apart, 0, 0), Eigen::Vector3d(0, -apart, 0)}) {
    JugAndCan scene = jug_and_can_scene();
    scene.ds.objects.push_back({3, "riser", make_box_mesh({0.5f, 0.5f, height})});
    const Transform riser_pose = scene.jug_pose * make_transform(Eigen::Matrix3d::Identity(), side + Eigen::Vector3d(0, 0, jug.min.z() + 0.5 * height));
    const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}, {2, riser_pose}}}, SensorModel::kinect_v1(), 3);
    const Recognition r = Recognizer(db).recognize(frame_from_depth(f.depth, K));
    EXPECT_EQ(r.dropped_inside_planes, 0u) << side.transpose();
    ASSERT_EQ(r.detections.size(), 1u) << side.transpose();
    EXPECT_LT(add_s_error(r.detections[0].T_camera_object, f.gt[0].T_camera_object, make_jug().vertices), 0.1 * mesh_diameter(make_jug()));
  }
}

TEST(Recognize, ACanTurnedAboutItsAxisGivesTheSamePose) {
  // A can looks the same turned about its axis: the pose reported is the canonical one, the same
  // for every turn (issue 10), and still right under ADD-S.
  const ViewDatabase& db = jug_and_can_db();
  ASSERT_EQ(db.objects[1].symmetries.continuous.size(), 1u);
  const JugAndCan scene = jug_and_can_scene();
  const Transform can_pose = scene.can_at(0.0);  // where the jug would stand
  std::vector<Transform> reported;
  for (double deg : {0.0, 50.0, 130.0}) {
    const Transform turned = can_pose * make_transform(Eigen::AngleAxisd(deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d::Zero());
    const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{1, turned}}}, SensorModel::kinect_v1(), 5);
    const Recognition r = Recognizer(db).recognize(frame_from_depth(f.depth, K));
    ASSERT_EQ(r.detections.size(), 1u) << deg;
    EXPECT_EQ(r.detections[0].object_id, 2);
    EXPECT_LT(add_s_error(r.detections[0].T_camera_object, turned, make_can().vertices), 0.1 * db.objects[1].diameter_m);
    reported.push_back(r.detections[0].T_camera_object);
  }
  for (const Transform& T : reported) {
    EXPECT_LT(rotation_difference_deg(T.linear(), reported[0].linear()), 3.0);
    EXPECT_LT((T.translation() - reported[0].translation()).norm(), 0.005);
  }
}

TEST(Recognize, ACanIsReportedStandingOnItsTableByACameraUpsideDown) {
  // A can is alike end for end: which end is up comes from the table it stands on, not from the
  // camera's axes. Seen by the camera held upright and then rolled half a turn (the image turned
  // about its centre, as a wrist camera sees it), it is reported standing up both times; the
  // camera's own default up alone would stand it on its head in the second.
  const ViewDatabase& db = jug_and_can_db();
  const Symmetries& symmetries = db.objects[1].symmetries;
  ASSERT_FALSE(symmetries.empty());
  const JugAndCan scene = jug_and_can_scene();
  const Transform can_pose = scene.can_at(0.0);
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{1, can_pose}}}, SensorModel::kinect_v1(), 9);
  ASSERT_DOUBLE_EQ(K.cx, (K.width - 1) / 2.0);  // the turned image keeps the intrinsics
  ASSERT_DOUBLE_EQ(K.cy, (K.height - 1) / 2.0);
  DepthImage turned(f.depth.width, f.depth.height);
  for (int v = 0; v < f.depth.height; ++v)
    for (int u = 0; u < f.depth.width; ++u) turned.at(f.depth.width - 1 - u, f.depth.height - 1 - v) = f.depth.at(u, v);
  const Transform T_rolled_camera = make_transform(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix(), Eigen::Vector3d::Zero());
  std::size_t fixed_reference_upside_down = 0;
  for (const bool rolled : {false, true}) {
    SCOPED_TRACE(rolled ? "camera rolled half a turn" : "camera upright");
    const Transform truth = rolled ? T_rolled_camera * can_pose : can_pose;
    const Recognition r = Recognizer(db).recognize(frame_from_depth(rolled ? turned : f.depth, K));
    ASSERT_EQ(r.detections.size(), 1u);
    const Detection& d = r.detections[0];
    EXPECT_EQ(d.object_id, 2);
    EXPECT_LT(add_s_error(d.T_camera_object, truth, make_can().vertices), 0.1 * db.objects[1].diameter_m);
    const Eigen::Vector3d up = truth.linear().col(2);  // the can stands on the table, z up
    EXPECT_GT(d.T_camera_object.linear().col(2).dot(up), 0.95);
    fixed_reference_upside_down += canonical_pose(d.T_camera_object, symmetries).linear().col(2).dot(up) < 0 ? 1 : 0;
  }
  EXPECT_EQ(fixed_reference_upside_down, 1u) << "the camera's default up fails the rolled camera alone";
}

TEST(Recognize, AJugCutInTwoByABandOfMissingDepthIsFoundFromBothPieces) {
  // A band of rows with no depth across the jug's middle (a dark label, a shiny stripe): 10 or 14
  // rows at 1 m, 2-3 cm of its tilted surface, wider than a cluster's gap, so the jug comes out as two clusters and
  // neither half carries it (verification wants most of the pose's surface on its cluster). The
  // halves, joined in the image by the missing depth, are searched together
  // (SplitOptions::join_gap_m). Narrower bands leave one cluster: nothing to join.
  const ViewDatabase& db = jug_and_can_db();
  const JugAndCan scene = jug_and_can_scene();
  const SimulatedFrame f = simulate_image(scene.ds, SimImage{{{0, scene.jug_pose}}}, SensorModel::kinect_v1(), 5);
  int top = f.depth.height, bottom = 0;  // the jug's rows in the image
  for (const Eigen::Vector3f& p : make_jug().vertices) {
    const int v = static_cast<int>(std::lround(K.project(scene.jug_pose * p.cast<double>()).y()));
    top = std::min(top, v), bottom = std::max(bottom, v);
  }
  for (const int band : {0, 6, 10, 14}) {
    DepthImage cut = f.depth;
    for (int v = (top + bottom - band) / 2; v < (top + bottom - band) / 2 + band; ++v)
      for (int u = 0; u < cut.width; ++u) cut.at(u, v) = NAN;
    for (const float join_gap_m : {SplitOptions{}.join_gap_m, 0.0f}) {
      SCOPED_TRACE(fmt::format("a band of {} rows, {}", band, join_gap_m > 0 ? "pieces joined" : "no join"));
      RecognizerOptions options;
      options.split.join_gap_m = join_gap_m;
      const Recognition r = Recognizer(db, options).recognize(frame_from_depth(cut, K));
      const bool in_two = band >= 10;
      EXPECT_EQ(r.clusters, in_two ? 2u : 1u);
      EXPECT_EQ(r.joined_regions, in_two && join_gap_m > 0 ? 1u : 0u);
      if (in_two && join_gap_m == 0) {
        EXPECT_TRUE(r.detections.empty()) << "neither half alone";
        continue;
      }
      ASSERT_EQ(r.detections.size(), 1u);
      EXPECT_EQ(r.detections[0].object_id, 1);
      EXPECT_LT(add_s_error(r.detections[0].T_camera_object, scene.jug_pose, make_jug().vertices), 0.005);
    }
  }
  // The same band measured, a surface 1.6 m away seen there (a gap between two things, not a hole
  // in one): the halves are not joined. (What each half gives alone is not asserted: under the
  // sanitizers' build one half gave a pose that passed.)
  DepthImage seen_through = f.depth;
  for (int v = (top + bottom - 14) / 2; v < (top + bottom - 14) / 2 + 14; ++v)
    for (int u = 0; u < seen_through.width; ++u) seen_through.at(u, v) = 1.6f;
  const Recognition r = Recognizer(db).recognize(frame_from_depth(seen_through, K));
  EXPECT_GE(r.clusters, 2u) << "the two halves (and the band's pieces)";
  EXPECT_EQ(r.joined_regions, 0u);
}

TEST(Recognize, ABookSeenEdgeOnIsFoundFromTheStripsOwnStartingPoses) {
  // A book (20 x 15 x 2 cm) standing on its edge in the thesis's set-up, turned about the vertical:
  // in images 5 and 15 of 20 it shows the camera its 2 cm edge, a strip no rendered view stands in
  // line with. Every pose verification passes is taken (min_confidence 0: flat faces score low,
  // docs/RESULTS.md's book), with the strip's edge-on starts and without them.
  const TriangleMesh book = make_box_mesh({0.20f, 0.02f, 0.15f});
  const ObjectModel model{1, "book", book};
  const ViewDatabase db = build_view_database(std::span(&model, 1), DatabaseParams{});
  SeedExperimentOptions setup;
  setup.distances_m = {0.75, 1.0, 1.25};
  const SimDataset ds = make_seed_experiment(model, K, setup, 1);
  const double diameter = mesh_diameter(book);
  int right_with = 0, right_without = 0, wrong_with = 0, from_strip = 0;
  for (std::size_t scene = 0; scene < ds.scenes.size(); ++scene) {
    for (const std::size_t image : {5u, 15u}) {
      const SimulatedFrame f = simulate_image(ds, ds.scenes[scene].images[image], SensorModel::kinect_v1(), 100 + 20 * scene + image);
      const Frame frame = frame_from_depth(f.depth, K);
      for (const int turns : {12, 0}) {
        RecognizerOptions options;
        options.accept.min_confidence = 0.0;
        options.match.edge_on_turns = turns;
        options.match.source = PoseSource::vfh;  // no votes: a pose with no view's rank is an edge-on start's
        const Recognition r = Recognizer(db, options).recognize(frame);
        for (const Detection& d : r.detections) {
          const bool right = add_s_error(d.T_camera_object, f.gt[0].T_camera_object, book.vertices) < 0.1 * diameter;
          if (turns == 0) {
            right_without += right;
          } else {
            (right ? right_with : wrong_with) += 1;
            from_strip += right && d.match_rank == -1;  // an edge-on start has no view's rank
          }
        }
      }
    }
  }
  // Measured: 6 of 6 right with them (each from a strip's start), 4 without; none wrong.
  EXPECT_GT(right_with, right_without);
  EXPECT_GT(from_strip, 0);
  EXPECT_EQ(wrong_with, 0);
}

TEST(Recognize, ADoubtfulPoseIsChallengedByItsOwnObjectsNextPoses) {
  // The book of the test above at 1.5 m, turned about the vertical, every pose verification passes
  // taken (min_confidence 0): a flat face or an edge far away passes with low confidence in more
  // than one pose, and the first to pass is not always the right one. A pose below
  // doubtful_confidence is challenged by its own object's next poses, and the higher score wins.
  const TriangleMesh book = make_box_mesh({0.20f, 0.02f, 0.15f});
  const ObjectModel model{1, "book", book};
  const ViewDatabase db = build_view_database(std::span(&model, 1), DatabaseParams{});
  SeedExperimentOptions setup;
  setup.distances_m = {1.5};
  const SimDataset ds = make_seed_experiment(model, K, setup, 1);
  const double diameter = mesh_diameter(book);
  int right[2] = {0, 0}, wrong[2] = {0, 0}, doubtful = 0;
  std::size_t tried[2] = {0, 0};
  for (std::size_t image = 0; image < ds.scenes[0].images.size(); ++image) {
    const SimulatedFrame f = simulate_image(ds, ds.scenes[0].images[image], SensorModel::kinect_v1(), 700 + image);
    const Frame frame = frame_from_depth(f.depth, K);
    for (const int challenged : {0, 1}) {
      RecognizerOptions options;
      options.accept.min_confidence = 0.0;
      options.match.doubtful_confidence = challenged ? 0.5 : 0.0;
      const Recognition r = Recognizer(db, options).recognize(frame);
      tried[challenged] += r.hypotheses;
      for (const Detection& d : r.detections) {
        const bool ok = add_s_error(d.T_camera_object, f.gt[0].T_camera_object, book.vertices) < 0.1 * diameter;
        (ok ? right : wrong)[challenged] += 1;
        doubtful += challenged && d.score < 0.5;
      }
    }
  }
  // Measured: 18 right and 2 wrong unchallenged, 19 and 1 challenged; 7 of the poses reported
  // doubtful; 89 and 110 poses tried. (Which frame turns depends on the last bits of the noise and
  // the arithmetic; that the challenge ran, and made nothing worse, does not.)
  EXPECT_GT(doubtful, 0);
  EXPECT_GT(tried[1], tried[0]);  // the doubtful poses were challenged
  EXPECT_GE(right[1], right[0]);
  EXPECT_LE(wrong[1], wrong[0]);
}

TEST(Frame, IntrinsicsAreRecoveredFromAnOrganizedCloud) {
  const CameraIntrinsics truth{570.3, 565.1, 321.7, 236.2, 640, 480};
  DepthImage d(640, 480);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) d.at(u, v) = (u + v) % 9 == 0 ? NAN : 1.0f + 0.001f * static_cast<float>(u);
  const Frame f = frame_from_cloud(depth_to_cloud(d, truth));
  EXPECT_NEAR(f.K.fx, truth.fx, 1e-2);
  EXPECT_NEAR(f.K.fy, truth.fy, 1e-2);
  EXPECT_NEAR(f.K.cx, truth.cx, 1e-2);
  EXPECT_NEAR(f.K.cy, truth.cy, 1e-2);
  EXPECT_EQ(f.depth.count_valid(), d.count_valid());
  // A cloud that is not one pinhole image is refused, not silently mis-projected.
  PointCloud shuffled = depth_to_cloud(d, truth);
  std::swap(shuffled.points[1000], shuffled.points[200000]);
  for (std::size_t i = 0; i < shuffled.size(); i += 3) std::swap(shuffled.points[i], shuffled.points[shuffled.size() - 1 - i]);
  test::expect_error([&] { intrinsics_from_organized_cloud(shuffled); }, "not one pinhole image");
}

TEST(Metrics, AddAndAddSOnKnownOffsets) {
  const std::vector<Eigen::Vector3f> pts = {{0.1f, 0, 0}, {-0.1f, 0, 0}, {0, 0.1f, 0}, {0, -0.1f, 0}};
  const Transform truth = Transform::Identity();
  const Transform shifted = make_transform(Eigen::Matrix3d::Identity(), {0.003, 0, 0});
  EXPECT_NEAR(add_error(shifted, truth, pts), 0.003, 1e-9);
  // A half turn about z maps this symmetric set onto itself: ADD sees 0.2 m, ADD-S nothing.
  const Transform turned = make_transform(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d::Zero());
  EXPECT_NEAR(add_error(turned, truth, pts), 0.2, 1e-6);
  EXPECT_NEAR(add_s_error(turned, truth, pts), 0.0, 1e-6);
}

// The two real YCB-Video frames recognized against a database of the BOP meshes `ids`: how many of
// the six ground-truth poses (three objects, two frames) are found within ADD-S 10 % of the
// diameter; every detection must be one of them (no false positive), and each frame must give two.
void expect_ycbv_found(const std::vector<int>& ids, int at_least) {
  const auto dir = test::shared_data() / "ycbv_real_sample";
  const BopDataset ds = open_bop_dataset(dir, "data", {"models_bop_ycbv"});
  const std::map<int, std::string> ycb_names = {{8, "009_gelatin_box"}, {14, "025_mug"}, {21, "061_foam_brick"}};
  std::vector<ObjectModel> models;
  for (int id : ids) {
    PlyFile ply = read_ply(ds.model_files.at(id));
    for (auto& v : ply.mesh.vertices) v *= 0.001f;
    ply.mesh.normals.clear();
    models.push_back({id, fmt::format("obj_{:06d}", id), std::move(ply.mesh)});
  }
  // The ground truth is in the YCB-Video model frame (points.xyz); the BOP mesh is that model moved
  // so that its bounding box is centred (MANIFEST: a few mm), p_ycb = p_bop + c. In the mesh's frame
  // the truth is T_camera_ycb * translation(c).
  std::map<int, Transform> bop_to_ycb;  // per object id
  for (const auto& [id, name] : ycb_names) {
    std::vector<Eigen::Vector3f> ycb_points;
    std::ifstream in(dir / "models" / name / "points.xyz");
    float x, y, z;
    while (in >> x >> y >> z) ycb_points.emplace_back(x, y, z);
    ASSERT_GT(ycb_points.size(), 1000u) << name;
    const BoundingBox box = bounding_box(ycb_points);
    const Eigen::Vector3d c = (0.5f * (box.min + box.max)).cast<double>();
    EXPECT_LT(c.norm(), 0.01) << name << ": the MANIFEST's offset is a few mm";
    bop_to_ycb[id] = make_transform(Eigen::Matrix3d::Identity(), c);
  }
  const ViewDatabase db = build_view_database(models, DatabaseParams{});
  const Recognizer recognizer(db);
  int found = 0;
  for (const BopImage& im : ds.images) {
    const BopFrame bf = load_bop_frame(im);
    const Recognition r = recognizer.recognize(frame_from_depth(bf.depth, bf.K));
    ASSERT_EQ(im.gt.size(), 3u);
    std::set<int> found_here;
    for (const Detection& d : r.detections) {
      const auto object = std::find_if(db.objects.begin(), db.objects.end(), [&](const DatabaseObject& o) { return o.id == d.object_id; });
      ASSERT_NE(object, db.objects.end());
      double error = 1e9;
      for (const GroundTruthPose& g : im.gt) {
        if (g.obj_id == d.object_id) error = add_s_error(d.T_camera_object, g.T_camera_object * bop_to_ycb.at(g.obj_id), object->mesh.vertices);
      }
      EXPECT_LT(error, 0.1 * object->diameter_m) << "image " << im.im_id << ": a false positive, " << d.object_name;
      if (error < 0.1 * object->diameter_m) found_here.insert(d.object_id);
    }
    found += static_cast<int>(found_here.size());
    EXPECT_GE(found_here.size(), 2u) << "image " << im.im_id;
  }
  EXPECT_GE(found, at_least) << "of 6";
}

TEST(RealData, YcbvObjectsAreFoundInTheXtionFramesAndNothingWrong) {
  // Measured: with a database of the three matching BOP models all three are found in both frames
  // within 5 mm ADD-S. The mug and the foam brick touch and come out of Euclidean clustering as one
  // cluster; they are found in its convex parts. Asserted just below that: 5 of the 6.
  VIEWPOSE_REQUIRE_SHARED_DATA();
  expect_ycbv_found({8, 14, 21}, 5);
}

TEST(RealData, YcbvWithSixObjectsInTheDatabaseAcceptsNothingWrong) {
  // The three other meshes of the sample too (cracker box, mustard bottle, bleach cleanser), none
  // of them in view. Measured: the same six poses found and nothing else; before free-space
  // conflicts were held to 5 % the cracker box was fitted to the keyboard in both frames.
  VIEWPOSE_REQUIRE_SHARED_DATA();
  expect_ycbv_found({2, 5, 8, 12, 14, 21}, 5);
}

// The ycbv_real_dev meshes of `ids` (millimetres in the files), in a database made as make results makes it.
ViewDatabase ycbv_dev_database(const BopDataset& ds, std::initializer_list<int> ids) {
  std::vector<ObjectModel> models;
  for (const int id : ids) {
    PlyFile ply = read_ply(ds.model_files.at(id));
    for (auto& v : ply.mesh.vertices) v *= 0.001f;
    ply.mesh.normals.clear();
    models.push_back({id, fmt::format("obj_{:06d}", id), std::move(ply.mesh)});
  }
  return build_view_database(models, DatabaseParams{});
}

// The image of a scene, or null.
const BopImage* find_image(const BopDataset& ds, int scene_id, int im_id) {
  const auto image = std::find_if(ds.images.begin(), ds.images.end(), [&](const BopImage& im) { return im.scene_id == scene_id && im.im_id == im_id; });
  return image == ds.images.end() ? nullptr : &*image;
}

// An image of the dataset (its truth, for right_detections) and its frame, from its depth and
// intrinsics; throws where the dataset has no such image.
std::pair<BopImage, Frame> ycbv_dev_frame(const BopDataset& ds, int scene_id, int im_id) {
  const BopImage* image = find_image(ds, scene_id, im_id);
  if (!image) throw std::runtime_error(fmt::format("no image {} in scene {}", im_id, scene_id));
  const BopFrame bf = load_bop_frame(*image);
  return {*image, frame_from_depth(bf.depth, bf.K)};
}

// Each object found within ADD-S of a tenth of its diameter from its truth in `image`, with that
// error; any other detection fails the test (a false positive).
std::map<int, double> right_detections(const Recognition& r, const ViewDatabase& db, const BopImage& image) {
  std::map<int, double> right;
  for (const Detection& d : r.detections) {
    const DatabaseObject& object = *std::find_if(db.objects.begin(), db.objects.end(), [&](const DatabaseObject& o) { return o.id == d.object_id; });
    double error = 1e9;
    for (const GroundTruthPose& g : image.gt) {
      if (g.obj_id == d.object_id) error = std::min(error, add_s_error(d.T_camera_object, g.T_camera_object, object.mesh.vertices));
    }
    EXPECT_LT(error, 0.1 * object.diameter_m) << "a false positive: " << d.object_name;
    if (error < 0.1 * object.diameter_m) right[d.object_id] = error;
  }
  return right;
}

std::set<int> ids_of(const std::map<int, double>& right) {
  std::set<int> ids;
  for (const auto& [id, error] : right) ids.insert(id);
  return ids;
}

TEST(RealData, ACanStandingOnABoxAndTheBoxAreFoundTogetherFromPointPairVotes) {
  // YCB-Video 0014 frame 2 (ycbv_real_dev): a master chef can, a sugar box with a potted meat can
  // standing on it, and a pitcher. The box and the can on it stay one region even in convex parts
  // (the crease between them is bridged), whose VFH describes neither. Point pair votes give the
  // can's pose there; it explains half of the region, and the box found in the other half vouches
  // for it (SplitOptions::joint_min_cluster_explained). Measured: all four within 2 mm of the truth.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: point pair votes on a real frame take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const auto dir = test::shared_data() / "ycbv_real_dev";
  const BopDataset ds = open_bop_dataset(dir, "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {1, 3, 9, 11});
  const auto [image, frame] = ycbv_dev_frame(ds, 14, 2);
  // Votes everywhere nothing else passes (both), or only in what a detection leaves (touching: the
  // box and the can are what the pitcher and the master chef can left of their regions); touching
  // again as `recognize` of one file runs it, the pair tables left in the file until the first vote.
  const test::TempDir files;
  db.save(files / "ycbv4.vpdb");
  const ViewDatabase tables_on_disk = ViewDatabase::load(files / "ycbv4.vpdb", database_load_options(RecognizerOptions{}, FramesToServe::one));
  ASSERT_TRUE(tables_on_disk.pair_tables_on_disk);
  for (const auto& [source, database] : {std::pair{PoseSource::both, &db}, std::pair{PoseSource::touching, &db},
                                         std::pair{PoseSource::touching, &tables_on_disk}}) {
    RecognizerOptions options;
    options.match.source = source;
    const Recognition r = Recognizer(*database, options).recognize(frame);
    EXPECT_EQ(ids_of(right_detections(r, db, image)), (std::set<int>{1, 3, 9, 11})) << (source == PoseSource::both ? "both" : "touching")
                                                    << (database == &tables_on_disk ? ", tables read at the first vote" : "");
    // (With touching, after the views' poses of the region's parts: MatchOptions::votes_after_parts.)
    EXPECT_GT(r.voted_regions, 0u);
  }
}

TEST(RealData, AMugSeenInTwoPiecesIsFoundWhenThePiecesAreSearchedTogether) {
  // YCB-Video 0000 frame 5 (ycbv_real_dev): the gelatin box, the mug and the foam brick touching.
  // The Xtion returns no depth on the mug's rim: its inside is a cluster of its own, its outside
  // is what the box and the brick leave of theirs, and neither piece carries the mug alone. The
  // two, joined by a ring of missing pixels, are searched as one region
  // (SplitOptions::join_gap_m). Measured: the mug within ADD-S 5 mm; without the join, not found.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: point pair votes on a real frame take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const auto dir = test::shared_data() / "ycbv_real_dev";
  const BopDataset ds = open_bop_dataset(dir, "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {1, 3, 8, 9, 11, 14, 21});  // the dataset's seven
  const auto [image, frame] = ycbv_dev_frame(ds, 0, 5);
  for (const float join_gap_m : {SplitOptions{}.join_gap_m, 0.0f}) {
    SCOPED_TRACE(join_gap_m > 0 ? "pieces joined" : "no join");
    RecognizerOptions options;
    options.split.join_gap_m = join_gap_m;
    const Recognition r = Recognizer(db, options).recognize(frame);
    const std::map<int, double> found = right_detections(r, db, image);
    EXPECT_EQ(found.count(14), join_gap_m > 0 ? 1u : 0u);
    if (found.count(14)) {
      EXPECT_LT(found.at(14), 0.005) << "the mug's ADD-S error";
    }
    EXPECT_EQ(r.joined_regions > 0, join_gap_m > 0);
    EXPECT_TRUE(found.count(8) && found.count(21));
  }
}

TEST(RealData, AMugAgainstObjectsNotInTheDatabaseIsGrownFromItsPart) {
  // YCB-Video 0000 (ycbv_real_dev) with the mug alone in the database: it touches the foam brick
  // and the gelatin box, which the database does not hold. Their cluster is cut into convex parts,
  // and the mug's outer wall, inside and handle fall into different ones: a pose found on the wall
  // shows a model most of whose surface lies on the other parts, and fails the model's support.
  // Grown into the points near that model (SplitOptions::grow_reach_m), the mug is one region and
  // passes. Measured: 6 of the 8 frames found with it, none without, none wrong; two tested here.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: real frames against a database take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {14});
  // In frame 3 the wall's pose fails the support; in frame 6 it passes it narrowly (half the model
  // on the part) with a confidence of 0.72, below the bound.
  for (const int im_id : {3, 6}) {
    const auto [image, frame] = ycbv_dev_frame(ds, 0, im_id);
    for (const float grow_reach_m : {SplitOptions{}.grow_reach_m, 0.0f}) {
      SCOPED_TRACE(fmt::format("frame {}, grown within {} m", im_id, grow_reach_m));
      RecognizerOptions options;
      options.split.grow_reach_m = grow_reach_m;
      const Recognition r = Recognizer(db, options).recognize(frame);
      const std::map<int, double> found = right_detections(r, db, image);
      EXPECT_EQ(r.detections.size(), found.size()) << "a detection that is not the mug";
      EXPECT_EQ(found.count(14), grow_reach_m > 0 ? 1u : 0u);
      EXPECT_EQ(r.grown_regions > 0, grow_reach_m > 0);
      for (const Detection& d : r.detections) EXPECT_TRUE(d.from_split_cluster) << "grown from a part, not the whole cluster";
    }
  }
}

TEST(RealData, AMugGrownFromAPartOfAClusterThatWentOnWithItsPartsIsMarkedAsFromASplitCluster) {
  // The case above with the master chef can (not in the frame) in the database too: it is wide
  // enough to be tried on the whole cluster of the mug, the brick and the box, so the whole
  // cluster's first batch fails with poses left, and it goes on with its convex parts in one
  // budget (SplitOptions::whole_with_parts, the whole cluster as region 0). None passes; the mug's
  // pose grown from its part's seed does. Measured in frame 3 (with the can, the box or the
  // pitcher beside the mug): reached, and marked found in the whole cluster when that was judged
  // from which region the search returned without checking that it returned a pose (the fault
  // of 4a3b621 that f1e98c5 mended: this test fails with it, checked).
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: real frames against a database take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {1, 14});
  const auto [image, frame] = ycbv_dev_frame(ds, 0, 3);
  const Recognition r = Recognizer(db).recognize(frame);
  EXPECT_EQ(ids_of(right_detections(r, db, image)), std::set<int>{14});
  ASSERT_EQ(r.detections.size(), 1u) << "a detection that is not the mug";
  EXPECT_GT(r.grown_regions, 0u);
  EXPECT_GT(r.split_clusters, 0u);
  EXPECT_TRUE(r.detections[0].from_split_cluster) << "grown from a part, not found in the whole cluster";
}

TEST(RealData, WhatADetectionLeavesIsSplitIntoPartsBeforeAnyVoteIsCast) {
  // YCB-Video 0000 (ycbv_real_dev) with the dataset's seven objects: the gelatin box, the mug and
  // the foam brick touch. Once the first is found, the other two are what it leaves, one region
  // whose views' poses fail. Its convex parts' views find them both; votes for all seven objects,
  // cast before the parts (MatchOptions::votes_after_parts off), found nothing there and were most
  // of the frame's time. Measured: the same three poses either way in all eight frames; votes cast
  // without the option in six of them (4 and 6 here), with it in one (5: a piece of the pile's
  // region that nothing explains, where the votes find nothing either).
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: point pair votes on a real frame take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {1, 3, 8, 9, 11, 14, 21});
  for (const int im_id : {4, 6}) {
    const auto [image, frame] = ycbv_dev_frame(ds, 0, im_id);
    for (const bool after_parts : {true, false}) {
      SCOPED_TRACE(fmt::format("frame {}, votes after the parts: {}", im_id, after_parts));
      RecognizerOptions options;
      ASSERT_EQ(options.match.source, PoseSource::touching);
      options.match.votes_after_parts = after_parts;
      const Recognition r = Recognizer(db, options).recognize(frame);
      EXPECT_EQ(ids_of(right_detections(r, db, image)), (std::set<int>{8, 14, 21}));
      EXPECT_EQ(r.detections.size(), 3u);
      EXPECT_EQ(r.voted_regions > 0, !after_parts);
    }
  }
}

TEST(RealData, ARestTooWideToBeSearchedWholeCastsItsVotesInItsParts) {
  // YCB-Video 0000 frame 5 (ycbv_real_dev) against the foam brick and the potted meat can (not in
  // the frame; the larger, 0.13 m). The brick is found first in the pile; what it leaves, the
  // gelatin box and the mug, is wider than MatchOptions::max_region_size_factor times the can, so
  // it is searched in convex parts alone, and votes_after_parts has no whole region to cast votes
  // in: each part's votes are cast after its views, as with the option off. Measured: two regions
  // voted in either way; with the parts' votes skipped there (d1637c2's fault), none.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: point pair votes on a real frame take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {9, 21});
  const auto [image, frame] = ycbv_dev_frame(ds, 0, 5);
  RecognizerOptions options;
  ASSERT_TRUE(options.match.votes_after_parts);
  const Recognition r = Recognizer(db, options).recognize(frame);
  EXPECT_EQ(ids_of(right_detections(r, db, image)), (std::set<int>{21}));
  EXPECT_GT(r.voted_regions, 0u);
  options.match.votes_after_parts = false;
  const Recognition without = Recognizer(db, options).recognize(frame);
  EXPECT_EQ(r.voted_regions, without.voted_regions);
  EXPECT_EQ(r.hypotheses, without.hypotheses);
  EXPECT_EQ(r.detections.size(), without.detections.size());
}

TEST(RealData, APileOfThreeSmallObjectsIsSplitWhenOnlyTheyAreInTheDatabase) {
  // YCB-Video 0000 (ycbv_real_dev): the gelatin box, the mug and the foam brick touch, one cluster
  // 0.28 m across. With only these three in the database (the largest 0.125 m) a region more than
  // twice as wide as the largest object was not split, and the frames where they touch gave
  // nothing (2 of 8 frames found them). Now regions up to SplitOptions::min_size_m are split.
  // Measured: all three in each frame.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: real frames against a database take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {8, 14, 21});
  const Recognizer recognizer(db);
  for (const int im_id : {4, 6}) {  // two of the frames the old bound lost
    SCOPED_TRACE(fmt::format("frame {}", im_id));
    const auto [image, frame] = ycbv_dev_frame(ds, 0, im_id);
    const Recognition r = recognizer.recognize(frame);
    EXPECT_EQ(ids_of(right_detections(r, db, image)), (std::set<int>{8, 14, 21}));
  }
}

TEST(RealData, APoseWhoseHiddenPartLiesInsideTheTableIsDropped) {
  // YCB-Video 0014 frame 2 (ycbv_real_dev) with only the pitcher in the database: besides the
  // pitcher, a pitcher fitted to the master chef can passed every test of verification (score
  // 1.00), its handle and spout "occluded" by the table they would stand in
  // (AcceptOptions::max_share_inside_planes). Measured: 12 % of its model inside the table; the
  // right pitcher's 0. Refused, the can's region goes on to its next poses.
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: real frames against a database take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {11});
  const auto [image, frame] = ycbv_dev_frame(ds, 14, 2);
  const Recognition r = Recognizer(db).recognize(frame);
  EXPECT_EQ(r.detections.size(), 1u);
  EXPECT_EQ(ids_of(right_detections(r, db, image)), std::set<int>{11});
  EXPECT_GE(r.dropped_inside_planes, 1u);
  // Without the rule the phantom stands (the test's reason to exist).
  RecognizerOptions keep_all;
  keep_all.accept.max_share_inside_planes = 1;
  const Recognition unfiltered = Recognizer(db, keep_all).recognize(frame);
  EXPECT_EQ(unfiltered.detections.size(), 2u);
  EXPECT_EQ(unfiltered.dropped_inside_planes, 0u);
  // Refused in the search, not only dropped from the frame's detections: the can's region went on
  // to its next poses. Seen where votes are cast in it before its parts' views are tried
  // (MatchOptions::votes_after_parts off): their pitchers in the table are refused too (5 in all).
  // (With the default, the phantom is the only one: the parts' views find nothing in the table.)
  RecognizerOptions votes_first;
  votes_first.match.votes_after_parts = false;
  const Recognition searched_on = Recognizer(db, votes_first).recognize(frame);
  EXPECT_EQ(ids_of(right_detections(searched_on, db, image)), std::set<int>{11});
  EXPECT_EQ(searched_on.detections.size(), 1u);
  EXPECT_GT(searched_on.dropped_inside_planes, 1u);
}

TEST(RealData, ATallerCanFittedByItsTopDoesNotStandInTheTable) {
  // Real mOSD frames 36 and 45 (Kinect) hold no YCB-V object, but a can 13 cm tall: with YCB-V's
  // master chef can (14 cm) in the database, the chef can fitted by its top passed verification
  // (score 1.00), its foot 17 mm into the table. The table's band removes every object's foot, and
  // the model's part inside the table is hidden by it; not by more than inside_planes' margin
  // (the band and the depth's tolerance). Lifted onto the table it floats above the can's top and
  // fails again (AcceptOptions::lift_out_of_planes).
#ifdef VIEWPOSE_SANITIZER_BUILD
  GTEST_SKIP() << "skipped under the sanitizers: real frames against a database take minutes there";
#endif
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(test::shared_data() / "ycbv_real_dev", "test", {"models"});
  const ViewDatabase db = ycbv_dev_database(ds, {1});
  RecognizerOptions sunk;
  sunk.accept.lift_out_of_planes = false;
  for (const int id : {36, 45}) {
    const PointCloud cloud = read_pcd(test::shared_data() / fmt::format("pcl_mosd/test/test{}.pcd", id)).cloud;
    const Frame frame = frame_from_cloud(cloud);
    const Recognition r = Recognizer(db).recognize(frame);
    EXPECT_TRUE(r.detections.empty()) << "test" << id;
    EXPECT_GT(r.dropped_inside_planes, 0u) << "test" << id;
    // Without the rule the chef can stands in the table (the test's reason to exist).
    const Recognition unlifted = Recognizer(db, sunk).recognize(frame);
    EXPECT_EQ(unlifted.detections.size(), 1u) << "test" << id;
  }
}

TEST(RealData, AScannedMilkCartonIsFoundInTheKinectSceneWithinThreeMillimetres) {
  // The thesis's other way to fill a database: a view scanned with the sensor. milk.pcd is the
  // carton's partial model (its frame is the capture's); the scene holds it among other cartons
  // and a bottle.
  VIEWPOSE_REQUIRE_SHARED_DATA();
  ViewDatabase db;
  const int id = add_captured_view(db, read_pcd(test::shared_data() / "pcl_kinect/milk.pcd").cloud, "milk");
  EXPECT_EQ(id, 1);
  ASSERT_EQ(db.views.size(), 1u);
  EXPECT_TRUE(db.objects[0].mesh.triangles.empty());
  test::expect_error([&] {
    ViewDatabase with_mesh = jug_db();
    add_captured_view(with_mesh, read_pcd(test::shared_data() / "pcl_kinect/milk.pcd").cloud, "jug");
  }, "comes from a mesh");

  const PointCloud scene = read_pcd(test::shared_data() / "pcl_kinect/milk_cartoon_all_small_clorox.pcd").cloud;
  const Recognition r = Recognizer(db).recognize(frame_from_cloud(scene));
  ASSERT_EQ(r.detections.size(), 1u);
  const Detection& d = r.detections[0];
  EXPECT_EQ(d.object_name, "milk");
  // The model's points, placed by the estimate, lie on the scene's surface.
  std::vector<Eigen::Vector3f> finite;
  for (const auto& p : scene.points) if (p.allFinite()) finite.push_back(p);
  const KdTree tree(finite);
  double sum = 0;
  for (const auto& p : db.objects[0].model_points) {
    std::uint32_t k;
    float d2;
    tree.nearest((d.T_camera_object * p.cast<double>()).cast<float>(), k, d2);
    sum += d2;
  }
  const double rms = std::sqrt(sum / static_cast<double>(db.objects[0].model_points.size()));
  EXPECT_LT(rms, 0.003) << "RMS " << rms * 1000 << " mm";
}

}  // namespace

}  // namespace viewpose
