// `viewpose demo`: the main job on data the program makes itself. It builds the view database of
// the built-in detergent jug, simulates Kinect frames of it on a table at the thesis's distances,
// recognizes each, and prints every estimated pose beside the ground truth with its error and time.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/image_png.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/scene.hpp"
#include "viewpose/visualize/overlay.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

void add_demo_command(CLI::App& app, int& exit_code) {
  auto out_dir = std::make_shared<std::string>("demo-out");
  auto orientations = std::make_shared<int>(4);
  CLI::App* cmd = app.add_subcommand("demo", "Recognize the built-in jug in simulated Kinect frames; print poses and times");
  cmd->add_option("--out", *out_dir, "Folder for the frames and overlay pictures")->capture_default_str();
  cmd->add_option("--orientations", *orientations, "Orientations per distance")->check(CLI::Range(1, 100))->capture_default_str();
  cmd->callback([out_dir, orientations, &exit_code] {
    using Clock = std::chrono::steady_clock;
    const fs::path dir = *out_dir;
    fs::create_directories(dir);
    const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
    const ObjectModel jug{1, "jug", make_jug()};

    auto t0 = Clock::now();
    const ViewDatabase db = build_view_database(std::span(&jug, 1), DatabaseParams{});
    fmt::print("view database of the jug (27 x 17 x 11 cm, a handle and an off-centre cap): {} views in {:.2f} s\n",
               db.views.size(), std::chrono::duration<double>(Clock::now() - t0).count());

    SeedExperimentOptions setup;
    setup.orientations = *orientations;
    const SimDataset scenes = make_seed_experiment(ObjectModel{1, "jug", jug.mesh}, K, setup, 7);
    const Recognizer recognizer(db);
    const double threshold = 0.1 * db.objects[0].diameter_m;
    write_file_atomic(dir / "camera.json", format_bop_camera({K, 1.0}));
    fmt::print("simulated Kinect v1 frames (sensor model on), the jug on a table; success = ADD-S under {:.0f} mm "
               "(10% of its diameter)\n\n", threshold * 1000);
    fmt::print("{:>8} {:>4}  {:>22}  {:>22}  {:>7} {:>7} {:>7} {:>7}  {:>6}  {}\n", "distance", "view", "estimated t (m)",
               "true t (m)", "dt mm", "dR deg", "ADD-S", "ADD", "ms", "");
    int found = 0, correct = 0, correct_side = 0, total = 0;
    double total_ms = 0;
    std::vector<double> frame_ms;
    for (const SimScene& scene : scenes.scenes) {
      for (std::size_t k = 0; k < scene.images.size(); ++k) {
        const SimulatedFrame f = simulate_image(scenes, scene.images[k], SensorModel::kinect_v1(), 100 * scene.scene_id + k);
        const Frame frame = frame_from_depth(f.depth, K);
        const Recognition r = recognizer.recognize(frame);
        ++total;
        total_ms += r.times.total_ms;
        frame_ms.push_back(r.times.total_ms);
        const Transform& truth = f.gt[0].T_camera_object;
        const std::string name = fmt::format("d{:.2f}_o{}", setup.distances_m[static_cast<std::size_t>(scene.scene_id - 1)], k);
        write_depth_png(dir / (name + "_depth.png"), f.depth, 0.001);
        std::vector<OverlayItem> items;
        const Eigen::Vector3d tt = truth.translation();
        if (r.detections.empty()) {
          fmt::print("{:>7.2f}m {:>4}  {:>22}  ({:6.3f},{:6.3f},{:6.3f})  {:>7} {:>7} {:>7} {:>7}  {:6.0f}  not found\n",
                     setup.distances_m[static_cast<std::size_t>(scene.scene_id - 1)], k, "-", tt.x(), tt.y(), tt.z(), "-", "-",
                     "-", "-", r.times.total_ms);
        } else {
          ++found;
          const Detection& d = r.detections[0];
          const Eigen::Vector3d te = d.T_camera_object.translation();
          const double adds = add_s_error(d.T_camera_object, truth, db.objects[0].model_points);
          const double add = add_error(d.T_camera_object, truth, db.objects[0].model_points);
          correct += adds < threshold ? 1 : 0;
          correct_side += add < threshold ? 1 : 0;
          fmt::print("{:>7.2f}m {:>4}  ({:6.3f},{:6.3f},{:6.3f})  ({:6.3f},{:6.3f},{:6.3f})  {:7.1f} {:7.1f} {:7.1f} {:7.1f}  {:6.0f}  {}\n",
                     setup.distances_m[static_cast<std::size_t>(scene.scene_id - 1)], k, te.x(), te.y(), te.z(), tt.x(),
                     tt.y(), tt.z(), (te - tt).norm() * 1000, rotation_difference_deg(d.T_camera_object.linear(), truth.linear()),
                     adds * 1000, add * 1000, r.times.total_ms,
                     adds >= threshold ? "WRONG" : add >= threshold ? "right surface, turned (issue 10)" : "");
          items.push_back({&db.objects[0].mesh, d.T_camera_object, 0.1});
        }
        write_rgb_png(dir / (name + "_overlay.png"), draw_overlay(f.depth, K, items));
      }
    }
    std::sort(frame_ms.begin(), frame_ms.end());
    fmt::print("\nfound {} of {}; ADD-S correct {} of {}; ADD (the right side too) {} of {}; {:.0f} ms per frame median, "
               "{:.0f} on average\n", found, total, correct, total, correct_side, total, frame_ms[frame_ms.size() / 2],
               total_ms / total);
    fmt::print("depth frames and overlays (the estimated model drawn in colour): {}/\n", dir.string());
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
