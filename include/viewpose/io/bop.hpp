#pragma once
// The BOP dataset format (bop.felk.cvut.cz), the standard layout of 6-DoF pose benchmarks:
//   DATASET/camera.json                       default intrinsics, image size, depth_scale
//   DATASET/models/models_info.json           per object: diameter, extent, symmetries (mm)
//   DATASET/models/obj_NNNNNN.ply             meshes in mm
//   DATASET/SPLIT/SCENE/scene_camera.json     per image: cam_K, depth_scale
//   DATASET/SPLIT/SCENE/scene_gt.json         per image: objects with cam_R_m2c, cam_t_m2c (mm)
//   DATASET/SPLIT/SCENE/scene_gt_info.json    per image and object: visible fraction, boxes
//   DATASET/SPLIT/SCENE/depth/NNNNNN.png      16-bit depth; depth_mm = value * depth_scale
// YCB-Video's own naming of depth files, SCENE/NNNNNN-depth.png, is read as well.
// Everything is converted to metres on reading and back to millimetres on writing.
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/symmetry.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

/// camera.json, or one image's entry of scene_camera.json (whose image size is 0 when unknown).
struct BopCamera {
  CameraIntrinsics K;
  double depth_scale_mm = 1.0;  ///< millimetres per stored depth unit
};

struct GroundTruthPose {
  int obj_id = 0;
  Transform T_camera_object = Transform::Identity();  ///< metres
};

struct GroundTruthInfo {
  double visib_fract = 0.0;  ///< visible share of the object's silhouette, 0..1
  int px_count_all = 0, px_count_valid = 0, px_count_visib = 0;
  std::array<int, 4> bbox_obj{-1, -1, -1, -1};    ///< x, y, width, height in pixels
  std::array<int, 4> bbox_visib{-1, -1, -1, -1};
};

struct ModelInfo {
  double diameter_m = 0.0;
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
  std::vector<Transform> symmetries_discrete;  ///< object-frame transforms, metres
  std::vector<ContinuousSymmetry> symmetries_continuous;
};

using ImageId = int;
using SceneCameras = std::map<ImageId, BopCamera>;
using SceneGroundTruth = std::map<ImageId, std::vector<GroundTruthPose>>;
using SceneGroundTruthInfo = std::map<ImageId, std::vector<GroundTruthInfo>>;
using ModelsInfo = std::map<int, ModelInfo>;

// Parsers take the JSON text; `name` is used in error messages. Each checks types, counts and
// values (rotation matrices, positive focal lengths) and throws viewpose::Error naming the entry.
// Rotations are taken as rounded (core/transform.hpp: nearest_rotation): a matrix off orthonormal
// by what rounding explains is taken as its nearest rotation, and when that is more than a last
// digit, one line per file says so in `notes` (when given); a reflection, or a scaled or sheared
// matrix, is an error.
BopCamera parse_bop_camera(std::string_view json_text, std::string_view name);
SceneCameras parse_scene_camera(std::string_view json_text, std::string_view name);
SceneGroundTruth parse_scene_gt(std::string_view json_text, std::string_view name,
                                std::vector<std::string>* notes = nullptr);
SceneGroundTruthInfo parse_scene_gt_info(std::string_view json_text, std::string_view name);
ModelsInfo parse_models_info(std::string_view json_text, std::string_view name,
                             std::vector<std::string>* notes = nullptr);

/// One entry of a BOP19 targets file (test_targets_bop19.json): in image (scene_id, im_id), find
/// up to inst_count instances of object obj_id.
struct BopTarget {
  int scene_id = 0;
  ImageId im_id = 0;
  int obj_id = 0;
  int inst_count = 1;
  friend bool operator==(const BopTarget&, const BopTarget&) = default;
};
/// A JSON list of {"scene_id", "im_id", "obj_id", "inst_count"}, sorted by scene, image and object.
/// Throws viewpose::Error for a malformed entry, a count below 1, or the same object listed twice
/// for one image.
std::vector<BopTarget> parse_bop_targets(std::string_view json_text, std::string_view name);
std::vector<BopTarget> read_bop_targets(const std::filesystem::path& path);

