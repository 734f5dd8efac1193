#include "viewpose/simulate/scene.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/render/rasterizer.hpp"

namespace viewpose {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The fixed tripod camera of the presets, in a world frame whose z is up and whose table top is
// the plane z = 0; the camera looks along +y, pitched down.
Transform camera_in_world(double height, double pitch_deg) {
  const double p = pitch_deg * kDeg;
  Eigen::Matrix3d R_world_camera;
  R_world_camera.col(0) = Eigen::Vector3d(1, 0, 0);
  R_world_camera.col(1) = Eigen::Vector3d(0, -std::sin(p), -std::cos(p));  // image down
  R_world_camera.col(2) = Eigen::Vector3d(0, std::cos(p), -std::sin(p));   // viewing direction
  return make_transform(R_world_camera, Eigen::Vector3d(0, 0, height));
}

// A camera at `eye` turned by yaw from +y towards +x and pitched down: a robot's head looking
// around a room. With yaw 0 it is camera_in_world's.
Transform camera_looking(const Eigen::Vector3d& eye, double yaw, double pitch) {
  const Eigen::Vector3d z(std::sin(yaw) * std::cos(pitch), std::cos(yaw) * std::cos(pitch), -std::sin(pitch));
  const Eigen::Vector3d x(std::cos(yaw), -std::sin(yaw), 0);
  Eigen::Matrix3d R_world_camera;
  R_world_camera << x, z.cross(x), z;
  return make_transform(R_world_camera, eye);
}

// A 3 x 4 m table top (2 cm thick) in front of the camera, top face at z = 0: as good as endless.
BackgroundMesh endless_table(const Transform& T_camera_world) {
  return {"table", std::make_shared<const TriangleMesh>(make_box_mesh({3.0f, 4.0f, 0.02f})),
          T_camera_world * make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 2.2, -0.01))};
}

std::vector<BackgroundMesh> seen_from(const Transform& T_camera_world, const std::vector<WorldMesh>& meshes) {
  std::vector<BackgroundMesh> out;
  out.reserve(meshes.size());
  for (const WorldMesh& m : meshes) out.push_back({m.kind, m.mesh, T_camera_world * m.T_world_mesh});
  return out;
}

// An independent stream for each purpose and index: adding a room leaves the known objects'
// random choices, drawn from the preset's own stream, as they were.
std::uint64_t sub_seed(std::uint64_t seed, std::uint64_t purpose, std::uint64_t index = 0) {
  std::uint64_t x = seed ^ (purpose * 0x9E3779B97F4A7C15ull) ^ (index * 0xD1B54A32D192ED03ull);
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;  // splitmix64's finaliser
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
enum Purpose : std::uint64_t { kRoom = 1, kTableDistractors = 2, kRoomImages = 3 };

// The object standing on the table at horizontal position (x, y), turned by yaw about the vertical.
Transform standing_pose(const TriangleMesh& mesh, double x, double y, double yaw) {
  const double lift = -static_cast<double>(bounding_box(mesh).min.z());
  return make_transform(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d(x, y, lift));
}

// Radius of the object's footprint on the table, about its own origin.
double footprint_radius(const TriangleMesh& mesh) {
  double r = 0;
  for (const auto& v : mesh.vertices) r = std::max(r, std::hypot(static_cast<double>(v.x()), static_cast<double>(v.y())));
  return r;
}

}  // namespace

