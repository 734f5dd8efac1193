#include <numbers>
#include <sstream>

#include <fmt/ranges.h>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/inspect.hpp"

namespace viewpose {
namespace {

using test::expect_error;

Transform some_pose(double angle, double z) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return make_transform(R, Eigen::Vector3d(0.01 * angle, -0.02, z));
}

TEST(BopJson, CameraRoundTrip) {
  const BopCamera in{{572.4114, 573.57043, 325.2611, 242.04899, 640, 480}, 0.1};
  const BopCamera out = parse_bop_camera(format_bop_camera(in), "camera.json");
  EXPECT_EQ(out.K.fx, in.K.fx);
  EXPECT_EQ(out.K.cy, in.K.cy);
  EXPECT_EQ(out.K.width, 640);
  EXPECT_EQ(out.depth_scale_mm, 0.1);
}

TEST(BopJson, SceneFilesRoundTripInMetres) {
  SceneCameras cams;
  cams[0] = {{500, 501, 320, 240, 0, 0}, 1.0};
  cams[7] = {{510, 511, 321, 241, 0, 0}, 0.1};
  const SceneCameras cams_out = parse_scene_camera(format_scene_camera(cams), "scene_camera.json");
  ASSERT_EQ(cams_out.size(), 2u);
  EXPECT_EQ(cams_out.at(7).K.fy, 511);
  EXPECT_EQ(cams_out.at(7).depth_scale_mm, 0.1);

  SceneGroundTruth gt;
  gt[0] = {{5, some_pose(0.3, 0.9)}, {12, some_pose(2.0, 1.4)}};
  gt[7] = {};
  const SceneGroundTruth gt_out = parse_scene_gt(format_scene_gt(gt), "scene_gt.json");
  ASSERT_EQ(gt_out.at(0).size(), 2u);
  EXPECT_EQ(gt_out.at(0)[1].obj_id, 12);
  EXPECT_TRUE(gt_out.at(0)[1].T_camera_object.isApprox(gt[0][1].T_camera_object, 1e-12));
  EXPECT_TRUE(gt_out.at(7).empty());

  SceneGroundTruthInfo info;
  info[0] = {GroundTruthInfo{0.75, 100, 90, 75, {1, 2, 3, 4}, {2, 3, 4, 5}}, GroundTruthInfo{}};
  const auto info_out = parse_scene_gt_info(format_scene_gt_info(info), "scene_gt_info.json");
  EXPECT_EQ(info_out.at(0)[0].visib_fract, 0.75);
  EXPECT_EQ(info_out.at(0)[0].px_count_visib, 75);
  EXPECT_EQ(info_out.at(0)[0].bbox_visib, (std::array<int, 4>{2, 3, 4, 5}));
}

TEST(BopJson, ModelsInfoWithSymmetriesRoundTrip) {
  ModelsInfo models;
  ModelInfo& m = models[3];
  m.diameter_m = 0.172063;
  m.min_m = {-0.05, -0.05, -0.07};
  m.size_m = {0.1, 0.1, 0.14};
  m.symmetries_discrete.push_back(make_transform(
      Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {0, 0, 0.002}));
  m.symmetries_continuous.push_back({Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()});
  const ModelsInfo out = parse_models_info(format_models_info(models), "models_info.json");
  const ModelInfo& o = out.at(3);
  EXPECT_NEAR(o.diameter_m, 0.172063, 1e-12);
  EXPECT_TRUE(o.size_m.isApprox(m.size_m));
  ASSERT_EQ(o.symmetries_discrete.size(), 1u);
  EXPECT_TRUE(o.symmetries_discrete[0].isApprox(m.symmetries_discrete[0], 1e-9));
  ASSERT_EQ(o.symmetries_continuous.size(), 1u);
}

TEST(BopJson, MalformedFilesAreNamedWithTheEntry) {
  expect_error([] { parse_scene_gt("{\"1\": [", "scene_gt.json"); }, "scene_gt.json: invalid JSON");
  expect_error([] { parse_scene_gt("{\"1\": [{\"cam_R_m2c\": [1,0,0,0,1,0,0,0,1], \"obj_id\": 3}]}", "g.json"); },
               "g.json: image 1, object 0: 'cam_t_m2c' is missing");
  expect_error([] { parse_scene_gt("{\"1\": [{\"cam_R_m2c\": [2,0,0,0,1,0,0,0,1], \"cam_t_m2c\": [0,0,1], \"obj_id\": 3}]}", "g.json"); },
               "not a rotation matrix");
  expect_error([] { parse_scene_gt("{\"x\": []}", "g.json"); }, "key 'x' is not an id");
  expect_error([] { parse_scene_camera("{\"0\": {\"cam_K\": [1,2,3]}}", "c.json"); }, "'cam_K' must be 9 numbers");
  expect_error([] { parse_scene_camera("{\"0\": {\"cam_K\": [0,0,1,0,0,1,0,0,1]}}", "c.json"); }, "non-positive focal");
  expect_error([] { parse_bop_camera("{\"fx\": 1, \"fy\": 1, \"cx\": 1, \"cy\": 1, \"width\": -5, \"height\": 2}", "cam.json"); },
               "cam.json: ");
  expect_error([] { parse_models_info("{\"1\": {\"diameter\": -3}}", "m.json"); }, "diameter must be positive");
  expect_error([] { parse_scene_gt_info("{\"1\": [{\"visib_fract\": 1.5}]}", "i.json"); }, "not in 0..1");
}

// A scene_gt.json entry with the rotation's nine numbers as given.
std::string gt_entry(const Eigen::Matrix3d& R, int image = 0) {
  return fmt::format("{{\"{}\": [{{\"cam_R_m2c\": [{}], \"cam_t_m2c\": [0, 0, 800], \"obj_id\": 8}}]}}", image,
                     fmt::join(std::vector<double>{R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1),
                                                   R(2, 2)}, ", "));
}

