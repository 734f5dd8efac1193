#include "scene_input.hpp"

#include <filesystem>

#include <fmt/format.h>

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
    if (!K) throw Error(fmt::format("{}: a depth image needs its camera: give --camera camera.json or --intrinsics", path));
    if (K->width == 0) {
      K->width = depth.width;
      K->height = depth.height;
    }
    return frame_from_depth(std::move(depth), *K);
  }
  if (ext == ".pcd") return frame_from_cloud(read_pcd(path).cloud, K);
  if (ext == ".ply") return frame_from_cloud(read_ply(path).cloud, K);
  throw Error(fmt::format("{}: a scene must be a depth .png, a .pcd or a .ply", path));
}

}  // namespace viewpose::cli
