// `viewpose demo`: the main job on data the program makes itself. While the pipeline is being built
// it runs the stages that exist and says plainly which do not exist yet; it never fakes a result.
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "commands.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/io/file.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

namespace {

// A frame seen by a Kinect v1 at its nominal intrinsics: a wall 1.5 m away and a ball of 8 cm
// radius 1 m in front of the camera, ray-cast exactly. It stands in until the renderer (issue 3).
DepthImage analytic_scene(const CameraIntrinsics& K) {
  DepthImage depth(K.width, K.height);
  const Eigen::Vector3d centre(0.05, 0.0, 1.0);
  const double radius = 0.08, wall_z = 1.5;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray = K.unproject(u, v, 1.0);  // z = 1, so the ray parameter is the depth
      const double a = ray.squaredNorm(), b = -2.0 * ray.dot(centre), c = centre.squaredNorm() - radius * radius;
      const double disc = b * b - 4 * a * c;
      const double z = disc >= 0 ? (-b - std::sqrt(disc)) / (2 * a) : wall_z;
      depth.at(u, v) = static_cast<float>(z);
    }
  }
  return depth;
}

}  // namespace

void add_demo_command(CLI::App& app, int& exit_code) {
  auto out_dir = std::make_shared<std::string>("demo-out");
  CLI::App* cmd = app.add_subcommand("demo", "Run the pipeline on data viewpose makes itself, and say what it did");
  cmd->add_option("--out", *out_dir, "Folder for the files the demo writes")->capture_default_str();
  cmd->callback([out_dir, &exit_code] {
    using Clock = std::chrono::steady_clock;
    const fs::path dir = *out_dir;
    fs::create_directories(dir);
    const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
    fmt::print("viewpose demo: writes and reads back every file format, in {}\n\n", dir.string());

    const DepthImage depth = analytic_scene(K);
    const PointCloud cloud = depth_to_cloud(depth, K);
    write_file_atomic(dir / "camera.json", format_bop_camera(BopCamera{K, 1.0}));
    write_depth_png(dir / "scene_depth.png", depth, 0.001);
    write_pcd(dir / "scene_ascii.pcd", cloud, PcdEncoding::Ascii);
    write_pcd(dir / "scene_binary.pcd", cloud, PcdEncoding::Binary);
    write_pcd(dir / "scene_compressed.pcd", cloud, PcdEncoding::BinaryCompressed);
    write_ply(dir / "scene.ply", cloud, PlyEncoding::BinaryLittleEndian);
    TriangleMesh box = make_box_mesh({60.0f, 40.0f, 150.0f});  // a carton, in millimetres as CAD exports it
    write_ply(dir / "box_mm.ply", box, PlyEncoding::Ascii);

    for (const char* file : {"camera.json", "scene_depth.png", "scene_ascii.pcd", "scene_binary.pcd",
                             "scene_compressed.pcd", "scene.ply", "box_mm.ply"}) {
      const auto start = Clock::now();
      const FileInfo info = inspect_file(dir / file);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      print_file_info(dir / file, info);
      fmt::print("  read in:      {:.1f} ms\n\n", ms);
    }
    fmt::print(
        "Built so far: camera model, depth-to-cloud, and the PCD / PLY / mesh / depth PNG / BOP readers and writers.\n"
        "Not built yet, so no object is recognized and no pose is printed:\n"
        "  - rendering of CAD models and the Kinect sensor model (issue 3)\n"
        "  - segmentation, normals, VFH and CRH descriptors, the view database (issue 4)\n"
        "  - pose estimation, ICP and verification (issue 5)\n");
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