// LM-O's published ground truth (scene 2, image 3, the driller) is off orthonormal by up to 2e-3;
// such a rotation is taken as its nearest and said once per file. A reflection, a scaled or a
// sheared matrix is refused, naming the entry; so in the results CSV.
TEST(BopJson, RoundedRotationsAreTakenAndSaidOncePerFile) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, 1, -0.2).normalized()).toRotationMatrix();
  Eigen::Matrix3d off = R;
  off(0, 0) += 1.5e-3;
  off(2, 1) -= 2e-3;
  std::vector<std::string> notes;
  const SceneGroundTruth gt = parse_scene_gt(gt_entry(off), "scene_gt.json", &notes);
  const Eigen::Matrix3d taken = gt.at(0)[0].T_camera_object.linear();
  EXPECT_TRUE(is_rotation(taken, 1e-12));
  EXPECT_LT(rotation_difference_deg(taken, R), 0.2);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("scene_gt.json: 1 rotation is off orthonormal by up to"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("image 0, object 0"), std::string::npos) << notes[0];

  // Six digits, as BOP writes them: silent.
  notes.clear();
  const Eigen::Matrix3d six = (R * 1e6).array().round() / 1e6;
  (void)parse_scene_gt(gt_entry(six), "scene_gt.json", &notes);
  EXPECT_TRUE(notes.empty());

  Eigen::Matrix3d mirrored = R;
  mirrored.row(1) *= -1;
  expect_error([&] { parse_scene_gt(gt_entry(mirrored), "scene_gt.json"); },
               "scene_gt.json: image 0, object 0: 'cam_R_m2c' is a reflection");
  expect_error([&] { parse_scene_gt(gt_entry(1.02 * R), "scene_gt.json"); }, "is scaled or sheared");
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(1, 2) = 0.05;
  expect_error([&] { parse_scene_gt(gt_entry(R * shear), "scene_gt.json"); }, "is scaled or sheared");

  const auto row = [](const Eigen::Matrix3d& M) {
    return fmt::format("scene_id,im_id,obj_id,score,R,t,time\n2,3,8,0.9,{},1 2 800,0.5\n",
                       fmt::join(std::vector<double>{M(0, 0), M(0, 1), M(0, 2), M(1, 0), M(1, 1), M(1, 2), M(2, 0), M(2, 1),
                                                     M(2, 2)}, " "));
  };
  notes.clear();
  const auto results = parse_bop_results(row(off), "r.csv", &notes);
  EXPECT_TRUE(is_rotation(results.at(0).T_camera_object.linear(), 1e-12));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("line 2"), std::string::npos) << notes[0];
  expect_error([&] { parse_bop_results(row(mirrored), "r.csv"); }, "r.csv: line 2: R is a reflection");
  expect_error([&] { parse_bop_results(row(0.9 * R), "r.csv"); }, "r.csv: line 2: R is not a rotation matrix");
}

