#pragma once
// The view database: every object rendered from a view sphere, each view described exactly as a
// scene cluster is, stored with its pose so that a match gives a pose. One binary file, versioned
// and checksummed, written atomically.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/object_model.hpp"
#include "viewpose/core/symmetry.hpp"
#include "viewpose/core/transform.hpp"
#include "viewpose/describe/describe.hpp"

namespace viewpose {

struct DatabaseObject {
  int id = 0;        ///< BOP obj_id, or 1, 2, ... in the order given
  std::string name;
  double diameter_m = 0;
  TriangleMesh mesh;  ///< metres, object frame: rendered at a hypothesis to verify it
  std::vector<Eigen::Vector3f> model_points;   ///< the surface the views saw, object frame, voxel grid
  std::vector<Eigen::Vector3f> model_normals;  ///< outward, one per model point: ICP's target
  Symmetries symmetries;  ///< of the mesh's shape (find_symmetries); none for scanned objects
};

struct ViewEntry {
  std::uint32_t object = 0;  ///< index into ViewDatabase::objects
  Transform T_view_object = Transform::Identity();  ///< the pose the view was rendered at
  Vfh vfh{};
  Crh crh{};
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< view camera frame
  std::vector<Eigen::Vector3f> points;   ///< the described points (voxel grid), view camera frame
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Vector3f> icp_points;  ///< a coarser copy for ICP (5 mm voxels)
};

struct DatabaseParams {
  CameraIntrinsics camera = CameraIntrinsics::kinect_v1();  ///< the virtual scanner
  int subdivisions = 1;        ///< view sphere: 1 = 80 views (the thesis), 2 = 320
  double distance_m = 1.0;     ///< camera to object centre
  float voxel_m = 0.003f;      ///< scene and views are described at this resolution (thesis: 3 mm)
  float icp_voxel_m = 0.005f;  ///< the ICP copy (thesis: 5 mm)
  DescribeOptions describe;
};

struct ViewDatabase {
  static constexpr std::uint32_t kFormatVersion = 2;  // 2: objects carry their symmetries
  DatabaseParams params;
  std::vector<DatabaseObject> objects;
  std::vector<ViewEntry> views;

  void save(const std::filesystem::path& path) const;  ///< atomic
  static ViewDatabase load(const std::filesystem::path& path);
  std::vector<std::uint8_t> serialize() const;
  static ViewDatabase deserialize(std::span<const std::uint8_t> bytes, std::string_view name);
  /// A whole file around a payload: the 32-byte header (magic, format version, byte order, payload
  /// size, CRC-32 of the payload) and the payload. serialize() writes its payload through this; tests
  /// and the fuzzer use it to give hand-made payloads a valid header.
  static std::vector<std::uint8_t> file_from_payload(std::span<const std::uint8_t> payload);
  /// Databases grow by about 9 MB per object at 80 views; files up to this size are read.
  static constexpr std::size_t kMaxFileBytes = std::size_t{64} << 30;
};

/// Renders every object from the view sphere around its bounding-box centre and describes each
/// view. `progress(done, total)` is called after each object.
ViewDatabase build_view_database(std::span<const ObjectModel> objects, const DatabaseParams& params,
                                 const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Adds a view captured by a real sensor (the thesis's other way to fill a database): `cloud` holds
/// only the object, in the capture's camera frame, which becomes the object's frame. A new object
/// named `name` is created (id one more than the largest), or an earlier scanned object of that name
/// gets another view; an object with a mesh cannot (its frame is the mesh's). Returns the object id.
int add_captured_view(ViewDatabase& db, const PointCloud& cloud, const std::string& name);

/// The cloud a view (or a scene frame) is described from: its valid pixels, voxelized.
PointCloud view_points(const DepthImage& depth, const CameraIntrinsics& K, float voxel_m);

/// Describes one rendered view of an object into a database entry.
ViewEntry describe_view(const DepthImage& depth, const Transform& T_view_object, std::uint32_t object,
                        const DatabaseParams& params);

}  // namespace viewpose
