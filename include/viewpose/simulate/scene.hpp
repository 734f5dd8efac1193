#pragma once
// Synthetic scenes with exact ground truth: objects placed on a table in front of a camera,
// rendered, passed through the sensor model, and measured for visibility as BOP defines it.
//
// The presets share one world frame: z up, the table top is the plane z = 0, the camera stands
// above the origin and looks along +y. A scene may hold a room around the table (simulate/room.hpp):
// everything in it is background, rendered and hiding the known objects, but never ground truth.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/object_model.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/render/sensor_model.hpp"
#include "viewpose/simulate/room.hpp"

namespace viewpose {

struct ObjectPlacement {
  std::size_t object = 0;  ///< index into SimDataset::objects
  Transform T_camera_object = Transform::Identity();
};

/// A mesh that is seen but is not a known object: the table, a room's walls, floor and furniture,
/// unknown objects (distractors). It hides known objects and the sensor sees it; it has no ground
/// truth. Meshes are shared, so that the images of one room cost one copy of it.
struct BackgroundMesh {
  std::string kind;  ///< "table", "wall", "floor", "shelf", "distractor", ... (see room.hpp)
  std::shared_ptr<const TriangleMesh> mesh;
  Transform T_camera_mesh = Transform::Identity();
};

struct SimImage {
  SimImage() = default;
  SimImage(std::vector<ObjectPlacement> objects_, std::vector<BackgroundMesh> background_ = {})
      : objects(std::move(objects_)), background(std::move(background_)) {}
  std::vector<ObjectPlacement> objects;    ///< the known objects: the image's ground truth
  std::vector<BackgroundMesh> background;  ///< seen in this image only, besides the dataset's
};

struct SimScene {
  int scene_id = 0;
  std::string description;  ///< e.g. "nearest face at 0.75 m"
  std::vector<SimImage> images;
};

struct SimDataset {
  CameraIntrinsics K;
  std::vector<ObjectModel> objects;
  std::vector<BackgroundMesh> background;  ///< seen in every image (the table, when the camera does not move)
  /// The camera in the presets' world frame, for presets whose camera does not move.
  std::optional<Transform> T_world_camera;
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

/// Puts a fixed-camera preset (the seed experiment, clutter) in a room: its endless table gives way
/// to the room's finite one, grown to hold every known object, with walls, floor, furniture and
/// unknown objects around it; each image also gets its own unknown objects on the table, kept out
/// of the camera's line of sight to the known ones (so that the preset measures what it did, now
/// with a room behind it). The known objects' poses do not change. Throws viewpose::Error for a
/// dataset with no fixed camera.
void put_in_room(SimDataset& dataset, const RoomOptions& options, std::uint64_t seed);

/// Rooms as a robot sees them: known objects on a room's table among unknown ones, in piles where
/// they touch and hide each other, seen from a few camera heights, each camera turned towards the
/// pile; and negative frames, with no known object anywhere, half of them looking at the table
/// (with only unknown things on it) and half turned away to the walls and furniture. One scene per
/// room; its images share the room, each with its own camera and its own things on the table.
struct RoomPresetOptions {
  int rooms = 4;
  int images = 20;  ///< in all, dealt to the rooms in turn
  int min_objects = 1, max_objects = 4;  ///< known objects in an image that has any
  double empty_fraction = 0.2;  ///< share of the images with no known object (rounded to whole images)
  std::vector<double> camera_heights_m = {0.30, 0.45, 0.65, 0.90};  ///< above the table top, drawn per image
  double pile_fraction = 0.75;  ///< chance that a thing on the table is put touching one already there
  RoomOptions room;             ///< the rooms; their table distractors are drawn per image
};
SimDataset make_room_scenes(const std::vector<ObjectModel>& objects, const CameraIntrinsics& K,
                            const RoomPresetOptions& options, std::uint64_t seed);

/// One image as the sensor reports it, with its ground truth.
struct SimulatedFrame {
  DepthImage depth;
  std::vector<GroundTruthPose> gt;
  std::vector<GroundTruthInfo> gt_info;  ///< visib_fract = visible pixels / pixels of the object alone
};
/// Renders the image's known objects, then the dataset's background, then the image's: all of it
/// hides the known objects, and visibility is measured against each object rendered alone.
SimulatedFrame simulate_image(const SimDataset& dataset, const SimImage& image, const SensorModel& sensor,
                              std::uint64_t seed);

}  // namespace viewpose