std::string format_bop_camera(const BopCamera& camera);
std::string format_scene_camera(const SceneCameras& cameras);
std::string format_scene_gt(const SceneGroundTruth& gt);
std::string format_scene_gt_info(const SceneGroundTruthInfo& info);
std::string format_models_info(const ModelsInfo& models);

/// One image of a split, with everything needed to load and score it.
struct BopImage {
  int scene_id = 0;
  ImageId im_id = 0;
  std::filesystem::path depth_path;
  BopCamera camera;  ///< size from camera.json when present, else filled by load_bop_depth
  std::vector<GroundTruthPose> gt;
  std::vector<GroundTruthInfo> gt_info;  ///< empty, or one per gt entry
};

/// A split folder as BOP names them: `test`, `val`, or SPLIT_TYPE (`test_primesense`, `train_pbr`,
/// T-LESS's `train_render_reconst`): the split is the name before the first underscore.
struct BopSplitFolder {
  std::string folder;  ///< as on disk: "test_primesense"
  std::string split;   ///< "test"
  std::string type;    ///< "primesense"; empty when the folder has none
};

/// What a dataset folder holds, found from its names alone (no image is read): the split folders
/// (those with scene folders holding scene_camera.json), the model folders (with obj_NNNNNN.ply:
/// models, models_eval, T-LESS's models_cad and models_reconst, YCB-V's models_fine), the camera
/// files (camera.json, or per sensor: camera_primesense.json, YCB-V's camera_uw.json) and the
/// target lists (test_targets_bop19.json, ...). Each list sorted by name.
struct BopLayout {
  std::filesystem::path root;
  std::vector<BopSplitFolder> splits;
  std::vector<std::string> model_folders;
  std::vector<std::string> camera_files;
  std::vector<std::string> target_files;
};
BopLayout scan_bop_layout(const std::filesystem::path& root);

/// The split folder a name means: the folder of that name (`test_primesense`), or, for a bare split
/// (`test`) with no folder of its own, its one typed folder. Throws viewpose::Error listing the
/// choices when there is none or several.
BopSplitFolder resolve_bop_split(const BopLayout& layout, std::string_view name);

/// The models folder to read: `name` when it exists; for the default "models" when it does not,
/// the first of models_cad (T-LESS), models_eval and any other models_* folder with meshes.
/// Empty when the dataset has none.
std::string resolve_models_folder(const BopLayout& layout, std::string_view name = "models");

struct BopDataset {
  std::filesystem::path root;
  std::string split;                ///< the split folder read ("test", "test_primesense", ...)
  std::string models_dir;           ///< the models folder read, under root (empty: none)
  /// The models folder scoring should use: models_eval when the dataset has it (the BOP toolkit's
  /// choice: meshes resampled evenly for the errors), else models_dir.
  std::string eval_models_dir;
  std::optional<BopCamera> camera;  ///< camera.json (or the split type's camera_TYPE.json), when there is one
  ModelsInfo models;                ///< models_info.json, when the dataset has one
  std::map<int, std::filesystem::path> model_files;  ///< obj_id -> obj_NNNNNN.ply
  std::vector<BopImage> images;     ///< sorted by scene, then image
  /// What the reader took on trust and a user should hear once (rotations taken as the nearest
  /// rotation, per file); commands print each line on stderr.
  std::vector<std::string> notes;
};

struct BopOpenOptions {
  /// Folder under the root with models_info.json and meshes (resolve_models_folder: the default
  /// finds T-LESS's models_cad when there is no models/).
  std::string models_dir = "models";
};

/// The obj_NNNNNN.ply files of a BOP models folder, by obj_id (none when the folder is absent).
std::map<int, std::filesystem::path> find_bop_model_files(const std::filesystem::path& dir);

/// Reads a split's json files and checks that every image's depth file exists. `split` is a split
/// folder or a bare split name (resolve_bop_split). Throws viewpose::Error naming the first missing
/// or malformed file.
BopDataset open_bop_dataset(const std::filesystem::path& root, std::string_view split,
                            const BopOpenOptions& options = {});

/// The image's depth in metres, and its intrinsics with the image size filled in.
struct BopFrame {
  DepthImage depth;
  CameraIntrinsics K;
};
BopFrame load_bop_frame(const BopImage& image);

}  // namespace viewpose
