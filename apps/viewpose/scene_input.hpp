#pragma once
// A scene named on the command line, as a recognition frame: a depth PNG with intrinsics from the
// camera flags, or a PCD/PLY cloud in the camera frame.
#include <string>

#include "camera_flags.hpp"
#include "viewpose/recognize/frame.hpp"

namespace viewpose::cli {

Frame load_scene(const std::string& path, const CameraFlags& camera);

}  // namespace viewpose::cli