TEST(BopJson, TargetsListObjectsAndCountsPerImage) {
  const auto targets = parse_bop_targets(R"([{"im_id": 3, "inst_count": 1, "obj_id": 8, "scene_id": 2},
      {"im_id": 3, "inst_count": 2, "obj_id": 1, "scene_id": 2}, {"im_id": 0, "inst_count": 1, "obj_id": 5, "scene_id": 2}])",
                                         "t.json");
  ASSERT_EQ(targets.size(), 3u);
  EXPECT_EQ(targets[0], (BopTarget{2, 0, 5, 1}));  // sorted by scene, image, object
  EXPECT_EQ(targets[1], (BopTarget{2, 3, 1, 2}));
  EXPECT_EQ(targets[2], (BopTarget{2, 3, 8, 1}));
  expect_error([] { parse_bop_targets("{}", "t.json"); }, "t.json: expected a list of targets");
  expect_error([] { parse_bop_targets(R"([{"im_id": 3, "obj_id": 8, "scene_id": 2}])", "t.json"); },
               "t.json: target 0: 'inst_count' is missing");
  expect_error([] { parse_bop_targets(R"([{"im_id": 3, "inst_count": 0, "obj_id": 8, "scene_id": 2}])", "t.json"); },
               "inst_count 0 is below 1");
  expect_error([] { parse_bop_targets(R"([{"im_id": 3, "inst_count": 1, "obj_id": 8, "scene_id": 2},
                                          {"im_id": 3, "inst_count": 2, "obj_id": 8, "scene_id": 2}])", "t.json"); },
               "object 8 is listed twice for scene 2, image 3");
}

// A small dataset on disk: camera.json, a test split with one scene of two images.
struct SmallDataset {
  test::TempDir dir;
  SmallDataset() {
    const auto root = dir.path();
    std::filesystem::create_directories(root / "test" / "000003" / "depth");
    std::filesystem::create_directories(root / "models");
    write_file_atomic(root / "camera.json", format_bop_camera({{600, 600, 31.5, 23.5, 64, 48}, 0.1}));
    ModelsInfo models;
    models[5].diameter_m = 0.1;
    write_file_atomic(root / "models" / "models_info.json", format_models_info(models));
    write_file_atomic(root / "models" / "obj_000005.ply", "ply");
    SceneCameras cams;
    cams[0] = cams[1] = {{600, 600, 31.5, 23.5, 0, 0}, 0.1};
    write_file_atomic(root / "test" / "000003" / "scene_camera.json", format_scene_camera(cams));
    SceneGroundTruth gt;
    gt[0] = {{5, some_pose(0.5, 1.0)}};
    gt[1] = {};
    write_file_atomic(root / "test" / "000003" / "scene_gt.json", format_scene_gt(gt));
    DepthImage d(64, 48);
    for (float& z : d.depth_m) z = 1.25f;
    for (int im : {0, 1}) write_depth_png(root / "test" / "000003" / "depth" / fmt::format("{:06d}.png", im), d, 0.0001);
  }
};

