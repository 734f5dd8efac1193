// Point pair features against known answers: a model's own points moved by a known pose give that
// pose back; a rendered frame of the jug beside a can, on a table and half hidden, gives the jug's
// pose among its first hypotheses, before any refinement.
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/describe/normals.hpp"
#include "viewpose/pose/ppf.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {
namespace {

const DatabaseObject& jug() {
  static const ViewDatabase db = [] {
    const ObjectModel jug{1, "jug", make_jug()};
    return build_view_database(std::span(&jug, 1), DatabaseParams{});
  }();
  return db.objects[0];
}

constexpr double kHalfPi = 1.57079632679489662;

double rotation_deg(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / 3.14159265358979;
}

// The best of the first `n` hypotheses: the smallest translation error among those within `max_deg`.
double best_translation(const std::vector<PpfHypothesis>& h, const Transform& truth, std::size_t n, double max_deg) {
  double best = 1e9;
  for (std::size_t i = 0; i < std::min(n, h.size()); ++i) {
    if (rotation_deg(h[i].T_camera_object, truth) <= max_deg)
      best = std::min(best, (h[i].T_camera_object.translation() - truth.translation()).norm());
  }
  return best;
}

TEST(Ppf, SamplingKeepsBothFacesOfAnEdgeAndOneNormalOfAFlatPatch) {
  // A cell holding points of two faces at right angles, and a flat cell: three sampled points.
  std::vector<Eigen::Vector3f> p, n;
  for (int i = 0; i < 10; ++i) {
    p.emplace_back(0.001f * i, 0.002f, 0.001f), n.emplace_back(0, 0, 1);
    p.emplace_back(0.002f, 0.001f * i, 0.0005f), n.emplace_back(1, 0, 0);
    p.emplace_back(0.05f + 0.001f * i, 0.002f, 0.001f), n.emplace_back(0, 0.1f, 1);
  }
  p.emplace_back(0.5f, 0.5f, 0.5f), n.emplace_back(NAN, NAN, NAN);  // no normal: left out
  const OrientedPoints s = ppf_sample(p, n, 0.012f, 30);
  ASSERT_EQ(s.size(), 3u);
  for (const auto& normal : s.normals) EXPECT_NEAR(normal.norm(), 1.0f, 1e-5f);
  EXPECT_THROW(ppf_sample(p, std::span(n).first(3), 0.01f, 30), Error);
}

TEST(Ppf, TheModelsOwnPointsMovedByAKnownPoseGiveThatPose) {
  const DatabaseObject& o = jug();
  const PpfModel model(o.model_points, o.model_normals, o.diameter_m);
  EXPECT_GT(model.sampled().size(), 100u);
  EXPECT_GT(model.pairs(), model.sampled().size() * 50);
  const Transform T_camera_object =
      make_transform(Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix(), {0.1, -0.05, 0.9});
  // Only the half the camera would see: the points whose normals face it.
  std::vector<Eigen::Vector3f> p, n;
  for (std::size_t i = 0; i < o.model_points.size(); ++i) {
    const Eigen::Vector3f q = (T_camera_object * o.model_points[i].cast<double>()).cast<float>();
    const Eigen::Vector3f m = (T_camera_object.linear() * o.model_normals[i].cast<double>()).cast<float>();
    if (m.dot(-q) > 0) p.push_back(q), n.push_back(m);
  }
  const OrientedPoints scene = ppf_sample(p, n, model.sample_step_m(), model.options().normal_split_deg);
  const std::vector<PpfHypothesis> h = model.hypotheses(scene);
  ASSERT_FALSE(h.empty());
  EXPECT_LT(rotation_deg(h[0].T_camera_object, T_camera_object), 8.0);
  EXPECT_LT((h[0].T_camera_object.translation() - T_camera_object.translation()).norm(), 0.05 * o.diameter_m);
  EXPECT_GT(h[0].poses, 3u);
  for (std::size_t i = 1; i < h.size(); ++i) EXPECT_GE(h[i - 1].votes, h[i].votes);
  // The same inputs, the same hypotheses.
  const std::vector<PpfHypothesis> again = model.hypotheses(scene);
  ASSERT_EQ(again.size(), h.size());
  EXPECT_TRUE(again[0].T_camera_object.isApprox(h[0].T_camera_object, 0));
}

TEST(Ppf, TheJugHalfHiddenBesideACanIsAmongTheFirstHypotheses) {
  const DatabaseObject& o = jug();
  const PpfModel model(o.model_points, o.model_normals, o.diameter_m);
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const TriangleMesh can = make_can();
  const TriangleMesh box = make_box_mesh({0.3f, 0.12f, 0.08f});
  const TriangleMesh table = test::square(2.0f);
  // Standing (its z up, the camera's -y), turned 35 degrees about the vertical.
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-kHalfPi, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Transform T_camera_jug = make_transform(R, {-0.05, 0.0, 0.95});
  // The can touches the jug's side; a long box in front hides the jug's lower part.
  const MeshInstance all[] = {{&o.mesh, T_camera_jug},
                              {&can, make_transform(Eigen::Matrix3d::Identity(), {0.09, 0.02, 0.93})},
                              {&box, make_transform(Eigen::Matrix3d::Identity(), {-0.05, 0.1, 0.75})},
                              {&table, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.4})}};
  const RenderedFrame f = render(all, K, {});
  std::size_t jug_pixels = 0, unhidden = 0;
  for (const std::int32_t i : f.instance) jug_pixels += i == 0;
  {
    const MeshInstance alone[] = {{&o.mesh, T_camera_jug}};
    for (const std::int32_t i : render(alone, K, {}).instance) unhidden += i == 0;
  }
  ASSERT_LT(jug_pixels, unhidden * 8 / 10) << "the box hides part of the jug: " << jug_pixels << " of " << unhidden;
  ASSERT_GT(jug_pixels, unhidden * 4 / 10);

  PointCloud cloud = depth_to_cloud(f.depth, K);
  estimate_normals_organized(cloud);
  // Everything in front of the table: the jug, the can and the box, as one region.
  std::vector<Eigen::Vector3f> p, n;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.points[i].allFinite() && cloud.points[i].z() < 1.3f) p.push_back(cloud.points[i]), n.push_back(cloud.normals[i]);
  }
  const OrientedPoints scene = ppf_sample(p, n, model.sample_step_m(), model.options().normal_split_deg);
  const std::vector<PpfHypothesis> h = model.hypotheses(scene);
  ASSERT_FALSE(h.empty());
  // Within ICP's reach (a tenth of the diameter, 15 degrees) among the first three hypotheses.
  EXPECT_LT(best_translation(h, T_camera_jug, 3, 15.0), 0.1 * o.diameter_m)
      << "first: " << h[0].T_camera_object.translation().transpose() << ", "
      << rotation_deg(h[0].T_camera_object, T_camera_jug) << " deg, " << h[0].votes << " votes";
}