SimDataset make_seed_experiment(const ObjectModel& object, const CameraIntrinsics& K, const SeedExperimentOptions& options,
                                std::uint64_t seed) {
  K.validate();
  if (options.orientations < 1 || options.distances_m.empty()) throw Error("seed experiment: need distances and orientations");
  for (double d : options.distances_m) {
    if (!(d > 0.2 && d < 20)) throw Error(fmt::format("seed experiment: distance {} m is out of range", d));
  }
  SimDataset ds;
  ds.K = K;
  ds.objects = {object};
  const Transform T_world_camera = camera_in_world(options.camera_height_m, options.camera_pitch_deg);
  const Transform T_camera_world = T_world_camera.inverse();
  ds.background = {endless_table(T_camera_world)};
  ds.T_world_camera = T_world_camera;
  // The same yaw angles at every distance: evenly spread, with a seeded offset per orientation
  // so that no view is exactly axis-aligned.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-4.0, 4.0);
  std::vector<double> yaws;
  for (int k = 0; k < options.orientations; ++k) yaws.push_back((360.0 * k / options.orientations + jitter(rng)) * kDeg);
  const Eigen::Vector3d eye_world = T_world_camera.translation();
  int scene_id = 1;
  for (double distance : options.distances_m) {
    SimScene scene;
    scene.scene_id = scene_id++;
    scene.description = fmt::format("{} at {:.2f} m (nearest surface to the camera)", object.name, distance);
    for (double yaw : yaws) {
      // Slide the object along the camera's line of sight on the table until its nearest surface
      // point is exactly `distance` from the camera centre.
      double y = distance;
      Transform T_world_object = standing_pose(object.mesh, 0.0, y, yaw);
      for (int it = 0; it < 30; ++it) {
        const double nearest = distance_to_surface(object.mesh, T_world_object.inverse() * eye_world);
        if (std::abs(nearest - distance) < 1e-5) break;
        y += distance - nearest;
        T_world_object = standing_pose(object.mesh, 0.0, y, yaw);
      }
      scene.images.push_back(SimImage({ObjectPlacement{0, T_camera_world * T_world_object}}));
    }
    ds.scenes.push_back(std::move(scene));
  }
  return ds;
}

SimDataset make_clutter(const std::vector<ObjectModel>& objects, const CameraIntrinsics& K, const ClutterOptions& options,
                        std::uint64_t seed) {
  K.validate();
  if (objects.empty()) throw Error("clutter: no objects to place");
  if (options.min_objects < 1 || options.max_objects < options.min_objects) throw Error("clutter: bad object counts");
  SimDataset ds;
  ds.K = K;
  ds.objects = objects;
  const Transform T_world_camera = camera_in_world(0.45, 18.0);
  const Transform T_camera_world = T_world_camera.inverse();
  ds.background = {endless_table(T_camera_world)};
  ds.T_world_camera = T_world_camera;
  std::vector<double> radius;
  for (const auto& o : objects) radius.push_back(footprint_radius(o.mesh));

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SimScene scene;
  scene.scene_id = 1;
  scene.description = "clutter: objects touching and partly hiding each other";
  for (int im = 0; im < options.images; ++im) {
    const int count = options.min_objects + static_cast<int>(unit(rng) * (options.max_objects - options.min_objects + 1) * 0.9999);
    // Distinct objects while there are enough of them.
    std::vector<std::size_t> pick(objects.size());
    for (std::size_t i = 0; i < pick.size(); ++i) pick[i] = i;
    std::shuffle(pick.begin(), pick.end(), rng);
    struct Spot { std::size_t object; double x, y, yaw; };
    std::vector<Spot> spots;
    for (int n = 0; n < count; ++n) {
      const std::size_t obj = pick[static_cast<std::size_t>(n) % pick.size()];
      for (int attempt = 0; attempt < 200; ++attempt) {
        Spot s{obj, 0, 0, unit(rng) * 2 * std::numbers::pi};
        if (spots.empty()) {
          s.x = (unit(rng) - 0.5) * 0.2;
          s.y = options.min_distance_m + unit(rng) * (options.max_distance_m - options.min_distance_m);
        } else {
          // Beside a placed object, footprints touching (0 to 5 mm apart).
          const Spot& other = spots[static_cast<std::size_t>(unit(rng) * static_cast<double>(spots.size()) * 0.9999)];
          const double phi = unit(rng) * 2 * std::numbers::pi;
          const double gap = radius[obj] + radius[other.object] + 0.005 * unit(rng);
          s.x = other.x + gap * std::cos(phi);
          s.y = other.y + gap * std::sin(phi);
        }
        bool free = std::abs(s.x) < 0.6 && s.y > 0.5 && s.y < 2.5;
        for (const Spot& o : spots) free = free && std::hypot(s.x - o.x, s.y - o.y) >= radius[obj] + radius[o.object] - 1e-9;
        if (free) {
          spots.push_back(s);
          break;
        }
      }
    }
    SimImage image;
    for (const Spot& s : spots) {
      image.objects.push_back({s.object, T_camera_world * standing_pose(objects[s.object].mesh, s.x, s.y, s.yaw)});
    }
    scene.images.push_back(std::move(image));
  }
  ds.scenes.push_back(std::move(scene));
  return ds;
}

