#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/bop_writer.hpp"
#include "viewpose/simulate/room.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

// A quarter-VGA camera: rooms are big, the tests should not be.
CameraIntrinsics small_camera() {
  CameraIntrinsics k = K;
  k.fx = k.fy = 525.0 / 4;
  k.cx = 79.5;
  k.cy = 59.5;
  k.width = 160;
  k.height = 120;
  return k;
}

// The presets' camera: above the origin at `height`, facing +y, pitched down (z up, table top z = 0).
Transform camera_at(double height, double pitch_deg) {
  const double p = pitch_deg * std::numbers::pi / 180;
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(1, 0, 0);
  R.col(1) = Eigen::Vector3d(0, -std::sin(p), -std::cos(p));
  R.col(2) = Eigen::Vector3d(0, std::cos(p), -std::sin(p));
  return make_transform(R, Eigen::Vector3d(0, 0, height));
}

// A room with nothing in it but walls, floor, ceiling and a table, all at fixed distances.
RoomOptions bare_room() {
  RoomOptions o;
  o.back_wall_m = {3.5, 3.5};
  o.side_wall_m = {1.6, 1.6};
  o.table_height_m = {0.75, 0.75};
  o.table_width_m = {0.9, 0.9};
  o.table_depth_m = {0.7, 0.7};
  o.table_near_edge_m = {0.5, 0.5};
  o.table_centre_x_m = {0.0, 0.0};
  o.min_furniture = o.max_furniture = 0;
  o.min_off_table_distractors = o.max_off_table_distractors = 0;
  return o;
}

std::vector<ObjectModel> known_objects() { return {{1, "jug", make_jug()}, {2, "box", make_named_shape("box")}}; }

TEST(Room, WallsAndFloorAreAtTheDistancesAsked) {
  const Room room = make_room(bare_room(), 3);
  EXPECT_DOUBLE_EQ(room.back_wall_y, 3.5);
  EXPECT_DOUBLE_EQ(room.left_wall_x, -1.6);
  EXPECT_DOUBLE_EQ(room.right_wall_x, 1.6);
  EXPECT_DOUBLE_EQ(room.floor_z, -0.75);
  const Transform T_world_camera = camera_at(0.45, 18.0);
  const Transform T_camera_world = T_world_camera.inverse();
  std::vector<MeshInstance> instances;
  for (const WorldMesh& m : room.meshes) instances.push_back({m.mesh.get(), T_camera_world * m.T_world_mesh});
  const RenderedFrame f = render(instances, K);
  // Every floor and wall pixel lies on its plane: its depth is where the pixel's ray meets it.
  int floor_px = 0, back_px = 0, side_px = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v * K.width + u);
      if (f.instance[i] < 0) continue;
      const std::string& kind = room.meshes[static_cast<std::size_t>(f.instance[i])].kind;
      const Eigen::Vector3d ray = T_world_camera.linear() * K.unproject(u, v, 1.0);  // world direction, depth 1
      const Eigen::Vector3d eye = T_world_camera.translation();
      const double z = f.depth.depth_m[i];
      if (kind == "floor") {
        ++floor_px;
        EXPECT_NEAR(z, (room.floor_z - eye.z()) / ray.z(), 1e-4 * z) << u << "," << v;
      } else if (kind == "wall") {
        // The nearest of the three walls the ray meets ahead.
        double nearest = 1e9;
        if (ray.y() > 0) nearest = std::min(nearest, (room.back_wall_y - eye.y()) / ray.y());
        if (ray.x() < 0) nearest = std::min(nearest, (room.left_wall_x - eye.x()) / ray.x());
        if (ray.x() > 0) nearest = std::min(nearest, (room.right_wall_x - eye.x()) / ray.x());
        EXPECT_NEAR(z, nearest, 1e-4 * z) << u << "," << v;
        const Eigen::Vector3d p = eye + z * ray;
        (std::abs(p.y() - room.back_wall_y) < 1e-3 ? back_px : side_px) += 1;
      }
    }
  }
  // The table ends: the floor shows beyond and beside it, and the walls behind it.
  EXPECT_GT(floor_px, 20000) << "back " << back_px << ", sides " << side_px;
  EXPECT_GT(back_px, 20000);
  EXPECT_GT(side_px, 2000);
  // Looking level, the optical axis meets the back wall 3.5 m away; through the sensor model the
  // median depth there stays within a disparity step of it.
  const Transform level = camera_at(0.45, 0.0);
  instances.clear();
  for (const WorldMesh& m : room.meshes) instances.push_back({m.mesh.get(), level.inverse() * m.T_world_mesh});
  RenderOptions with_normals;
  with_normals.normals = true;
  const RenderedFrame ahead = render(instances, K, with_normals);
  EXPECT_NEAR(ahead.depth.at(320, 240), 3.5, 1e-6);
  const DepthImage sensed = simulate_sensor(ahead, K, SensorModel::kinect_v1(), 5);
  std::vector<float> centre;
  for (int v = 220; v < 260; ++v)
    for (int u = 300; u < 340; ++u)
      if (std::isfinite(sensed.at(u, v))) centre.push_back(sensed.at(u, v));
  ASSERT_GT(centre.size(), 1500u);
  std::nth_element(centre.begin(), centre.begin() + static_cast<std::ptrdiff_t>(centre.size() / 2), centre.end());
  EXPECT_NEAR(centre[centre.size() / 2], 3.5, quantization_step(3.5, K.fx, SensorModel::kinect_v1()));
}

