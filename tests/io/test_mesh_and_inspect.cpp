#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/inspect.hpp"
#include "viewpose/io/mesh_loader.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {
namespace {

using test::expect_error;

// A 60 x 40 x 150 box as an OBJ in millimetres, the way CAD tools export.
std::string box_obj_mm() {
  const TriangleMesh box = make_box_mesh({60, 40, 150});
  std::string s = "# box\no box\n";
  for (const auto& v : box.vertices) s += fmt::format("v {} {} {}\n", v.x(), v.y(), v.z());
  for (const auto& t : box.triangles) s += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  return s;
}

TEST(MeshLoader, ObjInMillimetresArrivesInMetres) {
  test::TempDir dir;
  write_file_atomic(dir / "box.obj", box_obj_mm());
  const LoadedMesh m = load_mesh(dir / "box.obj", LengthUnit::Millimetres);
  EXPECT_TRUE(m.warnings.empty());
  EXPECT_EQ(m.mesh.triangles.size(), 12u);
  EXPECT_TRUE(bounding_box(m.mesh).size().isApprox(Eigen::Vector3f(0.06f, 0.04f, 0.15f), 1e-6f));
  EXPECT_NEAR(m.mesh.surface_area(), 2 * (0.06 * 0.04 + 0.04 * 0.15 + 0.06 * 0.15), 1e-6);
}

TEST(MeshLoader, WarnsWhenTheSizeLooksLikeTheOtherUnit) {
  test::TempDir dir;
  write_file_atomic(dir / "box.obj", box_obj_mm());
  const LoadedMesh m = load_mesh(dir / "box.obj", LengthUnit::Metres);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("looks like millimetres"), std::string::npos) << m.warnings[0];
}

TEST(MeshLoader, AsciiStlAndPlyLoadTheSameBox) {
  test::TempDir dir;
  const TriangleMesh box = make_box_mesh({0.1f, 0.2f, 0.3f});
  std::string stl = "solid box\n";
  for (const auto& t : box.triangles) {
    stl += "facet normal 0 0 0\nouter loop\n";
    for (auto i : t) stl += fmt::format("vertex {} {} {}\n", box.vertices[i].x(), box.vertices[i].y(), box.vertices[i].z());
    stl += "endloop\nendfacet\n";
  }
  stl += "endsolid box\n";
  write_file_atomic(dir / "box.stl", stl);
  write_ply(dir / "box.ply", box, PlyEncoding::BinaryLittleEndian);
  for (const char* name : {"box.stl", "box.ply"}) {
    const LoadedMesh m = load_mesh(dir / name, LengthUnit::Metres);
    EXPECT_EQ(m.mesh.triangles.size(), 12u) << name;
    EXPECT_NEAR(m.mesh.surface_area(), box.surface_area(), 1e-6) << name;
  }
}

TEST(MeshLoader, UnreadableFilesAreNamed) {
  test::TempDir dir;
  expect_error([&] { load_mesh(dir / "none.obj", LengthUnit::Metres); }, "none.obj: no such file");
  write_file_atomic(dir / "junk.stl", std::string("\x01\x02 this is not a mesh at all", 29));
  EXPECT_THROW(load_mesh(dir / "junk.stl", LengthUnit::Metres), Error);
  write_file_atomic(dir / "points.obj", "v 0 0 0\nv 1 0 0\n");
  EXPECT_THROW(load_mesh(dir / "points.obj", LengthUnit::Metres), Error);
}