TEST(BopDatasetTest, OpensASplitAndLoadsFramesInMetres) {
  SmallDataset s;
  const BopDataset ds = open_bop_dataset(s.dir.path(), "test");
  ASSERT_TRUE(ds.camera.has_value());
  EXPECT_EQ(ds.models.size(), 1u);
  EXPECT_EQ(ds.model_files.count(5), 1u);
  ASSERT_EQ(ds.images.size(), 2u);
  EXPECT_EQ(ds.images[0].scene_id, 3);
  EXPECT_EQ(ds.images[1].im_id, 1);
  ASSERT_EQ(ds.images[0].gt.size(), 1u);
  EXPECT_NEAR(ds.images[0].gt[0].T_camera_object.translation().z(), 1.0, 1e-12);
  const BopFrame f = load_bop_frame(ds.images[0]);
  EXPECT_EQ(f.K.width, 64);
  EXPECT_EQ(f.depth.count_valid(), 64u * 48u);
  EXPECT_NEAR(f.depth.at(10, 10), 1.25f, 1e-6);  // depth_scale 0.1 mm per unit honoured
}

TEST(BopDatasetTest, MissingOrInconsistentPiecesAreNamed) {
  SmallDataset s;
  expect_error([&] { open_bop_dataset(s.dir.path(), "val"); }, "no split 'val'");
  std::filesystem::remove(s.dir.path() / "test" / "000003" / "depth" / "000001.png");
  expect_error([&] { open_bop_dataset(s.dir.path(), "test"); }, "no depth image for image 1");
  SmallDataset t;
  SceneGroundTruthInfo info;
  info[0] = {GroundTruthInfo{}, GroundTruthInfo{}};  // two entries for one pose
  write_file_atomic(t.dir.path() / "test" / "000003" / "scene_gt_info.json", format_scene_gt_info(info));
  expect_error([&] { open_bop_dataset(t.dir.path(), "test"); }, "image 0 lists 2 objects but scene_gt.json lists 1");
  SmallDataset u;
  write_file_atomic(u.dir.path() / "camera.json", format_bop_camera({{600, 600, 31.5, 23.5, 640, 480}, 0.1}));
  const BopDataset ds = open_bop_dataset(u.dir.path(), "test");
  expect_error([&] { load_bop_frame(ds.images[0]); }, "image is 64x48 but camera.json says 640x480");
}

// T-LESS / HB / LM-O as published: typed split folders (test_primesense, train_pbr), no models/ but
// models_cad/ and models_eval/, the sensor's camera file, the BOP19 targets, a rotation off
// orthonormal by LM-O's 2e-3.
struct PublishedLayout {
  test::TempDir dir;
  PublishedLayout() {
    const auto root = dir.path();
    for (const char* split : {"test_primesense", "train_pbr"}) {
      const auto scene = root / split / "000002";
      std::filesystem::create_directories(scene / "depth");
      SceneCameras cams;
      cams[3] = {{1075.65, 1073.90, 31.5, 23.5, 0, 0}, 0.1};
      write_file_atomic(scene / "scene_camera.json", format_scene_camera(cams));
      DepthImage d(64, 48);
      for (float& z : d.depth_m) z = 0.9f;
      write_depth_png(scene / "depth" / "000003.png", d, 0.0001);
    }
    Eigen::Matrix3d off = some_pose(0.8, 1.0).linear();
    off(1, 2) += 2e-3;
    write_file_atomic(root / "test_primesense" / "000002" / "scene_gt.json", gt_entry(off, 3));
    write_file_atomic(root / "camera_primesense.json", format_bop_camera({{1075.65, 1073.90, 31.5, 23.5, 64, 48}, 0.1}));
    write_file_atomic(root / "camera_kinect.json", format_bop_camera({{1076, 1074, 31.5, 23.5, 720, 540}, 0.1}));
    ModelsInfo models;
    models[8].diameter_m = 0.26;
    for (const char* folder : {"models_cad", "models_eval"}) {
      std::filesystem::create_directories(root / folder);
      write_file_atomic(root / folder / "models_info.json", format_models_info(models));
      write_file_atomic(root / folder / "obj_000008.ply", "ply");
    }
    write_file_atomic(root / "test_targets_bop19.json", R"([{"im_id": 3, "inst_count": 1, "obj_id": 8, "scene_id": 2}])");
  }
};