TEST(Room, DrawnDistancesStayInTheirRangesAndTheTableHoldsWhatItMust) {
  RoomOptions o;
  o.table_must_cover = PlanRect{-0.2, 0.7, 0.2, 2.1};  // the seed experiment's objects reach 2 m
  int furniture = 0, distractors = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const Room room = make_room(o, seed);
    EXPECT_GE(room.back_wall_y, 2.1 + 0.1 + 0.3 - 1e-9);  // beyond the table it had to grow
    EXPECT_LE(room.back_wall_y, 4.0);
    EXPECT_GE(-room.left_wall_x, 1.5);
    EXPECT_LE(-room.left_wall_x, 4.0);
    EXPECT_GE(room.right_wall_x, 1.5);
    EXPECT_LE(room.right_wall_x, 4.0);
    EXPECT_GE(-room.floor_z, 0.70);
    EXPECT_LE(-room.floor_z, 0.78);
    EXPECT_LE(room.table_top.x0, -0.3);
    EXPECT_GE(room.table_top.y1, 2.2);
    furniture += room.furniture;
    distractors += room.off_table_distractors;
    EXPECT_EQ(room.meshes.size(), 7u + static_cast<std::size_t>(room.furniture + room.off_table_distractors));
  }
  // Furniture and unknown objects are drawn 2-5 and 2-6 a room; a few may not fit.
  EXPECT_GT(furniture, 30 * 2);
  EXPECT_GT(distractors, 30 * 2);
}

TEST(Room, DistractorsStandOnTheirBaseAndFitTheirLimits) {
  std::mt19937_64 rng(4);
  const std::vector<Distractor> others = {standing_distractor(make_mug())};
  for (int n = 0; n < 60; ++n) {
    const Distractor d = make_distractor(rng, others, 0.1, 0.2);
    ASSERT_TRUE(d.mesh);
    const BoundingBox box = bounding_box(*d.mesh);
    EXPECT_NEAR(box.min.z(), 0.0f, 1e-6f);
    EXPECT_NEAR(box.max.z(), d.height, 1e-6);
    EXPECT_LE(d.radius, 0.1 + 1e-6);
    EXPECT_LE(d.height, 0.2 + 1e-6);
  }
  // A blob is smooth and closed, stretched but never more than its bumpiness allows.
  const TriangleMesh blob = make_blob(0.1, 0.3, rng);
  for (const auto& v : blob.vertices) {
    EXPECT_LT(v.norm(), 0.1 * 1.3 * 1.3 + 1e-6);
    EXPECT_GT(v.norm(), 0.1 * 0.75 * 0.7 - 1e-6);
  }
}

TEST(Room, AKnownObjectBehindADistractorIsPartlyHidden) {
  // A 20 cm cube 1.5 m away; an unknown board at 1 m whose right edge lies on the optical axis
  // hides exactly the left half of its columns. The board is background: no ground truth.
  SimDataset ds;
  ds.K = K;
  ds.objects = {{1, "cube", make_box_mesh({0.2f, 0.2f, 0.2f})}};
  const auto board = std::make_shared<const TriangleMesh>(make_box_mesh({0.3f, 0.6f, 0.01f}));
  const Transform cube_at = make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.5});
  const Transform board_at = make_transform(Eigen::Matrix3d::Identity(), {-0.15, 0, 1.0});
  SimImage image({{0, cube_at}}, {{"distractor", board, board_at}});
  const SimulatedFrame hidden = simulate_image(ds, image, SensorModel::ideal(), 1);
  ASSERT_EQ(hidden.gt.size(), 1u);
  EXPECT_NEAR(hidden.gt_info[0].visib_fract, 0.5, 0.02);
  // Moved 30 cm left, the board hides nothing; in front of the cube's centre, everything.
  image.background[0].T_camera_mesh = make_transform(Eigen::Matrix3d::Identity(), {-0.45, 0, 1.0});
  EXPECT_EQ(simulate_image(ds, image, SensorModel::ideal(), 1).gt_info[0].visib_fract, 1.0);
  image.background[0].T_camera_mesh = make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.0});
  EXPECT_EQ(simulate_image(ds, image, SensorModel::ideal(), 1).gt_info[0].visib_fract, 0.0);
  // The same board as the dataset's background (seen in every image) hides the same half.
  ds.background = image.background;
  ds.background[0].T_camera_mesh = board_at;
  EXPECT_NEAR(simulate_image(ds, SimImage({{0, cube_at}}), SensorModel::ideal(), 1).gt_info[0].visib_fract, 0.5, 0.02);
}

