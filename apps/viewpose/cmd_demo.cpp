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
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

void add_demo_command(CLI::App& app, int& exit_code) {
  auto out_dir = std::make_shared<std::string>("demo-out");
  CLI::App* cmd = app.add_subcommand("demo", "Run the pipeline on data viewpose makes itself, and say what it did");
  cmd->add_option("--out", *out_dir, "Folder for the files the demo writes")->capture_default_str();
  cmd->callback([out_dir, &exit_code] {
    using Clock = std::chrono::steady_clock;
    const fs::path dir = *out_dir;
    fs::create_directories(dir);
    const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
    fmt::print("viewpose demo: a simulated Kinect frame of the detergent jug, in every file format, in {}\n\n",
               dir.string());

    // The thesis's set-up: the jug on a table, its nearest surface 1 m from a Kinect v1.
    auto t0 = Clock::now();
    SeedExperimentOptions setup;
    setup.distances_m = {1.0};
    setup.orientations = 1;
    const SimDataset scene = make_seed_experiment(SimObject{1, "jug", make_jug()}, K, setup, 1);
    const SimulatedFrame frame = simulate_image(scene, scene.scenes[0].images[0], SensorModel::kinect_v1(), 1);
    const double simulate_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    const DepthImage& depth = frame.depth;
    const PointCloud cloud = depth_to_cloud(depth, K);
    const Transform& T = frame.gt[0].T_camera_object;
    const Eigen::AngleAxisd rotation(T.linear());
    fmt::print("rendered and passed through the sensor model in {:.1f} ms; {} of {} pixels have depth\n", simulate_ms,
               depth.count_valid(), depth.depth_m.size());
    fmt::print("ground truth T_camera_object of the jug: t = ({:.3f}, {:.3f}, {:.3f}) m, rotation {:.1f} deg about "
               "({:.3f}, {:.3f}, {:.3f}), {:.0f}% visible\n\n",
               T.translation().x(), T.translation().y(), T.translation().z(), rotation.angle() * 180.0 / 3.14159265358979,
               rotation.axis().x(), rotation.axis().y(), rotation.axis().z(), 100.0 * frame.gt_info[0].visib_fract);
    write_file_atomic(dir / "camera.json", format_bop_camera(BopCamera{K, 1.0}));
    write_depth_png(dir / "scene_depth.png", depth, 0.001);
    write_pcd(dir / "scene_ascii.pcd", cloud, PcdEncoding::Ascii);
    write_pcd(dir / "scene_binary.pcd", cloud, PcdEncoding::Binary);
    write_pcd(dir / "scene_compressed.pcd", cloud, PcdEncoding::BinaryCompressed);
    write_ply(dir / "scene.ply", cloud, PlyEncoding::BinaryLittleEndian);
    TriangleMesh jug_mm = make_jug();  // the model, in millimetres as CAD exports it
    for (auto& v : jug_mm.vertices) v *= 1000.0f;
    write_ply(dir / "jug_mm.ply", jug_mm, PlyEncoding::BinaryLittleEndian);

    for (const char* file : {"camera.json", "scene_depth.png", "scene_ascii.pcd", "scene_binary.pcd",
                             "scene_compressed.pcd", "scene.ply", "jug_mm.ply"}) {
      const auto start = Clock::now();
      const FileInfo info = inspect_file(dir / file);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      print_file_info(dir / file, info);
      fmt::print("  read in:      {:.1f} ms\n\n", ms);
    }
    fmt::print(
        "Built so far: file formats, the renderer and view sphere, the Kinect sensor model, `viewpose simulate`.\n"
        "Not built yet, so no object is recognized and no pose is estimated:\n"
        "  - segmentation, normals, VFH and CRH descriptors, the view database (issue 4)\n"
        "  - pose estimation, ICP and verification (issue 5)\n");
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
