#pragma once
// Synthetic scenes with exact ground truth: objects placed on a table in front of a camera,
// rendered, passed through the sensor model, and measured for visibility as BOP defines it.
#include <cstdint>
#include <string>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/object_model.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/render/sensor_model.hpp"

namespace viewpose {

struct ObjectPlacement {
  std::size_t object = 0;  ///< index into SimDataset::objects
  Transform T_camera_object = Transform::Identity();
};

struct SimImage {
  std::vector<ObjectPlacement> objects;
};

struct SimScene {
  int scene_id = 0;
  std::string description;  ///< e.g. "nearest face at 0.75 m"
  std::vector<SimImage> images;
};

struct SimDataset {
  CameraIntrinsics K;
  std::vector<ObjectModel> objects;
  TriangleMesh table;  ///< the support surface seen in every image (may be empty)
  Transform T_camera_table = Transform::Identity();
  std::vector<SimScene> scenes;
};

/// The thesis's experiment: one object standing on a table, its nearest surface at each distance
/// (measured from the camera centre, as the thesis measured from the lens), turned to the same
/// `orientations` yaw angles at every distance; one scene per distance. The camera is fixed, as
/// on the thesis's tripod. The object stands on its -z face.
struct SeedExperimentOptions {
  std::vector<double> distances_m = {0.75, 1.00, 1.25, 1.50, 2.00};
  int orientations = 20;
  double camera_height_m = 0.45;   ///< above the table top
  double camera_pitch_deg = 18.0;  ///< looking down
};
SimDataset make_seed_experiment(const ObjectModel& object, const CameraIntrinsics& K,
                                const SeedExperimentOptions& options, std::uint64_t seed);

/// Two to five objects standing on a table, touching and partly hiding each other.
struct ClutterOptions {
  int images = 20;
  int min_objects = 2;
  int max_objects = 5;
  double min_distance_m = 0.8;  ///< horizontal distance of the group from the camera
  double max_distance_m = 1.3;
};
SimDataset make_clutter(const std::vector<ObjectModel>& objects, const CameraIntrinsics& K, const ClutterOptions& options,
                        std::uint64_t seed);

/// One image as the sensor reports it, with its ground truth.
struct SimulatedFrame {
  DepthImage depth;
  std::vector<GroundTruthPose> gt;
  std::vector<GroundTruthInfo> gt_info;  ///< visib_fract = visible pixels / pixels of the object alone
};
SimulatedFrame simulate_image(const SimDataset& dataset, const SimImage& image, const SensorModel& sensor,
                              std::uint64_t seed);

}  // namespace viewpose
