// Readers against real captures and meshes in ../shared/data (see its MANIFEST.md), cross-checked
// against facts stated elsewhere: other files describing the same data, the dataset's own notes.
#include <algorithm>
#include <cmath>
#include <set>

#include "test_support.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/mesh_loader.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {
namespace {

namespace fs = std::filesystem;
using test::shared_data;

std::vector<fs::path> pcd_files() {
  std::vector<fs::path> files;
  for (const char* dir : {"pcl_kinect", "pcl_kinect/grabber_sequences/pcd", "pcl_kinect/alignment_prerejective", "pcl_mosd/test"}) {
    if (!fs::is_directory(shared_data() / dir)) continue;
    for (const auto& e : fs::directory_iterator(shared_data() / dir)) {
      if (e.path().extension() == ".pcd") files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(RealData, EveryPcdMatchesItsHeaderAndLiesInFrontOfTheCamera) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const auto files = pcd_files();
  ASSERT_GE(files.size(), 20u);
  for (const auto& path : files) {
    SCOPED_TRACE(path.string());
    const PcdFile f = read_pcd(path);
    EXPECT_EQ(f.cloud.size(), f.header.points);
    EXPECT_EQ(static_cast<std::size_t>(f.header.width) * static_cast<std::size_t>(f.header.height), f.header.points);
    const bool frame = f.header.height > 1;
    if (frame) {
      EXPECT_EQ(f.cloud.width, 640);
      EXPECT_EQ(f.cloud.height, 480);
      EXPECT_LT(f.cloud.count_finite(), f.cloud.size()) << "a real Kinect frame has holes";
      EXPECT_GT(f.cloud.count_finite(), f.cloud.size() / 3);
    }
    const BoundingBox box = bounding_box(f.cloud.points);
    ASSERT_FALSE(box.empty);
    EXPECT_LT(box.diagonal(), 20.0f) << "metres expected";
    if (frame) {
      EXPECT_GT(box.min.z(), 0.3f) << "a Kinect sees nothing closer than about 0.4 m";
    }
  }
}

TEST(RealData, MosdLabelZeroMarksExactlyTheMissingPoints) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  for (const char* name : {"test0.pcd", "test25.pcd", "test60.pcd"}) {
    SCOPED_TRACE(name);
    const PcdFile f = read_pcd(shared_data() / "pcl_mosd/test" / name);
    ASSERT_EQ(f.cloud.labels.size(), f.cloud.size());
    ASSERT_EQ(f.cloud.rgba.size(), f.cloud.size());
    std::size_t label0 = 0, objects = 0, mismatched = 0;
    for (std::size_t i = 0; i < f.cloud.size(); ++i) {
      const bool missing = !f.cloud.points[i].allFinite();
      label0 += f.cloud.labels[i] == 0 ? 1 : 0;
      objects += f.cloud.labels[i] >= 20 ? 1 : 0;
      mismatched += (missing != (f.cloud.labels[i] == 0)) ? 1 : 0;
    }
    EXPECT_EQ(mismatched, 0u) << "the README says label 0 = NaN";
    EXPECT_GT(label0, 0u) << "a real frame has pixels without depth";
    EXPECT_GT(objects, 1000u);
  }
}

TEST(RealData, MilkAndMilkColourHoldTheSamePoints) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const PcdFile xyz = read_pcd(shared_data() / "pcl_kinect/milk.pcd");
  const PcdFile colour = read_pcd(shared_data() / "pcl_kinect/milk_color.pcd");
  EXPECT_EQ(xyz.cloud.size(), 13704u);
  EXPECT_EQ(xyz.cloud.count_finite(), 13704u);
  EXPECT_TRUE(test::same_bits(xyz.cloud.points, colour.cloud.points));
  EXPECT_EQ(colour.cloud.rgba.size(), 13704u);
}

TEST(RealData, PclFixtureCloudHasUnitNormalsAndValidCurvature) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const PcdFile f = read_pcd(test::shared_dir() / "reference/pcl-fixtures/cloud_3mm_normals.pcd");
  EXPECT_EQ(f.header.encoding, PcdEncoding::Ascii);
  ASSERT_EQ(f.cloud.size(), 5860u);  // README.txt: 5860 points
  ASSERT_EQ(f.cloud.normals.size(), 5860u);
  ASSERT_EQ(f.cloud.curvature.size(), 5860u);
  for (std::size_t i = 0; i < f.cloud.size(); ++i) {
    ASSERT_NEAR(f.cloud.normals[i].norm(), 1.0f, 1e-3f) << i;
    ASSERT_GE(f.cloud.curvature[i], 0.0f);
    ASSERT_LE(f.cloud.curvature[i], 1.0f / 3.0f + 1e-5f);  // lambda0 / sum of lambdas
  }
}

TEST(RealData, RealFramesSurviveReencodingBitForBit) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const PcdFile f = read_pcd(shared_data() / "pcl_kinect/milk_cartoon_all_small_clorox.pcd");
  for (const auto encoding : {PcdEncoding::Ascii, PcdEncoding::Binary, PcdEncoding::BinaryCompressed}) {
    test::expect_same_cloud(f.cloud, parse_pcd(encode_pcd(f.cloud, encoding), "re").cloud);
  }
}

