// libFuzzer target: a depth PNG with its BOP json (or results CSV, or BOP19 targets). Input layout: byte 0 picks the json kind, bytes
// 1-2 give the json length (little-endian), then the json, then the PNG. When both parse, the
// frame goes through depth_to_cloud as a real BOP image would.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"
#include "viewpose/io/depth_png.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  const int kind = data[0] % 7;
  const std::size_t json_size = std::min<std::size_t>(size - 3, data[1] | (std::size_t{data[2]} << 8));
  const std::string_view json(reinterpret_cast<const char*>(data + 3), json_size);
  const std::span<const std::uint8_t> png(data + 3 + json_size, size - 3 - json_size);
  using namespace viewpose;
  std::optional<CameraIntrinsics> K;
  try {
    switch (kind) {
      case 0: K = parse_bop_camera(json, "camera.json").K; break;
      case 1: {
        const SceneCameras cams = parse_scene_camera(json, "scene_camera.json");
        if (!cams.empty()) K = cams.begin()->second.K;
        break;
      }
      case 2: (void)parse_scene_gt(json, "scene_gt.json"); break;
      case 3: (void)parse_scene_gt_info(json, "scene_gt_info.json"); break;
      case 4: (void)parse_models_info(json, "models_info.json"); break;
      case 5: (void)parse_bop_results(json, "results.csv"); break;
      default: (void)parse_bop_targets(json, "test_targets_bop19.json"); break;
    }
  } catch (const Error&) {
  }
  try {
    const DepthImage depth = decode_depth_png(png, "depth.png", 0.001);
    if (K) {
      K->width = depth.width;
      K->height = depth.height;
      const PointCloud cloud = depth_to_cloud(depth, *K);
      if (cloud.size() != depth.depth_m.size()) __builtin_trap();
    }
  } catch (const Error&) {
  }
  return 0;
}
