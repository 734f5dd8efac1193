#include "viewpose/pose/points_on_model.hpp"

#include <array>
#include <cmath>
#include <utility>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace viewpose {
namespace {

// A square plate 10 x 10 cm in the object's xy plane, a point every `spacing_m`, its normals along +z.
IcpTarget plate(float spacing_m) {
  std::vector<Eigen::Vector3f> points, normals;
  const int n = static_cast<int>(std::lround(0.05f / spacing_m));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      points.emplace_back(spacing_m * static_cast<float>(i), spacing_m * static_cast<float>(j), 0.0f);
      normals.emplace_back(0.0f, 0.0f, 1.0f);
    }
  return IcpTarget(std::move(points), std::move(normals));
}

// The plate 1 m in front of the camera, turned a little so that no axis lines up with the grid's.
Transform plate_pose() {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())).toRotationMatrix();
  return make_transform(R, Eigen::Vector3d(0.01, -0.02, 1.0));
}

// A point of the plate's frame in the camera's.
Eigen::Vector3f in_camera(const Transform& T_camera_object, float x, float y, float z) {
  return (T_camera_object * Eigen::Vector3d(x, y, z)).cast<float>();
}

// Points around the plate out to 5 cm each way beyond it (past the grid's 4 cm margin), and the
// exact distance of each to the nearest model point (brute force). Seeded: the same points each run.
struct Sampled {
  std::vector<Eigen::Vector3f> points_camera;
  std::vector<float> distance_m;
};
// (Other extents and seeds: points nearer the plate, where most are within a few cells of a tolerance.)
Sampled sample_around(const IcpTarget& model, const Transform& T_camera_object, std::size_t count, float half_xy_m = 0.1f,
                      float half_z_m = 0.05f, unsigned seed = 7) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> xy(-half_xy_m, half_xy_m), z(-half_z_m, half_z_m);
  Sampled s;
  while (s.points_camera.size() < count) {
    const Eigen::Vector3f p_object(xy(random), xy(random), z(random));
    float d2 = std::numeric_limits<float>::max();
    for (const Eigen::Vector3f& m : model.points) d2 = std::min(d2, (m - p_object).squaredNorm());
    s.points_camera.push_back(in_camera(T_camera_object, p_object.x(), p_object.y(), p_object.z()));
    s.distance_m.push_back(std::sqrt(d2));
  }
  return s;
}

// What an exact search says of a point at distance d and depth z.
NearModel exactly(float d, float z, float reach_m, const VerifyOptions& verify) {
  const float tolerance = std::min(reach_m, depth_tolerance(z, verify));
  return d > reach_m ? NearModel::far : d > tolerance ? NearModel::near : NearModel::on;
}

// near_model against the exact answer for every sampled point, but those within 0.1 mm of the reach
// or the tolerance (too close for float rounding to say which side they lie on); the counts of each
// kind expected.
std::array<std::size_t, 3> expect_exact(const IcpTarget& model, const Transform& T_camera_object, const Sampled& s,
                                        float reach_m, const IcpOptions& icp) {
  const VerifyOptions verify;
  const std::vector<NearModel> got = near_model(s.points_camera, model, T_camera_object, reach_m, verify, icp);
  EXPECT_EQ(got.size(), s.points_camera.size());
  std::array<std::size_t, 3> counts{};
  for (std::size_t i = 0; i < got.size(); ++i) {
    const float d = s.distance_m[i], z = s.points_camera[i].z();
    const float tolerance = std::min(reach_m, depth_tolerance(z, verify));
    if (std::abs(d - reach_m) < 1e-4f || std::abs(d - tolerance) < 1e-4f) continue;
    const NearModel expected = exactly(d, z, reach_m, verify);
    EXPECT_EQ(got[i], expected) << "point " << i << " at " << d << " m";
    ++counts[static_cast<std::size_t>(expected)];
  }
  return counts;
}