TEST(Room, GroundTruthOfKnownObjectsMatchesTheRenderedDepth) {
  const CameraIntrinsics k = small_camera();
  RoomPresetOptions o;
  o.rooms = 2;
  o.images = 6;
  o.empty_fraction = 0;
  const SimDataset ds = make_room_scenes(known_objects(), k, o, 21);
  int partly_hidden = 0, objects = 0;
  for (const SimScene& scene : ds.scenes) {
    for (const SimImage& image : scene.images) {
      const SimulatedFrame f = simulate_image(ds, image, SensorModel::ideal(), 1);
      ASSERT_EQ(f.gt.size(), image.objects.size());
      ASSERT_GE(f.gt.size(), 1u);
      for (std::size_t g = 0; g < f.gt.size(); ++g) {
        const TriangleMesh& mesh = ds.objects[image.objects[g].object].mesh;
        EXPECT_EQ(f.gt[g].obj_id, ds.objects[image.objects[g].object].id);
        EXPECT_TRUE(f.gt[g].T_camera_object.isApprox(image.objects[g].T_camera_object));
        // The object alone at its ground-truth pose: where it is visible, the frame shows exactly its
        // depth; nowhere does the frame show something behind it.
        const MeshInstance alone{&mesh, f.gt[g].T_camera_object};
        const RenderedFrame a = render(std::span(&alone, 1), k);
        int same = 0;
        for (std::size_t i = 0; i < a.depth.depth_m.size(); ++i) {
          if (!std::isfinite(a.depth.depth_m[i])) continue;
          EXPECT_LE(f.depth.depth_m[i], a.depth.depth_m[i] + 1e-6f);
          if (f.depth.depth_m[i] == a.depth.depth_m[i]) {
            ++same;
            // And the point seen there lies on the model at that pose.
            const int u = static_cast<int>(i % static_cast<std::size_t>(k.width)), v = static_cast<int>(i / static_cast<std::size_t>(k.width));
            const Eigen::Vector3d p = k.unproject(u, v, f.depth.depth_m[i]);
            if (i % 5 == 0) {
              EXPECT_LT(distance_to_surface(mesh, f.gt[g].T_camera_object.inverse() * p), 1e-4);
            }
          }
        }
        EXPECT_NEAR(same, f.gt_info[g].px_count_visib, 0.01 * f.gt_info[g].px_count_visib + 1);
        EXPECT_EQ(a.depth.depth_m.size() - static_cast<std::size_t>(std::count_if(a.depth.depth_m.begin(), a.depth.depth_m.end(), [](float z) { return std::isnan(z); })),
                  static_cast<std::size_t>(f.gt_info[g].px_count_all));
        ++objects;
        partly_hidden += f.gt_info[g].visib_fract < 0.95 ? 1 : 0;
      }
    }
  }
  EXPECT_GE(objects, 6);
  EXPECT_GT(partly_hidden, 0) << "piles should hide parts of some known objects";
}

TEST(Room, NegativeFramesHaveNoGroundTruthAndShowTheRoom) {
  const CameraIntrinsics k = small_camera();
  RoomPresetOptions o;
  o.rooms = 2;
  o.images = 8;
  o.empty_fraction = 0.5;
  const SimDataset ds = make_room_scenes(known_objects(), k, o, 8);
  test::TempDir dir;
  write_bop_dataset(dir.path(), ds, {});
  const BopDataset bop = open_bop_dataset(dir.path(), "test");
  ASSERT_EQ(bop.images.size(), 8u);
  int negatives = 0;
  for (const BopImage& im : bop.images) {
    const SimImage& image = ds.scenes[static_cast<std::size_t>(im.scene_id - 1)].images[static_cast<std::size_t>(im.im_id)];
    EXPECT_EQ(im.gt.size(), image.objects.size());
    if (!im.gt.empty()) continue;
    ++negatives;
    EXPECT_TRUE(im.gt_info.empty());
    // Nothing of a known object in it, yet a room full of things to see.
    EXPECT_TRUE(image.objects.empty());
    const BopFrame frame = load_bop_frame(im);
    const auto valid = std::count_if(frame.depth.depth_m.begin(), frame.depth.depth_m.end(), [](float z) { return std::isfinite(z); });
    EXPECT_GT(valid, k.width * k.height / 2);
    EXPECT_GT(image.background.size(), 7u);
  }
  EXPECT_EQ(negatives, 4);
}