TEST(RealData, XtionDepthHasTheValidPixelsAndMedianTheManifestStates) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  // MANIFEST: 640x480, 1e-4 m per unit, about 276 k valid pixels, median about 0.63 m.
  const DepthImage d = read_depth_png(shared_data() / "ycbv_real_sample/data/0000/000001-depth.png", 0.0001);
  ASSERT_EQ(d.width, 640);
  ASSERT_EQ(d.height, 480);
  EXPECT_NEAR(static_cast<double>(d.count_valid()), 276000.0, 6000.0);
  std::vector<float> z;
  for (float v : d.depth_m) if (std::isfinite(v)) z.push_back(v);
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  EXPECT_NEAR(z[z.size() / 2], 0.63, 0.03);
}

TEST(RealData, YcbvSampleOpensAsABopSplitAndGroundTruthAgreesWithDepth) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  const BopDataset ds = open_bop_dataset(shared_data() / "ycbv_real_sample", "data", {"models_bop_ycbv"});
  ASSERT_EQ(ds.images.size(), 2u);
  EXPECT_EQ(ds.models.size(), 21u);
  EXPECT_EQ(ds.model_files.size(), 6u);
  for (const BopImage& im : ds.images) {
    std::set<int> ids;
    for (const auto& g : im.gt) ids.insert(g.obj_id);
    EXPECT_EQ(ids, (std::set<int>{8, 14, 21}));
    const BopFrame frame = load_bop_frame(im);
    EXPECT_EQ(frame.K.width, 640);
    for (const GroundTruthPose& g : im.gt) {
      SCOPED_TRACE(g.obj_id);
      // The object's centre projects into the image, and the surface seen there lies in front of
      // the centre by less than the object's radius.
      const Eigen::Vector3d c = g.T_camera_object.translation();
      const Eigen::Vector2d uv = frame.K.project(c);
      ASSERT_TRUE(frame.K.contains(uv.x(), uv.y()));
      const float z = frame.depth.at(static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y())));
      ASSERT_TRUE(std::isfinite(z));
      EXPECT_LT(z, c.z() + 0.01);
      EXPECT_GT(z, c.z() - 0.5 * ds.models.at(g.obj_id).diameter_m);
    }
  }
}

TEST(RealData, BopMeshesMatchTheirModelsInfo) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  for (const char* dir : {"hope_models", "ycbv_real_sample/models_bop_ycbv"}) {
    const auto info_text = read_file_bytes(shared_data() / dir / "models_info.json");
    const ModelsInfo models = parse_models_info(std::string(info_text.begin(), info_text.end()), "models_info.json");
    int checked = 0;
    for (const auto& [id, m] : models) {
      const fs::path path = shared_data() / dir / fmt::format("obj_{:06d}.ply", id);
      if (!fs::exists(path)) continue;
      SCOPED_TRACE(path.string());
      const PlyFile ply = read_ply(path);
      ASSERT_TRUE(ply.has_faces());
      ply.mesh.check_consistent();
      const BoundingBox b = bounding_box(ply.mesh);  // millimetres, as BOP stores them
      EXPECT_TRUE((b.size().cast<double>() / 1000.0).isApprox(m.size_m, 1e-3)) << b.size().transpose();
      EXPECT_NEAR(b.min.x() / 1000.0, m.min_m.x(), 1e-4);
      ++checked;
    }
    EXPECT_GE(checked, 6) << dir;
  }
}

TEST(RealData, AssimpReadsTheStlObjAndPlyMeshesInTheirUnits) {
  VIEWPOSE_REQUIRE_SHARED_DATA();
  // MANIFEST: the ORK coke can is about 6.8 cm across and 12 cm tall, in metres.
  const LoadedMesh coke = load_mesh(shared_data() / "ork_models/coke.stl", LengthUnit::Metres);
  EXPECT_TRUE(coke.warnings.empty());
  const Eigen::Vector3f s = bounding_box(coke.mesh).size();
  EXPECT_NEAR(s.x(), 0.068, 0.002);
  EXPECT_NEAR(s.z(), 0.12, 0.005);
  const LoadedMesh sugar = load_mesh(shared_data() / "ycb_meshes/drake_original/004_sugar_box_textured.obj", LengthUnit::Metres);
  EXPECT_TRUE(sugar.warnings.empty());
  EXPECT_GT(sugar.mesh.triangles.size(), 1000u);
  // The same BOP mesh through assimp and through our own PLY reader.
  const fs::path soup = shared_data() / "hope_models/obj_000001.ply";
  const LoadedMesh by_assimp = load_mesh(soup, LengthUnit::Millimetres);
  const PlyFile by_us = read_ply(soup);
  EXPECT_NEAR(by_assimp.mesh.surface_area() * 1e6, by_us.mesh.surface_area(), 1e-3 * by_us.mesh.surface_area());
  const LoadedMesh wrong_unit = load_mesh(soup, LengthUnit::Metres);
  ASSERT_EQ(wrong_unit.warnings.size(), 1u);
}

}  // namespace
}  // namespace viewpose
