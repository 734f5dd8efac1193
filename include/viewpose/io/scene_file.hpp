#pragma once
// A scene file as a recognition frame: a 16-bit depth PNG with its intrinsics, or a PCD/PLY cloud in
// the camera frame (metres; an organized cloud's intrinsics are recovered from its points).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/recognize/frame.hpp"

namespace viewpose {

struct SceneFile {
  Frame frame;
  /// Depth that lies outside what depth cameras measure (a PNG read at the wrong depth scale, a
  /// cloud in millimetres), in words naming the fix.
  std::vector<std::string> warnings;
};

/// `K` is needed for a depth PNG (its size, when 0, is the image's) and optional for a cloud.
/// `depth_scale_mm`: millimetres per PNG unit (BOP's depth_scale). Throws viewpose::Error for a
/// missing or unreadable file, another kind of file, or a PNG without intrinsics.
SceneFile load_scene_file(const std::filesystem::path& path, std::optional<CameraIntrinsics> K, double depth_scale_mm = 1.0);

}  // namespace viewpose
