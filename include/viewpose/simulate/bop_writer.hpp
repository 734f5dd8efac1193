#pragma once
// Writes a simulated dataset in the BOP layout (see io/bop.hpp): camera.json, models/ in mm with
// models_info.json, and test/SCENE/ with scene_camera.json, scene_gt.json, scene_gt_info.json and
// depth/IMAGE.png. Every file is written atomically.
#include <cstdint>
#include <filesystem>
#include <functional>

#include "viewpose/simulate/scene.hpp"

namespace viewpose {

struct BopWriteOptions {
  SensorModel sensor = SensorModel::kinect_v1();
  std::uint64_t seed = 1;
  double depth_scale_mm = 1.0;  ///< BOP depth_scale of the PNGs (depth beyond 65.535 m is dropped)
  std::string split = "test";
  std::function<void(std::size_t done, std::size_t total)> progress;  ///< after each image
};

void write_bop_dataset(const std::filesystem::path& dir, const SimDataset& dataset, const BopWriteOptions& options);

/// models_info.json's entry for a mesh in metres: diameter, extent.
ModelInfo model_info(const TriangleMesh& mesh);

}  // namespace viewpose
