#pragma once
// A room around the table, as a real frame shows one: walls, a floor and a ceiling 1.5-4 m from the
// camera, a table of finite size on legs (so that its edges end and the floor shows), shelves,
// cabinets, chairs and cartons, and unknown objects (distractors: boxes, cylinders, smooth blobs,
// other meshes) on the table, on the floor and on the furniture. None of it is a known object: it
// is rendered, hides known objects and is seen by the sensor, but has no ground truth.
//
// World frame of the presets (see simulate/scene.hpp): z up, the table top is the plane z = 0, the
// camera stands above the origin and faces +y. Everything is drawn from one seed.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

/// A closed interval that a size or distance is drawn from, uniformly.
struct Interval {
  double min = 0, max = 0;
};

/// An axis-aligned rectangle of the horizontal plane (world x, y).
struct PlanRect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  /// Distance from (x, y) to the rectangle, 0 inside.
  double distance(double x, double y) const;
};

/// A mesh placed in the world frame. Meshes are shared: a room's images reuse them.
struct WorldMesh {
  std::string kind;  ///< "wall", "floor", "ceiling", "table", "shelf", "cabinet", "chair", "carton", "distractor"
  std::shared_ptr<const TriangleMesh> mesh;
  Transform T_world_mesh = Transform::Identity();
};

/// An unknown object, standing on its base: its mesh's lowest point is at z = 0 of its own frame,
/// and its footprint is a disc of `radius` about the frame's z axis, whatever it is turned to.
struct Distractor {
  std::shared_ptr<const TriangleMesh> mesh;
  double radius = 0;
  double height = 0;
};

struct RoomOptions {
  Interval back_wall_m{1.5, 4.0};  ///< horizontal distance from the camera to the wall it faces (+y)
  Interval side_wall_m{1.5, 4.0};  ///< to the walls on its left (-x) and right (+x)
  Interval table_height_m{0.70, 0.78};  ///< table top above the floor
  Interval table_width_m{0.9, 1.8};     ///< along x
  Interval table_depth_m{0.7, 1.2};     ///< along y
  Interval table_near_edge_m{0.35, 0.6};  ///< y of the table's edge nearest the camera
  Interval table_centre_x_m{-0.3, 0.3};
  /// The table top spans at least this rectangle and 10 cm more on every side: for presets that
  /// place their known objects before the room is built around them.
  std::optional<PlanRect> table_must_cover;
  double ceiling_height_m = 2.6;  ///< above the floor
  int min_furniture = 2, max_furniture = 5;  ///< shelves, cabinets, chairs, cartons on the floor
  int min_off_table_distractors = 2, max_off_table_distractors = 6;  ///< on the floor and the furniture
  int min_table_distractors = 1, max_table_distractors = 4;          ///< on the table, per image
  /// Other meshes of unknown objects (a user's, or the built-in shapes that are not known objects),
  /// drawn as often as each generated kind (box, cylinder, blob). Each stands on its lowest point.
  std::vector<std::shared_ptr<const TriangleMesh>> distractor_meshes;
};

struct Room {
  std::vector<WorldMesh> meshes;  ///< walls, floor, ceiling, table, furniture and the distractors off the table
  double floor_z = 0;             ///< the floor's top (= minus the table height)
  double ceiling_z = 0;
  double back_wall_y = 0;   ///< the inner faces of the walls
  double left_wall_x = 0;   ///< negative
  double right_wall_x = 0;  ///< positive
  PlanRect table_top;       ///< at z = 0
  int furniture = 0;        ///< pieces of furniture
  int off_table_distractors = 0;
  std::string description;  ///< one line: wall distances, table size, what stands in the room
};

/// A room drawn from `seed`: the same options and seed give the same room.
Room make_room(const RoomOptions& options, std::uint64_t seed);

/// A mesh stood on its lowest point, its bounding box centred over the frame's origin.
Distractor standing_distractor(const TriangleMesh& mesh);

/// An unknown object no larger than `max_radius` (footprint) and `max_height`: a box, a cylinder or
/// a smooth blob of random size, or one of `others` (as often as each of those three kinds, if it
/// fits). An empty mesh when nothing that small is worth placing.
Distractor make_distractor(std::mt19937_64& rng, const std::vector<Distractor>& others, double max_radius,
                           double max_height);

/// A smooth closed blob of about `radius`: a sphere whose radius varies with direction by a few
/// low-frequency waves (up to `bumpiness` of it) and whose axes are stretched by up to 30 %.
TriangleMesh make_blob(double radius, double bumpiness, std::mt19937_64& rng);

/// Discs placed on a rectangle (a table top, a floor), none overlapping another: where objects
/// stand. `allowed` can refuse spots for other reasons (a clear line of sight, say).
class Footprints {
 public:
  explicit Footprints(PlanRect area) : area_(area) {}
  struct Disc {
    double x = 0, y = 0, r = 0;
  };
  /// A free spot for a disc of radius r, wholly on the area, or none after `attempts` tries.
  /// `touching`: beside one of the discs already placed (0 to 5 mm apart), as objects in a pile.
  std::optional<Disc> place(double r, bool touching, std::mt19937_64& rng,
                            const std::function<bool(const Disc&)>& allowed = {}, int attempts = 200);
  /// A free spot within `spread` of (x, y), or none after `attempts` tries.
  std::optional<Disc> place_around(double r, double x, double y, double spread, std::mt19937_64& rng, int attempts = 200);
  bool is_free(const Disc& d) const;
  void add(const Disc& d) { discs_.push_back(d); }
  const std::vector<Disc>& discs() const { return discs_; }
  const PlanRect& area() const { return area_; }

 private:
  PlanRect area_;
  std::vector<Disc> discs_;
};

/// The pose that stands a distractor (or any mesh whose base is at z = 0) at (x, y, z) turned by yaw.
Transform standing_at(double x, double y, double z, double yaw);

}  // namespace viewpose
