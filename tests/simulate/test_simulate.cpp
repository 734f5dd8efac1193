#include <cmath>

#include "test_support.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/ply.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/bop_writer.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

Transform at(double x, double y, double z) { return make_transform(Eigen::Matrix3d::Identity(), {x, y, z}); }

TEST(Simulate, VisibilityFractionAgainstAKnownOccluder) {
  // A 20 cm cube 1.5 m away, its silhouette's left half (x < 0) hidden by a board at 1 m whose
  // right edge lies on the optical axis: exactly half of its pixel columns stay visible.
  SimDataset ds;
  ds.K = K;
  ds.objects = {{1, "cube", make_box_mesh({0.2f, 0.2f, 0.2f})}, {2, "board", make_box_mesh({0.3f, 0.6f, 0.01f})}};
  const SimImage image{{{0, at(0, 0, 1.5)}, {1, at(-0.15, 0, 1.0)}}};
  const SimulatedFrame f = simulate_image(ds, image, SensorModel::ideal(), 1);
  ASSERT_EQ(f.gt_info.size(), 2u);
  EXPECT_NEAR(f.gt_info[0].visib_fract, 0.5, 0.02);
  EXPECT_EQ(f.gt_info[1].visib_fract, 1.0);
  EXPECT_EQ(f.gt_info[0].px_count_valid, f.gt_info[0].px_count_all);  // noise-free: every pixel has depth
  // The visible box is the right half of the whole box.
  EXPECT_EQ(f.gt_info[0].bbox_visib[0] + f.gt_info[0].bbox_visib[2], f.gt_info[0].bbox_obj[0] + f.gt_info[0].bbox_obj[2]);
  EXPECT_NEAR(f.gt_info[0].bbox_visib[2], f.gt_info[0].bbox_obj[2] / 2.0, 1.0);
  EXPECT_EQ(f.gt[1].obj_id, 2);
}

TEST(Simulate, SeedExperimentPutsTheNearestSurfaceAtEachDistance) {
  ObjectModel jug{1, "jug", make_jug()};
  SeedExperimentOptions o;
  o.orientations = 4;
  const SimDataset ds = make_seed_experiment(jug, K, o, 5);
  ASSERT_EQ(ds.scenes.size(), 5u);
  for (std::size_t s = 0; s < ds.scenes.size(); ++s) {
    const double distance = o.distances_m[s];
    ASSERT_EQ(ds.scenes[s].images.size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) {
      const Transform& T = ds.scenes[s].images[k].objects[0].T_camera_object;
      EXPECT_NEAR(distance_to_surface(jug.mesh, T.inverse() * Eigen::Vector3d::Zero()), distance, 1e-4);
      // The same orientation at every distance (the camera does not move).
      EXPECT_LT(rotation_difference_deg(T.linear(), ds.scenes[0].images[k].objects[0].T_camera_object.linear()), 1e-9);
    }
    // And the closest pixel the camera sees on the object agrees, within the pixel spacing.
    SimDataset object_only = ds;
    object_only.background.clear();
    const SimulatedFrame f = simulate_image(object_only, ds.scenes[s].images[0], SensorModel::ideal(), 1);
    const PointCloud cloud = depth_to_cloud(f.depth, K);
    const Transform& T = ds.scenes[s].images[0].objects[0].T_camera_object;
    double nearest = 1e9;
    for (const auto& p : cloud.points) {
      if (!p.allFinite() || p.norm() > distance + 0.01) continue;  // only candidates near the answer
      if (distance_to_surface(jug.mesh, T.inverse() * p.cast<double>()) < 0.001) {
        nearest = std::min(nearest, static_cast<double>(p.norm()));
      }
    }
    EXPECT_NEAR(nearest, distance, 0.004) << "scene " << s;
    EXPECT_GT(f.gt_info[0].visib_fract, 0.99);  // standing alone on the table, nothing hides it
  }
}