TEST(PointsOnModel, EachPointIsFarNearOrOnAsTheExactNearestModelPointSays) {
  // Model points 1 cm apart: the grid's point (3 mm cells) is often not the nearest, by up to its
  // slack, so both the grid's answers and the tree's are tested.
  const IcpTarget model = plate(0.01f);
  const Transform T_camera_object = plate_pose();
  const Sampled s = sample_around(model, T_camera_object, 20000);
  const std::array<std::size_t, 3> counts = expect_exact(model, T_camera_object, s, 0.02f, IcpOptions{});
  for (const std::size_t n : counts) EXPECT_GT(n, 1000u);
  // A reach beyond the grid's 4 cm margin: the points outside the grid are looked up in the tree.
  const std::array<std::size_t, 3> wide = expect_exact(model, T_camera_object, s, 0.06f, IcpOptions{});
  std::size_t beyond_margin = 0;
  for (const float d : s.distance_m) beyond_margin += d > 0.045f && d < 0.06f;
  EXPECT_GT(beyond_margin, 1000u);
  EXPECT_GT(wide[static_cast<std::size_t>(NearModel::near)], counts[static_cast<std::size_t>(NearModel::near)] + beyond_margin / 2);
}

TEST(PointsOnModel, AGridMadeBeforeWithOtherSizesGivesTheSameAnswers) {
  // ICP made the model's grid first, with other sizes than the options say: its own slack and
  // margin decide what the grid may answer. Coarse cells over sparse points (3 cm apart), whose
  // cell points are often far from the nearest; and a margin narrower than the reach.
  const Transform T_camera_object = plate_pose();
  for (const auto& [cell_m, margin_m] : {std::pair{0.02f, 0.05f}, std::pair{0.01f, 0.01f}}) {
    const IcpTarget model = plate(0.03f);
    ASSERT_NE(model.grid(cell_m, margin_m), nullptr);
    const Sampled s = sample_around(model, T_camera_object, 20000);
    const std::array<std::size_t, 3> counts = expect_exact(model, T_camera_object, s, 0.02f, IcpOptions{});
    for (const std::size_t n : counts) EXPECT_GT(n, 200u) << cell_m << " m cells, " << margin_m << " m margin";
  }
}

// on_model against the exact answer (within the depth tolerance of the nearest model point) for
// every sampled point but those within 0.1 mm of the tolerance; how many are on it.
std::size_t expect_on_exactly(const IcpTarget& model, const Transform& T_camera_object, const Sampled& s) {
  const VerifyOptions verify;
  const std::vector<char> got = on_model(s.points_camera, model, T_camera_object, verify, IcpOptions{});
  EXPECT_EQ(got.size(), s.points_camera.size());
  std::size_t on = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const float tolerance = depth_tolerance(s.points_camera[i].z(), verify);
    if (std::abs(s.distance_m[i] - tolerance) < 1e-4f) continue;
    const bool expected = s.distance_m[i] <= tolerance;
    EXPECT_EQ(got[i] != 0, expected) << "point " << i << " at " << s.distance_m[i] << " m";
    on += expected;
  }
  return on;
}

TEST(PointsOnModel, OnTheModelIsWithinTheToleranceOfTheExactNearestModelPoint) {
  // The same plates and grids as above: the grid's slack, the tree's answers near the tolerance,
  // and a grid made first with a margin (1 cm) narrower than the largest tolerance (2 cm), outside
  // which a point may still be on the model. Points are sampled near the plate, where most of
  // them are within a tolerance (2-3 mm at 1 m) or a few cells of it.
  const Transform T_camera_object = plate_pose();
  const auto near_plate = [&](const IcpTarget& model) { return sample_around(model, T_camera_object, 20000, 0.06f, 0.012f, 11); };
  {
    const IcpTarget model = plate(0.01f);
    const Sampled s = near_plate(model);
    const std::size_t on = expect_on_exactly(model, T_camera_object, s);
    EXPECT_GT(on, 1000u);
    EXPECT_LT(on, s.points_camera.size() - 1000u);
  }
  // Cells wider than the plate's spacing: a cell's point is often not the nearest one.
  for (const auto& [cell_m, margin_m] : {std::pair{0.02f, 0.05f}, std::pair{0.01f, 0.01f}}) {
    const IcpTarget model = plate(0.005f);
    ASSERT_NE(model.grid(cell_m, margin_m), nullptr);
    const Sampled s = near_plate(model);
    EXPECT_GT(expect_on_exactly(model, T_camera_object, s), 1000u) << cell_m << " m cells, " << margin_m << " m margin";
  }
  // A far tolerance (2 cm, the cap) beyond a 1 cm margin: a point 1.5 cm off a plate 3 m away.
  const IcpTarget model = plate(0.002f);
  ASSERT_NE(model.grid(0.003f, 0.01f), nullptr);
  const Transform far = make_transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 3.0));
  const VerifyOptions verify;
  ASSERT_GT(depth_tolerance(3.0f, verify), 0.015f);
  const std::vector<Eigen::Vector3f> points = {in_camera(far, 0, 0, 0.015f), in_camera(far, 0, 0, 0.03f)};
  const std::vector<char> got = on_model(points, model, far, verify, {});
  EXPECT_EQ(got[0], 1);
  EXPECT_EQ(got[1], 0);
}

