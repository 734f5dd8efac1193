#include <omp.h>

#include <cmath>
#include <numbers>

#include "test_support.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

RenderedFrame wall_at(double z, const TriangleMesh& wall) {
  const MeshInstance inst{&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, z})};
  RenderOptions o;
  o.normals = true;
  return render(std::span(&inst, 1), K, o);
}

// Mean and standard deviation of the valid depths in the central 200 x 200 pixels.
std::pair<double, double> stats(const DepthImage& d) {
  double s = 0, ss = 0;
  int n = 0;
  for (int v = 140; v < 340; ++v)
    for (int u = 220; u < 420; ++u) {
      const float z = d.at(u, v);
      if (!std::isfinite(z)) continue;
      s += z;
      ss += static_cast<double>(z) * z;
      ++n;
    }
  const double mean = s / n;
  return {mean, std::sqrt(ss / n - mean * mean)};
}

TEST(SensorModel, NoiseOnAFlatWallHasTheDocumentedSigma) {
  // docs/SENSOR_MODEL.md: sigma(z) = 1.2 mm + 1.9 mm/m^2 (z - 0.4)^2 at normal incidence (Nguyen 2012),
  // quantization included: 1.88 mm at 1 m and 6.06 mm at 2 m.
  const TriangleMesh wall = test::square(5.0f);
  for (const double z : {1.0, 2.0}) {
    const auto [mean, sigma] = stats(simulate_sensor(wall_at(z, wall), K, SensorModel::kinect_v1(), 42));
    const double expected = axial_noise_sigma(z, 0.0);
    EXPECT_NEAR(sigma, expected, 0.2 * expected) << "at " << z << " m";
    EXPECT_NEAR(mean, z, 0.25 * expected) << "noise should be unbiased at " << z << " m";
  }
  EXPECT_NEAR(axial_noise_sigma(1.0, 0.0), 0.001884, 1e-6);
  EXPECT_NEAR(axial_noise_sigma(2.0, 0.0), 0.006064, 1e-6);
}

TEST(SensorModel, DisparityQuantizationMakesDiscreteDepthLevels) {
  SensorModel m = SensorModel::ideal();
  m.quantize = true;
  // At 2 m the levels are z^2 / (8 fx b) = 12.7 mm apart for fx = 525, b = 7.5 cm.
  EXPECT_NEAR(quantization_step(2.0, K.fx, m), 4.0 / (8 * 525 * 0.075), 1e-12);
  const TriangleMesh wall = test::square(5.0f);
  const DepthImage d = simulate_sensor(wall_at(2.0, wall), K, m, 1);
  const double disparity = K.fx * m.baseline_m / d.at(320, 240);
  EXPECT_NEAR(disparity * 8, std::round(disparity * 8), 1e-3);  // a whole number of 1/8 pixels
  EXPECT_NEAR(d.at(320, 240), 2.0, quantization_step(2.0, K.fx, m) / 2 + 1e-6);
}

TEST(SensorModel, IdealModelPassesTheRenderThroughUnchanged) {
  const TriangleMesh wall = test::square(5.0f);
  const RenderedFrame f = wall_at(1.3, wall);
  const DepthImage d = simulate_sensor(f, K, SensorModel::ideal(), 7);
  EXPECT_EQ(std::memcmp(d.depth_m.data(), f.depth.depth_m.data(), d.depth_m.size() * sizeof(float)), 0);
}

TEST(SensorModel, SameSeedSameFrameOtherSeedOtherNoise) {
  const TriangleMesh wall = test::square(5.0f);
  const RenderedFrame f = wall_at(1.5, wall);
  const DepthImage a = simulate_sensor(f, K, SensorModel::kinect_v1(), 3);
  const DepthImage b = simulate_sensor(f, K, SensorModel::kinect_v1(), 3);
  const DepthImage c = simulate_sensor(f, K, SensorModel::kinect_v1(), 4);
  EXPECT_EQ(std::memcmp(a.depth_m.data(), b.depth_m.data(), a.depth_m.size() * sizeof(float)), 0);
  EXPECT_NE(std::memcmp(a.depth_m.data(), c.depth_m.data(), a.depth_m.size() * sizeof(float)), 0);
}