TEST(Simulate, DatasetReadsBackThroughTheBopReaderWithItsGroundTruth) {
  test::TempDir dir;
  ObjectModel jug{7, "jug", make_jug()};
  SeedExperimentOptions o;
  o.orientations = 2;
  o.distances_m = {0.75, 1.5};
  const SimDataset ds = make_seed_experiment(jug, K, o, 9);
  BopWriteOptions w;
  w.sensor = SensorModel::ideal();
  std::size_t progress_calls = 0;
  w.progress = [&](std::size_t done, std::size_t total) {
    ++progress_calls;
    EXPECT_LE(done, total);
  };
  write_bop_dataset(dir.path(), ds, w);
  EXPECT_EQ(progress_calls, 4u);

  const BopDataset bop = open_bop_dataset(dir.path(), "test");
  ASSERT_EQ(bop.images.size(), 4u);
  ASSERT_EQ(bop.models.count(7), 1u);
  EXPECT_NEAR(bop.models.at(7).diameter_m, mesh_diameter(jug.mesh), 1e-9);
  // The model file is in millimetres and matches the mesh.
  const PlyFile model = read_ply(bop.model_files.at(7));
  EXPECT_TRUE((bounding_box(model.mesh).size() / 1000.0f).isApprox(bounding_box(jug.mesh).size(), 1e-5f));
  for (const BopImage& im : bop.images) {
    ASSERT_EQ(im.gt.size(), 1u);
    const Transform& truth = ds.scenes[static_cast<std::size_t>(im.scene_id - 1)].images[static_cast<std::size_t>(im.im_id)].objects[0].T_camera_object;
    EXPECT_TRUE(im.gt[0].T_camera_object.isApprox(truth, 1e-9));
    // Every object pixel of the noise-free depth, carried into the object frame by the ground
    // truth, lies on the model (within the 1 mm rounding of the PNG).
    const BopFrame frame = load_bop_frame(im);
    const PointCloud cloud = depth_to_cloud(frame.depth, frame.K);
    int on_object = 0;
    const double reach = 0.5 * mesh_diameter(jug.mesh) + 0.01;  // nothing farther from its centre is on it
    for (std::size_t i = 0; i < cloud.size(); i += 7) {
      if (!cloud.points[i].allFinite() || (cloud.points[i].cast<double>() - truth.translation()).norm() > reach) continue;
      const double d = distance_to_surface(jug.mesh, truth.inverse() * cloud.points[i].cast<double>());
      if (d < 0.0015) ++on_object;
    }
    const GroundTruthInfo& info = im.gt_info.at(0);
    EXPECT_NEAR(on_object, info.px_count_visib / 7.0, 0.05 * info.px_count_visib / 7.0 + 3);
  }
}

TEST(Simulate, ClutterPlacesTwoToFiveObjectsThatDoNotOverlap) {
  std::vector<ObjectModel> objects;
  for (const auto& name : shape_names()) objects.push_back({static_cast<int>(objects.size()) + 1, name, make_named_shape(name)});
  ClutterOptions o;
  o.images = 6;
  const SimDataset ds = make_clutter(objects, K, o, 11);
  ASSERT_EQ(ds.scenes.size(), 1u);
  ASSERT_EQ(ds.scenes[0].images.size(), 6u);
  int partly_hidden = 0;
  for (const SimImage& im : ds.scenes[0].images) {
    ASSERT_GE(im.objects.size(), 2u);
    ASSERT_LE(im.objects.size(), 5u);
    // Object centres are at least the sum of the footprint radii apart horizontally.
    for (std::size_t a = 0; a < im.objects.size(); ++a) {
      for (std::size_t b = a + 1; b < im.objects.size(); ++b) {
        const Eigen::Vector3d d = im.objects[a].T_camera_object.translation() - im.objects[b].T_camera_object.translation();
        EXPECT_GT(d.norm(), 0.02);
      }
    }
    const SimulatedFrame f = simulate_image(ds, im, SensorModel::kinect_v1(), 3);
    for (const auto& info : f.gt_info) {
      EXPECT_GT(info.px_count_all, 100);
      partly_hidden += info.visib_fract < 0.95 ? 1 : 0;
    }
  }
  EXPECT_GT(partly_hidden, 0) << "clutter should hide parts of some objects";
}

}  // namespace
}  // namespace viewpose