TEST(Inspect, EveryFormatIsRecognizedAndCounted) {
  test::TempDir dir;
  const PointCloud organized = test::sample_cloud(16, 12, true, true, false);
  write_pcd(dir / "o.pcd", organized, PcdEncoding::BinaryCompressed);
  write_ply(dir / "m.ply", make_box_mesh({1, 1, 1}), PlyEncoding::Ascii);
  DepthImage d(8, 4);
  d.at(1, 1) = 0.75f;
  d.at(2, 1) = 1.5f;
  write_depth_png(dir / "d.png", d, 0.001);
  write_file_atomic(dir / "camera.json", format_bop_camera({CameraIntrinsics::kinect_v1(), 1.0}));
  write_bop_results(dir / "r.csv", {BopResult{1, 2, 3, 0.5, Transform::Identity(), 0.1}});

  const FileInfo pcd = inspect_file(dir / "o.pcd");
  EXPECT_EQ(pcd.kind, "PCD point cloud (binary_compressed, v0.7)");
  EXPECT_EQ(pcd.points, 192u);
  EXPECT_EQ(pcd.valid_points, organized.count_finite());
  EXPECT_EQ(pcd.height, 12);
  EXPECT_EQ(pcd.fields.size(), 8u);
  EXPECT_TRUE(pcd.problems.empty());

  const FileInfo ply = inspect_file(dir / "m.ply");
  EXPECT_EQ(ply.kind, "PLY mesh (ascii)");
  EXPECT_EQ(ply.faces, 12u);

  const FileInfo png = inspect_file(dir / "d.png");
  EXPECT_EQ(png.valid_points, 2u);
  ASSERT_FALSE(png.notes.empty());
  EXPECT_EQ(png.notes[0], "depth 0.7500 to 1.5000 m at 0.001 m per unit");

  EXPECT_EQ(inspect_file(dir / "camera.json").kind, "BOP camera.json");
  EXPECT_EQ(inspect_file(dir / "r.csv").notes, std::vector<std::string>{"1 estimates over 1 images, 1 objects"});
  write_file_atomic(dir / "x.xyzw", "1 2 3\n");
  expect_error([&] { inspect_file(dir / "x.xyzw"); }, "unknown file type '.xyzw'");
  expect_error([&] { inspect_file(dir.path()); }, "no BOP split");
}

TEST(Inspect, DepthPngWithIntrinsicsReportsThePointsItMakes) {
  test::TempDir dir;
  DepthImage d(8, 4);
  d.at(1, 1) = 0.75f;
  d.at(2, 1) = 1.5f;
  write_depth_png(dir / "d.png", d, 0.001);
  InspectOptions options;
  options.camera = CameraIntrinsics{100, 100, 0, 0, 0, 0};
  const FileInfo info = inspect_file(dir / "d.png", options);
  ASSERT_FALSE(info.bbox.empty);
  EXPECT_EQ(info.bbox_unit, LengthUnit::Metres);
  // (u, v) = (1, 1) at 0.75 m and (2, 1) at 1.5 m: x = u z / 100, y = v z / 100.
  EXPECT_TRUE(info.bbox.min.isApprox(Eigen::Vector3f(0.0075f, 0.0075f, 0.75f), 1e-5f)) << info.bbox.min.transpose();
  EXPECT_TRUE(info.bbox.max.isApprox(Eigen::Vector3f(0.03f, 0.015f, 1.5f), 1e-5f)) << info.bbox.max.transpose();
  options.camera = CameraIntrinsics{100, 100, 0, 0, 640, 480};
  expect_error([&] { inspect_file(dir / "d.png", options); }, "image is 8x4 but the camera is 640x480");
}

TEST(Inspect, EmptyAndNaNOnlyCloudsAreReportedAsProblems) {
  test::TempDir dir;
  write_pcd(dir / "empty.pcd", PointCloud::from_points({}), PcdEncoding::Binary);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  write_pcd(dir / "nan.pcd", PointCloud::from_points({{nan, nan, nan}, {nan, 0, 1}}), PcdEncoding::Ascii);
  EXPECT_EQ(inspect_file(dir / "empty.pcd").problems, std::vector<std::string>{"empty: no points"});
  const FileInfo n = inspect_file(dir / "nan.pcd");
  ASSERT_EQ(n.problems.size(), 1u);
  EXPECT_NE(n.problems[0].find("no valid points"), std::string::npos);
}

}  // namespace
}  // namespace viewpose