TEST(SensorModel, OutputDoesNotDependOnTheThreadCount) {
  const TriangleMesh wall = test::square(5.0f), card = test::square(0.2f);
  const MeshInstance scene[] = {{&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 2.0})},
                                {&card, make_transform(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix(), {0.1, 0, 1.0})}};
  RenderOptions o;
  o.normals = true;
  const RenderedFrame f = render(scene, K, o);
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const DepthImage one = simulate_sensor(f, K, SensorModel::kinect_v1(), 99);
  omp_set_num_threads(4);
  const DepthImage four = simulate_sensor(f, K, SensorModel::kinect_v1(), 99);
  omp_set_num_threads(before);
  EXPECT_EQ(std::memcmp(one.depth_m.data(), four.depth_m.data(), one.depth_m.size() * sizeof(float)), 0);
}

TEST(SensorModel, ProjectorShadowFallsLeftOfAnObjectWithTheExpectedWidth) {
  // A card at 1 m in front of a wall at 1.5 m; the projector 7.5 cm to the right (+x) cannot light
  // fx b (1/1 - 1/1.5) = 13.1 pixels of wall just left of the card.
  const TriangleMesh wall = test::square(5.0f), card = test::square(0.15f);
  const MeshInstance scene[] = {{&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.5})},
                                {&card, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.0})}};
  RenderOptions o;
  o.normals = true;
  const RenderedFrame f = render(scene, K, o);
  SensorModel m = SensorModel::ideal();
  m.shadows = true;
  const DepthImage d = simulate_sensor(f, K, m, 1);
  const int card_left = static_cast<int>(std::ceil(K.cx - K.fx * 0.15));  // first card column
  int shadow_left = 0, shadow_right = 0;
  for (int u = 0; u < card_left; ++u) shadow_left += std::isfinite(d.at(u, 240)) ? 0 : 1;
  for (int u = card_left + 160; u < 640; ++u) shadow_right += std::isfinite(d.at(u, 240)) ? 0 : 1;
  EXPECT_NEAR(shadow_left, K.fx * 0.075 * (1 / 1.0 - 1 / 1.5), 1.5);
  EXPECT_EQ(shadow_right, 0);
  EXPECT_TRUE(std::isfinite(d.at(card_left + 5, 240)));  // the card itself is lit
}

TEST(SensorModel, RangeLimitsAndGrazingAnglesLoseData) {
  const TriangleMesh wall = test::square(20.0f);
  SensorModel m = SensorModel::ideal();
  m.range_limits = true;
  EXPECT_EQ(simulate_sensor(wall_at(5.0, wall), K, m, 1).count_valid(), 0u);
  EXPECT_EQ(simulate_sensor(wall_at(0.3, wall), K, m, 1).count_valid(), 0u);
  EXPECT_EQ(simulate_sensor(wall_at(2.0, wall), K, m, 1).count_valid(), 640u * 480u);
  // A wall turned 80 degrees away: each pixel is dropped by its own incidence angle, never below
  // 70 degrees, always beyond 85.
  SensorModel g = SensorModel::ideal();
  g.grazing_dropout = true;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(80 * std::numbers::pi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const MeshInstance inst{&wall, make_transform(R, {0, 0, 3})};
  RenderOptions o;
  o.normals = true;
  const RenderedFrame f = render(std::span(&inst, 1), K, o);
  const DepthImage d = simulate_sensor(f, K, g, 1);
  int low = 0, high = 0;
  for (int v = 0; v < K.height; v += 4) {
    for (int u = 0; u < K.width; u += 4) {
      const std::size_t i = static_cast<std::size_t>(v) * 640 + static_cast<std::size_t>(u);
      if (!std::isfinite(f.depth.depth_m[i])) continue;
      const Eigen::Vector3f ray = K.unproject(u, v, 1.0).cast<float>().normalized();
      const double theta = std::acos(std::clamp(-f.normal[i].dot(ray), -1.0f, 1.0f)) * 180 / std::numbers::pi;
      if (theta < 69.5) {
        EXPECT_TRUE(std::isfinite(d.depth_m[i])) << u << "," << v << " at " << theta;
        ++low;
      } else if (theta > 85.5) {
        EXPECT_FALSE(std::isfinite(d.depth_m[i])) << u << "," << v << " at " << theta;
        ++high;
      }
    }
  }
  EXPECT_GT(low, 100);
  EXPECT_GT(high, 100);
}

TEST(SensorModel, RefusesFramesWithoutNormals) {
  const TriangleMesh wall = test::square(5.0f);
  const MeshInstance inst{&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1})};
  const RenderedFrame f = render(std::span(&inst, 1), K);
  test::expect_error([&] { simulate_sensor(f, K, SensorModel::kinect_v1(), 1); }, "no normals");
}

}  // namespace
}  // namespace viewpose