void put_in_room(SimDataset& ds, const RoomOptions& options, std::uint64_t seed) {
  if (!ds.T_world_camera) throw Error("room: this dataset's camera moves; only a fixed camera's table can be put in a room");
  const Transform T_world_camera = *ds.T_world_camera;
  const Transform T_camera_world = T_world_camera.inverse();
  std::vector<double> radius;
  for (const auto& o : ds.objects) radius.push_back(footprint_radius(o.mesh));
  // Where the known objects stand in every image: the room's table must hold them all.
  std::vector<std::vector<Footprints::Disc>> known;
  PlanRect cover{1e9, 1e9, -1e9, -1e9};
  for (const SimScene& scene : ds.scenes) {
    for (const SimImage& image : scene.images) {
      auto& discs = known.emplace_back();
      for (const ObjectPlacement& p : image.objects) {
        if (p.object >= ds.objects.size()) throw Error("room: a placement names an object that does not exist");
        const Eigen::Vector3d at = (T_world_camera * p.T_camera_object).translation();
        discs.push_back({at.x(), at.y(), radius[p.object]});
        cover = {std::min(cover.x0, at.x() - radius[p.object]), std::min(cover.y0, at.y() - radius[p.object]),
                 std::max(cover.x1, at.x() + radius[p.object]), std::max(cover.y1, at.y() + radius[p.object])};
      }
    }
  }
  RoomOptions o = options;
  if (cover.x0 <= cover.x1) {
    if (o.table_must_cover) {
      const PlanRect& c = *o.table_must_cover;
      cover = {std::min(cover.x0, c.x0), std::min(cover.y0, c.y0), std::max(cover.x1, c.x1), std::max(cover.y1, c.y1)};
    }
    o.table_must_cover = cover;
  }
  const Room room = make_room(o, sub_seed(seed, kRoom));
  ds.background = seen_from(T_camera_world, room.meshes);

  std::vector<Distractor> others;
  for (const auto& m : options.distractor_meshes) others.push_back(standing_distractor(*m));
  const Eigen::Vector3d eye = T_world_camera.translation();
  std::mt19937_64 rng(sub_seed(seed, kTableDistractors));
  std::size_t n_image = 0;
  for (SimScene& scene : ds.scenes) {
    for (SimImage& image : scene.images) {
      const std::vector<Footprints::Disc>& here = known[n_image++];
      Footprints table(room.table_top);
      for (const auto& k : here) table.add(k);
      // Nothing between the camera and a known object: the preset measures what it did.
      const auto clear_of_sight_lines = [&](const Footprints::Disc& d) {
        for (const auto& k : here) {
          const Eigen::Vector2d a(eye.x(), eye.y()), b(k.x, k.y), p(d.x, d.y);
          const double t = std::clamp((p - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-12), 0.0, 1.0);
          if ((a + t * (b - a) - p).norm() < d.r + k.r + 0.02) return false;
        }
        return true;
      };
      const int count = std::uniform_int_distribution<int>(options.min_table_distractors,
                                                          std::max(options.min_table_distractors, options.max_table_distractors))(rng);
      for (int n = 0; n < count; ++n) {
        const Distractor d = make_distractor(rng, others, 0.15, 0.35);
        if (!d.mesh) continue;
        const auto spot = table.place(d.radius, false, rng, clear_of_sight_lines);
        const double yaw = std::uniform_real_distribution<double>(0, 2 * std::numbers::pi)(rng);
        if (spot) image.background.push_back({"distractor", d.mesh, T_camera_world * standing_at(spot->x, spot->y, 0, yaw)});
      }
    }
    scene.description += &scene == &ds.scenes.front() ? "; " + room.description : "; the same room";
  }
}