TEST(Room, SameSeedSameRoomsOtherSeedOtherRooms) {
  const CameraIntrinsics k = small_camera();
  RoomPresetOptions o;
  o.rooms = 1;
  o.images = 2;
  o.empty_fraction = 0;
  const auto frame = [&](std::uint64_t seed) {
    const SimDataset ds = make_room_scenes(known_objects(), k, o, seed);
    return simulate_image(ds, ds.scenes[0].images[1], SensorModel::kinect_v1(), 7).depth;
  };
  const DepthImage a = frame(5), b = frame(5), c = frame(6);
  EXPECT_EQ(std::memcmp(a.depth_m.data(), b.depth_m.data(), a.depth_m.size() * sizeof(float)), 0);
  EXPECT_NE(std::memcmp(a.depth_m.data(), c.depth_m.data(), a.depth_m.size() * sizeof(float)), 0);
  EXPECT_NE(make_room({}, 5).description, make_room({}, 6).description);
  EXPECT_EQ(make_room({}, 5).description, make_room({}, 5).description);
}

TEST(Room, SeedExperimentInARoomKeepsItsPosesAndItsClearView) {
  ObjectModel jug{1, "jug", make_jug()};
  SeedExperimentOptions se;
  se.orientations = 2;
  se.distances_m = {0.75, 2.0};
  const SimDataset plain = make_seed_experiment(jug, K, se, 5);
  // Without a room: the endless table, nothing else.
  ASSERT_EQ(plain.background.size(), 1u);
  EXPECT_EQ(plain.background[0].kind, "table");
  SimDataset roomy = plain;
  put_in_room(roomy, RoomOptions{}, 5);
  EXPECT_GT(roomy.background.size(), 7u);
  int distractors = 0;
  for (std::size_t s = 0; s < plain.scenes.size(); ++s) {
    for (std::size_t i = 0; i < plain.scenes[s].images.size(); ++i) {
      const SimImage& a = plain.scenes[s].images[i];
      const SimImage& b = roomy.scenes[s].images[i];
      EXPECT_TRUE(a.background.empty());
      ASSERT_EQ(b.objects.size(), 1u);
      EXPECT_TRUE(b.objects[0].T_camera_object.isApprox(a.objects[0].T_camera_object, 0));
      distractors += static_cast<int>(b.background.size());
      // Nothing stands between the camera and the jug: it is as visible as on the endless table.
      const SimulatedFrame f = simulate_image(roomy, b, SensorModel::ideal(), 1);
      EXPECT_GT(f.gt_info[0].visib_fract, 0.99);
    }
  }
  EXPECT_GT(distractors, 0);
  // Clutter in a room: the same poses too; a dataset whose camera moves cannot be put in one.
  ClutterOptions cl;
  cl.images = 3;
  const SimDataset clutter = make_clutter(known_objects(), K, cl, 2);
  SimDataset clutter_room = clutter;
  put_in_room(clutter_room, RoomOptions{}, 2);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_EQ(clutter_room.scenes[0].images[i].objects.size(), clutter.scenes[0].images[i].objects.size());
  }
  SimDataset moving = make_room_scenes(known_objects(), small_camera(), RoomPresetOptions{}, 1);
  EXPECT_THROW(put_in_room(moving, RoomOptions{}, 1), Error);
}

TEST(Room, BadOptionsAreRefused) {
  RoomOptions o;
  o.back_wall_m = {3.0, 2.0};
  EXPECT_THROW(make_room(o, 1), Error);
  RoomPresetOptions p;
  p.empty_fraction = 1.5;
  EXPECT_THROW(make_room_scenes(known_objects(), K, p, 1), Error);
  p = {};
  p.camera_heights_m = {};
  EXPECT_THROW(make_room_scenes(known_objects(), K, p, 1), Error);
  EXPECT_THROW(make_room_scenes({}, K, RoomPresetOptions{}, 1), Error);
}

}  // namespace
}  // namespace viewpose
