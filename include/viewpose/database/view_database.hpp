#pragma once
// The view database: every object rendered from a view sphere, each view described exactly as a
// scene cluster is, stored with its pose so that a match gives a pose. One binary file, versioned
// and checksummed, written atomically.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
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
#include "viewpose/pose/ppf.hpp"

namespace viewpose {

struct DatabaseObject {
  int id = 0;        ///< BOP obj_id, or 1, 2, ... in the order given
  std::string name;
  double diameter_m = 0;
  TriangleMesh mesh;  ///< metres, object frame: rendered at a hypothesis to verify it
  std::vector<Eigen::Vector3f> model_points;   ///< the surface the views saw, object frame, voxel grid
  std::vector<Eigen::Vector3f> model_normals;  ///< outward, one per model point: ICP's target
  Symmetries symmetries;  ///< of the mesh's shape (find_symmetries); none for scanned objects
  // Made when the database is built, so that a process that recognizes one frame does not make
  // them (for an object of 20 cm about 8 ms and 15 ms): what recognition would otherwise prepare
  // on an object's first hypothesis. Empty where not stored; the recognizer then makes them.
  /// `mesh` simplified for verification's drawing (simplify_for_drawing, DatabaseParams::drawn_mesh_error_m).
  TriangleMesh drawn_mesh;
  /// ICP's nearest-point grid over `model_points`, every cell filled (NearestGrid::cells(),
  /// DatabaseParams::grid_cell_m and grid_margin_m).
  std::vector<std::uint32_t> nearest_cells;
  /// Point pair votes' table of `model_points` (make_ppf_table, DatabaseParams::ppf); null where
  /// not stored. About 0.1 s to make and 3 MB for an object of 20 cm.
  std::shared_ptr<const PpfTable> pair_table;
};

struct ViewEntry {
  std::uint32_t object = 0;  ///< index into ViewDatabase::objects
  Transform T_view_object = Transform::Identity();  ///< the pose the view was rendered at
  Vfh vfh{};
  Crh crh{};
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< view camera frame
  /// How many points (voxel grid) the view was described from. The points themselves are not kept:
  /// recognition needs only the coarser copy below, and they were two thirds of a database's bytes.
  std::uint32_t described_points = 0;
  std::vector<Eigen::Vector3f> icp_points;  ///< the described points on a coarser grid (5 mm voxels), view camera frame
};

struct DatabaseParams {
  CameraIntrinsics camera = CameraIntrinsics::kinect_v1();  ///< the virtual scanner
  int subdivisions = 1;        ///< view sphere: 1 = 80 views (the thesis), 2 = 320
  double distance_m = 1.0;     ///< camera to object centre
  float voxel_m = 0.003f;      ///< scene and views are described at this resolution (thesis: 3 mm)
  float icp_voxel_m = 0.005f;  ///< the ICP copy (thesis: 5 mm)
  DescribeOptions describe;
  // What the prepared data of DatabaseObject was made with; the recognizer uses it where its own
  // options are the same (they are by default).
  float drawn_mesh_error_m = 0.002f;  ///< RecognizerOptions::verify_mesh_error_m
  float grid_cell_m = 0.003f;         ///< IcpOptions::grid_cell_m
  float grid_margin_m = 0.04f;        ///< IcpOptions::reach_m()
  /// Nearest-point grids are stored for the objects, in order, each that still fits within this
  /// many bytes of grids in all (a few MB an object; a large database prepares the rest as scenes
  /// suggest them).
  std::size_t max_grid_bytes = std::size_t{256} << 20;
  /// The pair tables' shape (sample_fraction, angle_bins, normal_split_deg; the other options act
  /// when votes are cast): RecognizerOptions::match.ppf.
  PpfOptions ppf{};
  /// Pair tables are stored for the objects, in order, each that still fits within this many
  /// bytes of tables in all; 0 stores none. The recognizer makes the rest on first use.
  std::size_t max_pair_table_bytes = std::size_t{256} << 20;
};

/// What a load unpacks. The pair tables are about half of a database's bytes, and only point pair
/// votes (MatchOptions::source other than vfh) use them: a process that will not cast votes neither
/// reads nor unpacks them, and a recognizer that does makes any table missing.
struct DatabaseLoadOptions {
  bool pair_tables = true;
};

/// Where the pair tables of a database loaded without them lie (DatabaseLoadOptions::pair_tables
/// false): its file, the file's size and header then, and the tables' offset in it. A recognizer
/// that first casts votes then reads them (read_stored_pair_tables): most real frames cast none,
/// and reading the tables of eight objects was a quarter of a `recognize` process.
struct PairTablesOnDisk {
  std::filesystem::path path;
  std::uint64_t file_size = 0;
  std::array<std::uint8_t, 32> header{};  // the file's header when it was loaded (the payload's size and CRC-32)
  std::uint64_t offset = 0;               // of the tables' 16-byte header
};

struct ViewDatabase {
  // 2: objects carry their symmetries. 3: objects carry a drawing mesh and a filled ICP grid; views
  // keep only their ICP points. 4: objects carry their point pair table.
  static constexpr std::uint32_t kFormatVersion = 4;
  DatabaseParams params;
  std::vector<DatabaseObject> objects;
  std::vector<ViewEntry> views;
  /// Set by load() without the pair tables, where the file holds some: where to read them later.
  std::optional<PairTablesOnDisk> pair_tables_on_disk;