TEST(Ppf, AStoredTableVotesAsTheTableMadeAgainAndADamagedOneIsRefused) {
  // The database's table (made with it) is the table the model's points make now, and votes the
  // same: a scene of the model's own points gives the same hypotheses from either.
  const DatabaseObject& o = jug();
  ASSERT_TRUE(o.pair_table) << "DatabaseParams::max_pair_table_bytes lets the jug's table be stored";
  const PpfModel made(o.model_points, o.model_normals, o.diameter_m);
  EXPECT_EQ(o.pair_table->entries, made.table().entries);
  EXPECT_EQ(o.pair_table->key_start, made.table().key_start);
  EXPECT_TRUE(o.pair_table->made_with(PpfOptions{}));
  PpfOptions coarser;
  coarser.sample_fraction = 0.06;
  EXPECT_FALSE(o.pair_table->made_with(coarser));
  const PpfModel stored(o.pair_table);
  EXPECT_EQ(stored.sample_step_m(), made.sample_step_m());
  const Transform T = make_transform(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(), {0, 0.1, 1.0});
  std::vector<Eigen::Vector3f> p, n;
  for (std::size_t i = 0; i < o.model_points.size(); ++i) {
    p.push_back((T * o.model_points[i].cast<double>()).cast<float>());
    n.push_back((T.linear() * o.model_normals[i].cast<double>()).cast<float>());
  }
  const OrientedPoints scene = ppf_sample(p, n, made.sample_step_m(), made.normal_split_deg());
  const std::vector<PpfHypothesis> a = made.hypotheses(scene), b = stored.hypotheses(scene);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].T_camera_object.isApprox(b[i].T_camera_object, 0));
    EXPECT_EQ(a[i].votes, b[i].votes);
  }
  // The options that act when votes are cast are the caller's; the table's shape is its own.
  PpfOptions fewer;
  fewer.max_hypotheses = 2;
  fewer.sample_fraction = 0.06;
  const PpfModel few(o.pair_table, fewer);
  EXPECT_EQ(few.hypotheses(scene).size(), 2u);
  EXPECT_EQ(few.sample_step_m(), made.sample_step_m());
  // Damage that would make votes read out of bounds is refused, by name.
  const auto damaged = [&](auto&& edit) {
    auto t = std::make_shared<PpfTable>(*o.pair_table);
    edit(*t);
    return [t] { check_ppf_table(*t); };
  };
  test::expect_error(damaged([](PpfTable& t) { t.entries[7] = PpfTable::entry(static_cast<std::uint32_t>(t.sampled.size()), 0); }),
                     "a pair naming a point that does not exist");
  test::expect_error(damaged([](PpfTable& t) { t.entries[9] = PpfTable::entry(0, PpfTable::kAlphaUnits); }), "angle is out of range");
  test::expect_error(damaged([](PpfTable& t) { std::swap(t.key_start[1000], t.key_start[60000]); }), "keys out of order");
  test::expect_error(damaged([](PpfTable& t) { t.key_start.pop_back(); }), "keys that do not match");
  test::expect_error(damaged([](PpfTable& t) { t.angle_bins = 11; }), "bad options");
  test::expect_error(damaged([](PpfTable& t) { t.sampled.normals.pop_back(); }), "number of points or normals");
  test::expect_error(damaged([](PpfTable& t) { t.sampled.normals[3] *= 2.0f; }), "not finite or not unit");
  EXPECT_THROW(PpfModel(std::shared_ptr<const PpfTable>()), Error);
}

TEST(Ppf, BadModelsAndOptionsAreRefusedInOneLine) {
  const std::vector<Eigen::Vector3f> one = {{0, 0, 0}}, up = {{0, 0, 1}};
  EXPECT_THROW(PpfModel(one, up, 0.1), Error);
  EXPECT_THROW(PpfModel(one, up, 0.0), Error);
  PpfOptions bad;
  bad.sample_fraction = 0;
  EXPECT_THROW(PpfModel(one, up, 0.1, bad), Error);
  // Options whose table could not be made (a trillion distance bins; 6720^3 angle bins) are refused
  // before anything is allocated.
  bad.sample_fraction = 1e-12;
  test::expect_error([&] { check_ppf_options(bad); }, "ppf: bad options");
  bad = PpfOptions{};
  bad.angle_bins = 13440;
  test::expect_error([&] { check_ppf_options(bad); }, "at most 2^24 feature bins");
  EXPECT_NO_THROW(check_ppf_options(PpfOptions{}));
}

}  // namespace
}  // namespace viewpose