SimDataset make_room_scenes(const std::vector<ObjectModel>& objects, const CameraIntrinsics& K, const RoomPresetOptions& o,
                            std::uint64_t seed) {
  K.validate();
  if (objects.empty()) throw Error("room: no objects to place");
  if (o.rooms < 1 || o.images < 1) throw Error("room: need at least one room and one image");
  if (o.min_objects < 1 || o.max_objects < o.min_objects) throw Error("room: bad object counts");
  if (!(o.empty_fraction >= 0 && o.empty_fraction <= 1)) throw Error(fmt::format("room: empty fraction {} is not in [0, 1]", o.empty_fraction));
  if (!(o.pile_fraction >= 0 && o.pile_fraction <= 1)) throw Error("room: the pile fraction must be in [0, 1]");
  if (o.camera_heights_m.empty()) throw Error("room: no camera heights");
  for (double h : o.camera_heights_m) {
    if (!(h > 0.05 && h < 2.0)) throw Error(fmt::format("room: camera height {} m above the table is out of range", h));
  }
  SimDataset ds;
  ds.K = K;
  ds.objects = objects;
  std::vector<double> radius;
  for (const auto& obj : objects) radius.push_back(footprint_radius(obj.mesh));
  std::vector<Distractor> others;
  for (const auto& m : o.room.distractor_meshes) others.push_back(standing_distractor(*m));

  std::mt19937_64 rng(sub_seed(seed, kRoomImages));
  const auto uniform = [&rng](double lo, double hi) { return lo < hi ? std::uniform_real_distribution<double>(lo, hi)(rng) : 0.5 * (lo + hi); };
  const auto count_in = [&rng](int lo, int hi) { return std::uniform_int_distribution<int>(lo, std::max(lo, hi))(rng); };
  // Exactly this many negative frames, spread over the rooms by a seeded shuffle.
  std::vector<bool> negative(static_cast<std::size_t>(o.images), false);
  const auto empty = static_cast<std::size_t>(std::lround(o.empty_fraction * o.images));
  std::fill(negative.begin(), negative.begin() + static_cast<std::ptrdiff_t>(empty), true);
  std::shuffle(negative.begin(), negative.end(), rng);

  std::vector<Room> rooms;
  for (int r = 0; r < std::min(o.rooms, o.images); ++r) {
    rooms.push_back(make_room(o.room, sub_seed(seed, kRoom, static_cast<std::uint64_t>(r))));
    SimScene scene;
    scene.scene_id = r + 1;
    ds.scenes.push_back(std::move(scene));
  }
  for (int im = 0; im < o.images; ++im) {
    const std::size_t r = static_cast<std::size_t>(im) % rooms.size();
    const Room& room = rooms[r];
    const PlanRect& top = room.table_top;
    // The pile's centre: on the table, within reach of the sensor's range.
    const double cx = uniform(top.x0 + 0.15, top.x1 - 0.15);
    const double cy = uniform(std::max(top.y0 + 0.15, 0.7), std::min(top.y1 - 0.15, 1.6));
    // The camera: a robot's head at one of a few heights, turned to the pile; for half the
    // negative frames, turned away from the table to the walls and the furniture.
    const double h = o.camera_heights_m[static_cast<std::size_t>(count_in(0, static_cast<int>(o.camera_heights_m.size()) - 1))];
    const Eigen::Vector3d eye(uniform(-0.25, 0.25), 0.0, h);
    double yaw = std::atan2(cx - eye.x(), cy) + uniform(-6, 6) * kDeg;
    double pitch = std::atan2(h - 0.08, std::hypot(cx - eye.x(), cy)) + uniform(-4, 4) * kDeg;
    const bool negative_frame = negative[static_cast<std::size_t>(im)];
    if (negative_frame && uniform(0, 1) < 0.5) {
      yaw = (uniform(0, 1) < 0.5 ? -1 : 1) * uniform(35, 70) * kDeg;
      pitch = uniform(5, 25) * kDeg;
    }
    const Transform T_camera_world = camera_looking(eye, yaw, pitch).inverse();

    // What stands on the table: known objects (none in a negative frame) and unknown ones, the
    // first known one at the pile's centre, most others touching something already there.
    struct Item { bool known; std::size_t object; Distractor distractor; double radius; };
    std::vector<Item> items;
    if (!negative_frame) {
      std::vector<std::size_t> pick(objects.size());
      for (std::size_t i = 0; i < pick.size(); ++i) pick[i] = i;
      std::shuffle(pick.begin(), pick.end(), rng);
      const int count = count_in(o.min_objects, o.max_objects);
      for (int n = 0; n < count; ++n) {
        const std::size_t obj = pick[static_cast<std::size_t>(n) % pick.size()];
        items.push_back({true, obj, {}, radius[obj]});
      }
    }
    const int unknown = count_in(o.room.min_table_distractors, o.room.max_table_distractors);
    for (int n = 0; n < unknown; ++n) {
      Distractor d = make_distractor(rng, others, 0.15, 0.35);
      if (d.mesh) items.push_back({false, 0, d, d.radius});
    }
    if (items.size() > 1) std::shuffle(items.begin() + (negative_frame ? 0 : 1), items.end(), rng);
    Footprints table(top);
    SimImage image;
    for (std::size_t n = 0; n < items.size(); ++n) {
      const Item& item = items[n];
      const bool touching = n > 0 && uniform(0, 1) < o.pile_fraction;
      // Known objects stay within 45 cm of the pile's centre, in view; unknown ones go anywhere.
      const auto in_view = [&](const Footprints::Disc& d) { return std::hypot(d.x - cx, d.y - cy) <= 0.45; };
      std::optional<Footprints::Disc> spot;
      if (n == 0) spot = table.place_around(item.radius, cx, cy, 0.05, rng);
      else if (item.known && !touching) spot = table.place_around(item.radius, cx, cy, 0.45, rng);
      else spot = table.place(item.radius, touching, rng, item.known ? std::function<bool(const Footprints::Disc&)>(in_view) : nullptr);
      const double turn = uniform(0, 2 * std::numbers::pi);
      if (!spot) continue;
      if (item.known) {
        image.objects.push_back({item.object, T_camera_world * standing_pose(objects[item.object].mesh, spot->x, spot->y, turn)});
      } else {
        image.background.push_back({"distractor", item.distractor.mesh, T_camera_world * standing_at(spot->x, spot->y, 0, turn)});
      }
    }
    std::vector<BackgroundMesh> room_seen = seen_from(T_camera_world, room.meshes);
    image.background.insert(image.background.begin(), room_seen.begin(), room_seen.end());
    ds.scenes[r].images.push_back(std::move(image));
  }
  for (std::size_t r = 0; r < rooms.size(); ++r) {
    std::size_t without = 0;
    for (const SimImage& im : ds.scenes[r].images) without += im.objects.empty() ? 1 : 0;
    ds.scenes[r].description = fmt::format("{} without a known object; {}", without, rooms[r].description);
  }
  return ds;
}

