#include "viewpose/simulate/bop_writer.hpp"

#include <cmath>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {

namespace fs = std::filesystem;

ModelInfo model_info(const TriangleMesh& mesh) {
  ModelInfo info;
  const BoundingBox box = bounding_box(mesh);
  info.diameter_m = mesh_diameter(mesh);
  info.min_m = box.min.cast<double>();
  info.size_m = box.size().cast<double>();
  // The shape's symmetries, as found for the view database: scoring (MSSD) then treats poses that
  // no depth sensor can tell apart as the same.
  const Symmetries symmetries = find_symmetries(mesh);
  info.symmetries_discrete = symmetries.discrete;
  info.symmetries_continuous = symmetries.continuous;
  return info;
}

void write_bop_dataset(const fs::path& dir, const SimDataset& ds, const BopWriteOptions& options) {
  if (!(options.depth_scale_mm > 0)) throw Error("simulate: depth scale must be positive");
  std::error_code ec;
  fs::create_directories(dir / "models", ec);
  if (ec) throw Error(fmt::format("{}: cannot create the dataset folder: {}", dir.string(), ec.message()));

  write_file_atomic(dir / "camera.json", format_bop_camera({ds.K, options.depth_scale_mm}));
  ModelsInfo models;
  for (const ObjectModel& o : ds.objects) {
    TriangleMesh mm = o.mesh;  // BOP models are in millimetres
    for (auto& v : mm.vertices) v *= 1000.0f;
    mm.normals.clear();
    write_ply(dir / "models" / fmt::format("obj_{:06d}.ply", o.id), mm, PlyEncoding::BinaryLittleEndian);
    models[o.id] = model_info(o.mesh);
  }
  write_file_atomic(dir / "models" / "models_info.json", format_models_info(models));

  std::size_t total = 0, done = 0;
  for (const auto& s : ds.scenes) total += s.images.size();
  const double max_depth_m = 65535.0 * options.depth_scale_mm / 1000.0;
  for (const SimScene& scene : ds.scenes) {
    const fs::path scene_dir = dir / options.split / fmt::format("{:06d}", scene.scene_id);
    fs::create_directories(scene_dir / "depth", ec);
    if (ec) throw Error(fmt::format("{}: cannot create: {}", scene_dir.string(), ec.message()));
    SceneCameras cameras;
    SceneGroundTruth gt;
    SceneGroundTruthInfo gt_info;
    for (std::size_t im = 0; im < scene.images.size(); ++im) {
      const int im_id = static_cast<int>(im);
      // Each image has its own noise stream, so any one image can be regenerated alone.
      const std::uint64_t image_seed = options.seed * 1000003ull + static_cast<std::uint64_t>(scene.scene_id) * 10007ull + im;
      SimulatedFrame frame = simulate_image(ds, scene.images[im], options.sensor, image_seed);
      for (float& z : frame.depth.depth_m) {
        if (z > max_depth_m) z = NAN;  // beyond what 16 bits hold at this scale: no data
      }
      write_depth_png(scene_dir / "depth" / fmt::format("{:06d}.png", im_id), frame.depth, options.depth_scale_mm / 1000.0);
      cameras[im_id] = BopCamera{ds.K, options.depth_scale_mm};
      gt[im_id] = std::move(frame.gt);
      gt_info[im_id] = std::move(frame.gt_info);
      if (options.progress) options.progress(++done, total);
    }
    // The json files last: a scene folder whose json is there is complete.
    write_file_atomic(scene_dir / "scene_gt_info.json", format_scene_gt_info(gt_info));
    write_file_atomic(scene_dir / "scene_gt.json", format_scene_gt(gt));
    write_file_atomic(scene_dir / "scene_camera.json", format_scene_camera(cameras));
  }
}

}  // namespace viewpose
