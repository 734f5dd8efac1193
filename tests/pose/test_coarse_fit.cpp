// The coarse fit that orders a region's starting poses (pose/coarse_fit), on a box whose poses are
// known: the right pose fits almost fully, a few centimetres off or turned it does not, and each of
// the two overlaps catches what the other misses.
#include <cmath>
#include <numbers>
#include <random>

#include "test_support.hpp"
#include "viewpose/pose/coarse_fit.hpp"

namespace viewpose {
namespace {

// A 12 x 8 x 5 cm box's surface every 2.5 mm (object frame); with `visible_only`, the three faces
// whose outward normals point along +x, +y, +z (those a camera on that side sees).
std::vector<Eigen::Vector3f> box_surface(bool visible_only) {
  const Eigen::Vector3f half(0.06f, 0.04f, 0.025f);
  const float step = 0.0025f;
  std::vector<Eigen::Vector3f> points;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      if (visible_only && sign < 0) continue;
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      for (float s = -half[a]; s <= half[a]; s += step)
        for (float t = -half[b]; t <= half[b]; t += step) {
          Eigen::Vector3f p;
          p[axis] = sign * half[axis];
          p[a] = s;
          p[b] = t;
          points.push_back(p);
        }
    }
  return points;
}

std::vector<Eigen::Vector3f> moved(const std::vector<Eigen::Vector3f>& points, const Transform& T, float noise_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, noise_m);
  std::vector<Eigen::Vector3f> out;
  for (const Eigen::Vector3f& p : points) out.push_back((T * p.cast<double>()).cast<float>() + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  return out;
}

struct BoxScene {
  std::vector<Eigen::Vector3f> model = box_surface(false), visible = box_surface(true);
  // The database view: the box seen from its +x+y+z side, 60 cm from the view's camera.
  Transform T_view_object = make_transform(Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix(), {0.0, 0.0, 0.6});
  std::vector<Eigen::Vector3f> view = moved(visible, T_view_object, 0.0f, 1);
  OccupancyGrid model_grid{model, 0.01f};
};

TEST(CoarseFit, TheTruePoseFitsAndPosesOffByCentimetresOrTurnedDoNot) {
  const BoxScene s;
  const Transform T_camera_object = make_transform(Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {0.05, -0.03, 0.4}) * s.T_view_object;
  const std::vector<Eigen::Vector3f> region = moved(s.visible, T_camera_object, 0.002f, 2);
  const OccupancyGrid region_grid(region, 0.01f);
  const CoarseFitInputs in{region, &region_grid, s.view, &s.model_grid};
  const auto fit = [&](const Transform& T_camera_object_guess) {
    return coarse_fit(in, T_camera_object_guess * s.T_view_object.inverse(), T_camera_object_guess, 64);
  };
  const double truth = fit(T_camera_object);
  EXPECT_GT(truth, 0.9);
  // 3 cm along the camera's x, or 4 cm deeper: most points a cell or more away.
  EXPECT_LT(fit(make_transform(Eigen::Matrix3d::Identity(), {0.03, 0, 0}) * T_camera_object), 0.6 * truth);
  EXPECT_LT(fit(make_transform(Eigen::Matrix3d::Identity(), {0, 0, 0.04}) * T_camera_object), 0.6 * truth);
  // A quarter turn about the line of sight through the box's centre (a wrong CRH roll).
  const Eigen::Vector3d centre = T_camera_object.translation();
  const Transform turn = make_transform(Eigen::Matrix3d::Identity(), centre) *
                         make_transform(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {0, 0, 0}) *
                         make_transform(Eigen::Matrix3d::Identity(), -centre);
  EXPECT_LT(fit(turn * T_camera_object), 0.8 * truth);
  // Fewer points read: still near the truth's, from evenly spread points.
  EXPECT_NEAR(coarse_fit(in, T_camera_object * s.T_view_object.inverse(), T_camera_object, 16), truth, 0.15);
  // Without grids nothing fits.
  EXPECT_EQ(coarse_fit(CoarseFitInputs{region, nullptr, s.view, &s.model_grid}, T_camera_object * s.T_view_object.inverse(), T_camera_object), 0.0);
}

TEST(CoarseFit, EachOverlapCatchesWhatTheOtherMisses) {
  const BoxScene s;
  const Transform T_camera_object = make_transform(Eigen::Matrix3d::Identity(), {0, 0, 0.4}) * s.T_view_object;
  const Transform T_camera_view = T_camera_object * s.T_view_object.inverse();
  // A region that is a small patch of the box's +z face (a 3 cm square): all of it lies on the
  // model, but most of the view lies where the region has nothing.
  std::vector<Eigen::Vector3f> patch;
  for (const Eigen::Vector3f& p : s.visible)
    if (p.z() > 0.024f && std::abs(p.x()) < 0.015f && std::abs(p.y()) < 0.015f) patch.push_back(p);
  const std::vector<Eigen::Vector3f> small_region = moved(patch, T_camera_object, 0.0f, 3);
  const OccupancyGrid small_grid(small_region, 0.01f);
  EXPECT_GT(overlap(small_region, T_camera_object.inverse(), s.model_grid), 0.95) << "region on the model";
  EXPECT_LT(overlap(s.view, T_camera_view, small_grid), 0.4) << "view on the region";
  EXPECT_LT(coarse_fit({small_region, &small_grid, s.view, &s.model_grid}, T_camera_view, T_camera_object), 0.4);
  // A region twice the box's size each way (a larger box with the same visible corner): the view
  // lies on it, but much of the region lies off the model.
  std::vector<Eigen::Vector3f> large = s.visible;
  for (Eigen::Vector3f& p : large) p = 2.0f * p - Eigen::Vector3f(0.06f, 0.04f, 0.025f);  // the +x+y+z corner stays put
  const std::vector<Eigen::Vector3f> large_region = moved(large, T_camera_object, 0.0f, 5);
  const OccupancyGrid large_grid(large_region, 0.01f);
  EXPECT_LT(overlap(large_region, T_camera_object.inverse(), s.model_grid), 0.6) << "region on the model";
  EXPECT_LT(coarse_fit({large_region, &large_grid, s.view, &s.model_grid}, T_camera_view, T_camera_object), 0.6);
}

TEST(CoarseFit, OverlapCountsHalvesForNeighbouringCellsAndReadsEvenlySpreadPoints) {
  const std::vector<Eigen::Vector3f> one = {Eigen::Vector3f(0, 0, 0)};
  const OccupancyGrid grid(one, 0.01f);
  const std::vector<Eigen::Vector3f> probes = {{0, 0, 0}, {0.012f, 0, 0}, {0.5f, 0, 0}, {0, 0, 0}};
  EXPECT_DOUBLE_EQ(overlap(probes, Transform::Identity(), grid, 4), (1.0 + 0.5 + 0 + 1.0) / 4);
  // Two of four: the 0th and the 2nd.
  EXPECT_DOUBLE_EQ(overlap(probes, Transform::Identity(), grid, 2), 0.5);
  EXPECT_DOUBLE_EQ(overlap({}, Transform::Identity(), grid), 0.0);
  EXPECT_DOUBLE_EQ(overlap(probes, Transform::Identity(), OccupancyGrid{}), 0.0);
  EXPECT_DOUBLE_EQ(overlap(probes, Transform::Identity(), grid, 0), 0.0);
}

// A pose from point pair votes has no view: the model's points that face the camera stand in.
TEST(CoarseFit, WithoutAViewTheModelsFacingPointsStandInForIt) {
  const std::vector<Eigen::Vector3f> model = box_surface(false);
  // Each point's outward normal: along the axis of the face it lies on (the largest share of its
  // half size; points on edges take one of their faces).
  const Eigen::Vector3f half(0.06f, 0.04f, 0.025f);
  std::vector<Eigen::Vector3f> normals;
  for (const Eigen::Vector3f& p : model) {
    Eigen::Index axis = 0;
    p.cwiseAbs().cwiseQuotient(half).maxCoeff(&axis);
    Eigen::Vector3f n = Eigen::Vector3f::Zero();
    n[axis] = p[axis] > 0 ? 1.0f : -1.0f;
    normals.push_back(n);
  }
  const OccupancyGrid model_grid(model, 0.01f);
  const Transform T_camera_object = make_transform(
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, 1, 0).normalized())).toRotationMatrix(),
      {0.04, -0.02, 0.7});
  // The region: the points the camera sees (normal towards it), with 2 mm of noise.
  std::vector<Eigen::Vector3f> seen;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Eigen::Vector3d p = T_camera_object * model[i].cast<double>();
    if ((T_camera_object.linear() * normals[i].cast<double>()).dot(p) < 0) seen.push_back(model[i]);
  }
  ASSERT_GT(seen.size(), model.size() / 4);
  ASSERT_LT(seen.size(), model.size() * 3 / 4);
  const std::vector<Eigen::Vector3f> region = moved(seen, T_camera_object, 0.002f, 3);
  const OccupancyGrid region_grid(region, 0.01f);
  const auto fit = [&](const Transform& T) { return coarse_fit_facing(region, region_grid, model, normals, model_grid, T, 64); };
  EXPECT_GT(fit(T_camera_object), 0.9);
  // Five centimetres aside; turned a quarter turn about its long axis (the 5 and 8 cm sides swap).
  EXPECT_LT(fit(make_transform(Eigen::Matrix3d::Identity(), {0.05, 0.0, 0.0}) * T_camera_object), 0.5);
  const auto turned = [&](double angle, const Eigen::Vector3d& axis) {
    return fit(T_camera_object * make_transform(Eigen::AngleAxisd(angle, axis).toRotationMatrix(), {0, 0, 0}));
  };
  EXPECT_LT(turned(std::numbers::pi / 2, Eigen::Vector3d::UnitX()), 0.7);
  // Half a turn is the same box (a box's symmetry): it fits as well.
  EXPECT_GT(turned(std::numbers::pi, Eigen::Vector3d::UnitX()), 0.9);
  // No normals, no facing points: no fit.
  EXPECT_EQ(coarse_fit_facing(region, region_grid, model, {}, model_grid, T_camera_object, 64), 0.0);
}

}  // namespace
}  // namespace viewpose