  void save(const std::filesystem::path& path) const;  ///< atomic
  static ViewDatabase load(const std::filesystem::path& path, DatabaseLoadOptions options = {});
  std::vector<std::uint8_t> serialize() const;
  static ViewDatabase deserialize(std::span<const std::uint8_t> bytes, std::string_view name, DatabaseLoadOptions options = {});
  /// A whole file around two payloads: the 32-byte header (magic, format version, byte order,
  /// payload size, CRC-32 of the payload), the payload (parameters, objects, views), then the
  /// pair tables' 16-byte header (size, CRC-32) and the tables (none where empty: one record per
  /// object otherwise). serialize() writes through this; tests and the fuzzer use it to give
  /// hand-made payloads valid headers.
  static std::vector<std::uint8_t> file_from_payload(std::span<const std::uint8_t> payload,
                                                     std::span<const std::uint8_t> pair_tables = {});
  /// Databases grow by about 2.3 MB per object at 80 views, and as much again for its pair table
  /// (hope8: 18.3 + 17.6 MB); files up to this size are read.
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

/// Describes one rendered view of an object into a database entry; `described` (if given) gets
/// the cloud it was described from (points and normals, view camera frame).
ViewEntry describe_view(const DepthImage& depth, const Transform& T_view_object, std::uint32_t object,
                        const DatabaseParams& params, PointCloud* described = nullptr);

/// The bytes of the nearest-point grids `db` stores (DatabaseObject::nearest_cells).
std::size_t stored_grid_bytes(const ViewDatabase& db);

/// The pair tables of a database loaded without them (ViewDatabase::pair_tables_on_disk), one per
/// object in order (null where the file stores none); empty when there is no such file part. Throws
/// Error (one line) when the file is gone, damaged, or no longer the one loaded (its header or size
/// changed: a `db build` over it).
std::vector<std::shared_ptr<const PpfTable>> read_stored_pair_tables(const ViewDatabase& db);

/// The bytes of the pair tables `db` stores (DatabaseObject::pair_table).
std::size_t stored_pair_table_bytes(const ViewDatabase& db);

/// What DatabaseParams' byte limits still allow, less what each prepared object took.
struct PreparedBytesLeft {
  std::size_t grids = 0;
  std::size_t pair_tables = 0;
};

/// Makes an object's prepared data (DatabaseObject::drawn_mesh, nearest_cells, pair_table) as
/// `params` says, each where `left` still allows it, and takes what they hold from `left`.
void prepare_object(DatabaseObject& object, const DatabaseParams& params, PreparedBytesLeft& left);

}  // namespace viewpose
