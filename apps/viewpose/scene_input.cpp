#include "scene_input.hpp"

#include <filesystem>

#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "viewpose/core/error.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose::cli {

Frame load_scene(const std::string& path, const CameraFlags& camera) {
  const std::string ext = std::filesystem::path(path).extension().string();
  std::optional<CameraIntrinsics> K;
  if (const auto cam = camera.camera()) K = cam->K;
  if (ext == ".png") {
    DepthImage depth = read_depth_png(path, camera.depth_scale() / 1000.0);
    if (const std::string w = depth_scale_warning(depth, camera.depth_scale()); !w.empty()) spdlog::warn("{}: {}", path, w);
    if (!K) throw Error(fmt::format("{}: a depth image needs its camera: give --camera camera.json or --intrinsics", path));
    if (K->width == 0) {
      K->width = depth.width;
      K->height = depth.height;
    }
    return frame_from_depth(std::move(depth), *K);
  }
  if (ext == ".pcd" || ext == ".ply") {
    Frame frame = frame_from_cloud(ext == ".pcd" ? read_pcd(path).cloud : read_ply(path).cloud, K);
    // Clouds carry no unit; PCL's and viewpose's are metres. One in millimetres lies kilometres away.
    const double median = median_depth_m(frame.depth);
    if (std::isfinite(median) && !within_depth_camera_range(median)) {
      spdlog::warn("{}: median depth {:.3g} m, outside what depth cameras measure (0.3-5 m): clouds are read in metres{}",
                   path, median, median > 100.0 ? "; this one looks like millimetres" : "");
    }
    return frame;
  }
  throw Error(fmt::format("{}: a scene must be a depth .png, a .pcd or a .ply", path));
}

}  // namespace viewpose::cli
