#include "viewpose/io/scene_file.hpp"

#include <cmath>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {

SceneFile load_scene_file(const std::filesystem::path& path, std::optional<CameraIntrinsics> K, double depth_scale_mm) {
  const std::string ext = path.extension().string(), name = path.string();
  SceneFile out;
  if (ext == ".png") {
    DepthImage depth = read_depth_png(path, depth_scale_mm / 1000.0);
    if (std::string w = depth_scale_warning(depth, depth_scale_mm); !w.empty()) out.warnings.push_back(name + ": " + w);
    if (!K) throw Error(fmt::format("{}: a depth image needs its camera: give --camera camera.json or --intrinsics", name));
    if (K->width == 0) {
      K->width = depth.width;
      K->height = depth.height;
    }
    out.frame = frame_from_depth(std::move(depth), *K);
    return out;
  }
  if (ext == ".pcd" || ext == ".ply") {
    out.frame = frame_from_cloud(ext == ".pcd" ? read_pcd(path).cloud : read_ply(path).cloud, K);
    // Clouds carry no unit; PCL's and viewpose's are metres. One in millimetres lies kilometres away.
    const double median = median_depth_m(out.frame.depth);
    if (std::isfinite(median) && !within_depth_camera_range(median)) {
      out.warnings.push_back(fmt::format("{}: median depth {:.3g} m, outside what depth cameras measure (0.3-5 m): clouds are read in metres{}",
                                         name, median, median > 100.0 ? "; this one looks like millimetres" : ""));
    }
    return out;
  }
  throw Error(fmt::format("{}: a scene must be a depth .png, a .pcd or a .ply", name));
}

}  // namespace viewpose