TEST(BopDatasetTest, PublishedLayoutsAreFoundByName) {
  PublishedLayout p;
  const BopLayout layout = scan_bop_layout(p.dir.path());
  ASSERT_EQ(layout.splits.size(), 2u);
  EXPECT_EQ(layout.splits[0].folder, "test_primesense");
  EXPECT_EQ(layout.splits[0].split, "test");
  EXPECT_EQ(layout.splits[0].type, "primesense");
  EXPECT_EQ(layout.splits[1].type, "pbr");
  EXPECT_EQ(layout.model_folders, (std::vector<std::string>{"models_cad", "models_eval"}));
  EXPECT_EQ(layout.camera_files, (std::vector<std::string>{"camera_kinect.json", "camera_primesense.json"}));
  EXPECT_EQ(layout.target_files, (std::vector<std::string>{"test_targets_bop19.json"}));
  EXPECT_EQ(resolve_models_folder(layout), "models_cad");
  EXPECT_EQ(resolve_models_folder(layout, "models_eval"), "models_eval");

  // "test" means the one test folder; its sensor's camera gives the image size.
  const BopDataset ds = open_bop_dataset(p.dir.path(), "test");
  EXPECT_EQ(ds.split, "test_primesense");
  EXPECT_EQ(ds.models_dir, "models_cad");
  EXPECT_EQ(ds.eval_models_dir, "models_eval");
  ASSERT_TRUE(ds.camera.has_value());
  EXPECT_EQ(ds.camera->K.width, 64);
  EXPECT_EQ(ds.models.count(8), 1u);
  ASSERT_EQ(ds.images.size(), 1u);
  ASSERT_EQ(ds.images[0].gt.size(), 1u);
  EXPECT_TRUE(is_rotation(ds.images[0].gt[0].T_camera_object.linear(), 1e-12));
  ASSERT_EQ(ds.notes.size(), 1u);
  EXPECT_NE(ds.notes[0].find("scene_gt.json: 1 rotation is off orthonormal"), std::string::npos) << ds.notes[0];
  EXPECT_NEAR(load_bop_frame(ds.images[0]).depth.at(5, 5), 0.9f, 1e-6);
  EXPECT_EQ(open_bop_dataset(p.dir.path(), "train_pbr").images.size(), 1u);

  // A second test folder: "test" is ambiguous, and the message lists both.
  std::filesystem::create_directories(p.dir.path() / "test_kinect");
  std::filesystem::copy(p.dir.path() / "test_primesense" / "000002", p.dir.path() / "test_kinect" / "000002",
                        std::filesystem::copy_options::recursive);
  expect_error([&] { open_bop_dataset(p.dir.path(), "test"); }, "2 'test' splits (test_kinect, test_primesense)");
  expect_error([&] { open_bop_dataset(p.dir.path(), "val"); }, "no split 'val' in the dataset (its splits: test_kinect");
  // ITODD keeps its depth as TIFF: said, not "missing".
  const auto scene = p.dir.path() / "train_pbr" / "000002" / "depth";
  std::filesystem::rename(scene / "000003.png", scene / "000003.tif");
  expect_error([&] { open_bop_dataset(p.dir.path(), "train_pbr"); }, "depth is a TIFF");
}