SimulatedFrame simulate_image(const SimDataset& ds, const SimImage& image, const SensorModel& sensor, std::uint64_t seed) {
  std::vector<MeshInstance> instances;
  for (const ObjectPlacement& p : image.objects) {
    if (p.object >= ds.objects.size()) throw Error("simulate: a placement names an object that does not exist");
    instances.push_back({&ds.objects[p.object].mesh, p.T_camera_object});
  }
  for (const auto* background : {&ds.background, &image.background}) {
    for (const BackgroundMesh& b : *background) {
      if (!b.mesh) throw Error("simulate: a background entry has no mesh");
      instances.push_back({b.mesh.get(), b.T_camera_mesh});
    }
  }
  RenderOptions with_normals;
  with_normals.normals = true;
  const RenderedFrame full = render(instances, ds.K, with_normals);
  SimulatedFrame out;
  out.depth = simulate_sensor(full, ds.K, sensor, seed);
  for (std::size_t i = 0; i < image.objects.size(); ++i) {
    const RenderedFrame alone = render(std::span(&instances[i], 1), ds.K);
    GroundTruthInfo info;
    int u_min = ds.K.width, v_min = ds.K.height, u_max = -1, v_max = -1;
    int vu_min = ds.K.width, vv_min = ds.K.height, vu_max = -1, vv_max = -1;
    for (int v = 0; v < ds.K.height; ++v) {
      for (int u = 0; u < ds.K.width; ++u) {
        const std::size_t px = static_cast<std::size_t>(v) * static_cast<std::size_t>(ds.K.width) + static_cast<std::size_t>(u);
        if (alone.instance[px] < 0) continue;
        ++info.px_count_all;
        u_min = std::min(u_min, u); u_max = std::max(u_max, u); v_min = std::min(v_min, v); v_max = std::max(v_max, v);
        if (std::isfinite(out.depth.depth_m[px])) ++info.px_count_valid;
        if (full.instance[px] == static_cast<std::int32_t>(i)) {
          ++info.px_count_visib;
          vu_min = std::min(vu_min, u); vu_max = std::max(vu_max, u); vv_min = std::min(vv_min, v); vv_max = std::max(vv_max, v);
        }
      }
    }
    if (u_max >= 0) info.bbox_obj = {u_min, v_min, u_max - u_min + 1, v_max - v_min + 1};
    if (vu_max >= 0) info.bbox_visib = {vu_min, vv_min, vu_max - vu_min + 1, vv_max - vv_min + 1};
    info.visib_fract = info.px_count_all > 0 ? static_cast<double>(info.px_count_visib) / info.px_count_all : 0.0;
    out.gt.push_back({ds.objects[image.objects[i].object].id, image.objects[i].T_camera_object});
    out.gt_info.push_back(info);
  }
  return out;
}

}  // namespace viewpose