TEST(PointsOnModel, NoReachAndPointsWithoutDepthAreFar) {
  const IcpTarget model = plate(0.002f);
  const Transform T_camera_object = plate_pose();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> points = {in_camera(T_camera_object, 0, 0, 0), Eigen::Vector3f(nan, nan, nan)};
  const std::vector<NearModel> got = near_model(points, model, T_camera_object, 0.02f, {}, {});
  EXPECT_EQ(got[0], NearModel::on);
  EXPECT_EQ(got[1], NearModel::far);
  for (const float reach : {0.0f, -0.01f, nan}) {
    for (const NearModel n : near_model(points, model, T_camera_object, reach, {}, {})) EXPECT_EQ(n, NearModel::far);
  }
  const std::vector<char> on = on_model(points, model, T_camera_object, {}, {});
  EXPECT_EQ(on, (std::vector<char>{1, 0}));
}

TEST(PointsOnModel, ThePieceGrownIsTheOneTheModelLiesOnNotTheLargest) {
  // A part of the plate seen (its left end, on the model), and behind the plate's right half, 3 cm
  // to the side of the part, a neighbour's surface 1.5 cm behind the plate: within the reach,
  // beyond the tolerance, four times as many points, and a piece of its own. Farther behind, a
  // wall; it comes first in the region, so that the pieces' indices are not their positions.
  const IcpTarget model = plate(0.002f);
  const Transform T_camera_object = plate_pose();
  const VerifyOptions verify;
  ASSERT_LT(depth_tolerance(1.1f, verify), 0.015f);
  PointCloud region;
  const auto add = [&](float x, float y, float z) { region.points.push_back(in_camera(T_camera_object, x, y, z)); };
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) add(-0.05f + 0.0025f * static_cast<float>(i), -0.05f + 0.0025f * static_cast<float>(j), -0.06f);
  const std::size_t part_from = region.points.size();
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 10; ++j) add(-0.05f + 0.002f * static_cast<float>(i), 0.002f * static_cast<float>(j), 0);
  const std::size_t neighbour_from = region.points.size();
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 15; ++j) add(0.01f + 0.001f * static_cast<float>(i), 0.001f * static_cast<float>(j), -0.015f);
  region.width = static_cast<int>(region.points.size());
  const ClusterOptions clusters;
  const PointCloud piece = piece_on_model(region, model, T_camera_object, 0.02f, verify, {}, clusters);
  ASSERT_EQ(piece.size(), neighbour_from - part_from);
  for (std::size_t k = 0; k < piece.size(); ++k) EXPECT_EQ(piece.points[k], region.points[part_from + k]);
  // Without the part, the neighbour's surface is all there is within reach: that piece.
  PointCloud beside;
  beside.points.assign(region.points.begin() + static_cast<std::ptrdiff_t>(neighbour_from), region.points.end());
  beside.width = static_cast<int>(beside.points.size());
  EXPECT_EQ(piece_on_model(beside, model, T_camera_object, 0.02f, verify, {}, clusters).size(), 600u);
  // Pieces smaller than the clusters' least: none.
  ClusterOptions fewer = clusters;
  fewer.min_points = 1000;
  EXPECT_EQ(piece_on_model(region, model, T_camera_object, 0.02f, verify, {}, fewer).size(), 0u);
}

}  // namespace
}  // namespace viewpose