TEST(BopDatasetTest, InfoSaysWhatAPublishedLayoutHolds) {
  PublishedLayout p;
  const FileInfo info = inspect_file(p.dir.path());
  EXPECT_EQ(info.kind, "BOP dataset folder");
  std::string all;
  for (const auto& n : info.notes) all += n + "\n";
  for (const char* expected : {"split 'test_primesense' (test, primesense): 1 scenes, 1 images, 1 ground-truth poses of 1 objects",
                               "split 'train_pbr' (train, pbr)", "64 x 48",
                               "models_cad/: 1 meshes, models_info.json with 1 objects, 0 of them symmetric (used for recognition's default)",
                               "models_eval/: 1 meshes, models_info.json with 1 objects, 0 of them symmetric (used for scoring)",
                               "cameras: camera_kinect.json, camera_primesense.json",
                               "targets: test_targets_bop19.json: 1 instances of 1 objects to find in 1 images",
                               "note: ", "rotation is off orthonormal"}) {
    EXPECT_NE(all.find(expected), std::string::npos) << expected << " not in:\n" << all;
  }
  EXPECT_TRUE(info.problems.empty());
}

TEST(BopResults, CsvRoundTripIsExact) {
  std::vector<BopResult> in = {{1, 2, 5, 0.93, some_pose(0.4, 0.8), 0.012}, {1, 3, 12, 0.5, some_pose(3.0, 1.5), -1}};
  test::TempDir dir;
  write_bop_results(dir / "r.csv", in);
  const auto out = read_bop_results(dir / "r.csv");
  ASSERT_EQ(out.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(out[i].scene_id, in[i].scene_id);
    EXPECT_EQ(out[i].im_id, in[i].im_id);
    EXPECT_EQ(out[i].obj_id, in[i].obj_id);
    EXPECT_EQ(out[i].score, in[i].score);
    EXPECT_EQ(out[i].time_s, in[i].time_s);
    EXPECT_TRUE(out[i].T_camera_object.isApprox(in[i].T_camera_object, 1e-15));
  }
  // Translations are written in millimetres, as BOP wants: the t column of the first row.
  const std::string text = format_bop_results(in);
  const std::string row = text.substr(text.find('\n') + 1, text.find('\n', text.find('\n') + 1) - text.find('\n') - 1);
  std::vector<std::string> cols;
  for (std::size_t a = 0, b; a <= row.size(); a = b + 1) {
    b = row.find(',', a);
    if (b == std::string::npos) b = row.size();
    cols.push_back(row.substr(a, b - a));
  }
  ASSERT_EQ(cols.size(), 7u);
  std::istringstream t_mm(cols[5]);
  Eigen::Vector3d t;
  t_mm >> t.x() >> t.y() >> t.z();
  EXPECT_TRUE(t.isApprox(in[0].T_camera_object.translation() * 1000.0, 1e-12)) << cols[5];
}

TEST(BopResults, MalformedLinesAreNamed) {
  const std::string head = "scene_id,im_id,obj_id,score,R,t,time\n";
  expect_error([] { parse_bop_results("a,b,c\n", "r.csv"); }, "r.csv: not a BOP results file");
  expect_error([&] { parse_bop_results(head + "1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0 1\n", "r.csv"); }, "line 2: 6 columns");
  expect_error([&] { parse_bop_results(head + "1,2,3,0.5,1 0 0 0 1 0 0 0,0 0 1,1\n", "r.csv"); }, "R must be 9 numbers");
  expect_error([&] { parse_bop_results(head + "1,2,3,0.5,3 0 0 0 1 0 0 0 1,0 0 1,1\n", "r.csv"); }, "not a rotation");
  expect_error([&] { parse_bop_results(head + "1,x,3,0.5,1 0 0 0 1 0 0 0 1,0 0 1,1\n", "r.csv"); }, "whole numbers");
}

}  // namespace
}  // namespace viewpose
