#include "scene_input.hpp"

#include <spdlog/spdlog.h>

#include "viewpose/io/scene_file.hpp"

namespace viewpose::cli {

Frame load_scene(const std::string& path, const CameraFlags& camera) {
  std::optional<CameraIntrinsics> K;
  if (const auto cam = camera.camera()) K = cam->K;
  SceneFile scene = load_scene_file(path, K, camera.depth_scale());
  for (const std::string& w : scene.warnings) spdlog::warn("{}", w);
  return std::move(scene.frame);
}

}  // namespace viewpose::cli
