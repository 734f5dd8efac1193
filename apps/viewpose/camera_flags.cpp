#include "camera_flags.hpp"

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose::cli {

void CameraFlags::add_to(CLI::App& cmd) {
  auto* file = cmd.add_option("--camera", camera_file, "BOP camera.json with the depth camera's intrinsics")
                   ->check(CLI::ExistingFile);
  cmd.add_option("--intrinsics", intrinsics, "Depth camera intrinsics in pixels: FX FY CX CY")
      ->expected(4)
      ->excludes(file);
  cmd.add_option("--depth-scale", depth_scale_mm, "Millimetres per unit in depth PNGs (BOP depth_scale; default 1)")
      ->check(CLI::PositiveNumber);
}

std::optional<BopCamera> CameraFlags::camera() const {
  if (!camera_file.empty()) {
    const auto bytes = read_file_bytes(camera_file, 1 << 20);
    return parse_bop_camera(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), camera_file);
  }
  if (intrinsics.size() == 4) {
    BopCamera cam{{intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3], 0, 0}, depth_scale()};
    if (!(cam.K.fx > 0 && cam.K.fy > 0)) throw Error(fmt::format("--intrinsics: focal lengths must be positive"));
    return cam;
  }
  return std::nullopt;
}

double CameraFlags::depth_scale() const {
  if (depth_scale_mm) return *depth_scale_mm;
  if (!camera_file.empty()) return camera()->depth_scale_mm;
  return 1.0;
}

}  // namespace viewpose::cli
