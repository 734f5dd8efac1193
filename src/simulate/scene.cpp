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

// A 3 x 4 m table top (2 cm thick) in front of the camera, top face at z = 0.
TriangleMesh table_mesh() { return make_box_mesh({3.0f, 4.0f, 0.02f}); }
Transform table_in_world() { return make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 2.2, -0.01)); }

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
  ds.table = table_mesh();
  ds.T_camera_table = T_camera_world * table_in_world();
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
      scene.images.push_back(SimImage{{ObjectPlacement{0, T_camera_world * T_world_object}}});
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
  ds.table = table_mesh();
  ds.T_camera_table = T_camera_world * table_in_world();
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

SimulatedFrame simulate_image(const SimDataset& ds, const SimImage& image, const SensorModel& sensor, std::uint64_t seed) {
  std::vector<MeshInstance> instances;
  for (const ObjectPlacement& p : image.objects) {
    if (p.object >= ds.objects.size()) throw Error("simulate: a placement names an object that does not exist");
    instances.push_back({&ds.objects[p.object].mesh, p.T_camera_object});
  }
  if (!ds.table.triangles.empty()) instances.push_back({&ds.table, ds.T_camera_table});
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
