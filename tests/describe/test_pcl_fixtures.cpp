// Our VFH, CRH and roll alignment against PCL 1.13's own outputs on a real Kinect cluster
// (../shared/reference/pcl-fixtures, see its README.txt). Skipped when ../shared is absent.
#include <fstream>

#include "test_support.hpp"
#include "viewpose/describe/crh.hpp"
#include "viewpose/describe/normals.hpp"
#include "viewpose/describe/vfh.hpp"
#include "viewpose/io/pcd.hpp"

namespace viewpose {
namespace {

std::vector<float> fixture(const std::string& name) {
  std::ifstream in(test::shared_dir() / "reference/pcl-fixtures" / name);
  std::vector<float> v;
  float x;
  while (in >> x) v.push_back(x);
  return v;
}

#define REQUIRE_FIXTURES()                                                                         \
  if (!std::filesystem::exists(test::shared_dir() / "reference/pcl-fixtures/cloud_3mm_normals.pcd")) \
  GTEST_SKIP() << "skipped: " << test::shared_dir().string() << "/reference/pcl-fixtures is absent"

struct Cluster {
  PointCloud cloud;
  Eigen::Vector3f centroid;
};

Cluster milk_cluster() {
  Cluster c{read_pcd(test::shared_dir() / "reference/pcl-fixtures/cloud_3mm_normals.pcd").cloud, Eigen::Vector3f::Zero()};
  for (const auto& p : c.cloud.points) c.centroid += p;
  c.centroid /= static_cast<float>(c.cloud.size());
  return c;
}

TEST(PclFixtures, CentroidIsPclsCompute3DCentroid) {
  REQUIRE_FIXTURES();
  const Cluster c = milk_cluster();
  const auto ref = fixture("centroid.txt");
  ASSERT_EQ(ref.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.centroid[k], ref[static_cast<std::size_t>(k)], 1e-7);
}

TEST(PclFixtures, VfhEqualsPclInAllThreeConfigurations) {
  REQUIRE_FIXTURES();
  const Cluster c = milk_cluster();
  struct Case {
    const char* file;
    bool normalize_distances, size_component;
  };
  for (const Case& k : {Case{"vfh_defaults.txt", false, false}, Case{"vfh_framework.txt", true, false},
                        Case{"vfh_normdist_size.txt", true, true}}) {
    SCOPED_TRACE(k.file);
    VfhOptions o;
    o.normalize_distances = k.normalize_distances;
    o.size_component = k.size_component;
    const Vfh ours = compute_vfh(c.cloud.points, c.cloud.normals, o);
    const auto pcl = fixture(k.file);
    ASSERT_EQ(pcl.size(), 308u);
    // Same float arithmetic in the same order: equal to PCL's printed digits.
    for (std::size_t i = 0; i < 308; ++i) EXPECT_NEAR(ours[i], pcl[i], 1e-5f * std::max(1.0f, pcl[i])) << "bin " << i;
  }
}

TEST(PclFixtures, CorrectedVfhUsesTheFullCosineRange) {
  REQUIRE_FIXTURES();
  const Cluster c = milk_cluster();
  VfhOptions o;
  o.pcl_compatible = false;
  const Vfh h = compute_vfh(c.cloud.points, c.cloud.normals, o);
  const Vfh pcl = compute_vfh(c.cloud.points, c.cloud.normals);
  int used_pcl = 0, used_corrected = 0;
  for (std::size_t b = 45; b < 135; ++b) {
    used_pcl += pcl[b] > 0 ? 1 : 0;
    used_corrected += h[b] > 0 ? 1 : 0;
  }
  EXPECT_LE(used_pcl, 2 * 15 + 2);  // PCL's quirk: about 15 of 45 bins each for f2 and f3
  EXPECT_GT(used_corrected, used_pcl + 10);
}

TEST(PclFixtures, CrhEqualsPclAndSoDoesItsRolledCopy) {
  REQUIRE_FIXTURES();
  const Cluster c = milk_cluster();
  const Crh ours = compute_crh(c.cloud.normals, c.centroid);
  const auto pcl = fixture("crh.txt");
  ASSERT_EQ(pcl.size(), 90u);
  for (std::size_t i = 0; i < 90; ++i) EXPECT_NEAR(ours[i], pcl[i], 1e-5f) << "coefficient " << i;

  // The same cloud turned 40 degrees about the ray through its centroid.
  const Eigen::Matrix3f R = Eigen::AngleAxisf(40.0f * static_cast<float>(M_PI) / 180.0f, c.centroid.normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3f> rolled;
  for (const auto& n : c.cloud.normals) rolled.push_back(R * n);
  const Crh ours_rolled = compute_crh(rolled, c.centroid);
  const auto pcl_rolled = fixture("crh_rolled40.txt");
  ASSERT_EQ(pcl_rolled.size(), 90u);
  for (std::size_t i = 0; i < 90; ++i) EXPECT_NEAR(ours_rolled[i], pcl_rolled[i], 2e-4f) << "coefficient " << i;

  // Roll angles as PCL's CRHAlignment reports them.
  EXPECT_EQ(crh_roll_angles(ours, ours_rolled), std::vector<float>{40.0f});
  EXPECT_EQ(crh_roll_angles(ours, ours), std::vector<float>{0.0f});
  Crh a, b;
  std::copy(pcl.begin(), pcl.end(), a.begin());
  std::copy(pcl_rolled.begin(), pcl_rolled.end(), b.begin());
  const auto pcl_angles = fixture("crh_roll_angles_deg.txt");
  EXPECT_EQ(crh_roll_angles(a, b), pcl_angles);
  EXPECT_EQ(crh_roll_angles(a, a), fixture("crh_roll_angles_self_deg.txt"));
}

TEST(CrhAlignment, FoundRollCarriesTheViewOntoARolledScene) {
  // The scene is the view turned 40 degrees about the ray through its centroid and moved 30 % farther
  // along that ray. CRH -> roll angle -> alignment must map every view point onto its scene point.
  REQUIRE_FIXTURES();
  const Cluster view = milk_cluster();
  const Eigen::Vector3d c = view.centroid.cast<double>();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(40 * M_PI / 180, c.normalized()).toRotationMatrix();
  const Transform T_scene_view = make_transform(R, 1.3 * c - R * c);
  std::vector<Eigen::Vector3f> scene_normals;
  for (const auto& n : view.cloud.normals) scene_normals.push_back((R * n.cast<double>()).cast<float>());
  const Crh view_crh = compute_crh(view.cloud.normals, view.centroid);
  const Crh scene_crh = compute_crh(scene_normals, (T_scene_view * c).cast<float>());
  const auto rolls = crh_roll_angles(view_crh, scene_crh);
  ASSERT_FALSE(rolls.empty());
  const Transform T = crh_alignment(c, T_scene_view * c, rolls[0]);
  double worst = 0;
  for (const auto& p : view.cloud.points) {
    worst = std::max(worst, (T * p.cast<double>() - T_scene_view * p.cast<double>()).norm());
  }
  EXPECT_LT(worst, 0.01) << "roll " << rolls[0];  // 2-degree steps over a 15 cm carton: a few mm
}

// A rendered view of the built-in jug (tests/fixtures/jug_view.pcd, made by viewpose) and PCL
// 1.13's VFH, CRH and normals on it (tests/fixtures/pcl, made by `make pcl-fixtures`, which builds
// tools/pcl_reference against Debian's libpcl-dev). Committed, so this runs without PCL.
std::vector<float> repo_fixture(const std::string& name) {
  std::ifstream in(std::filesystem::path(VIEWPOSE_SOURCE_DIR) / "tests/fixtures" / name);
  std::vector<float> v;
  float x;
  while (in >> x) v.push_back(x);
  return v;
}

TEST(PclRenderedView, VfhCrhAndNormalsEqualPcls) {
  const PointCloud view = read_pcd(std::filesystem::path(VIEWPOSE_SOURCE_DIR) / "tests/fixtures/jug_view.pcd").cloud;
  ASSERT_GT(view.size(), 5000u);
  ASSERT_TRUE(view.has_normals());
  const Vfh vfh = compute_vfh(view.points, view.normals);
  const auto pcl_vfh = repo_fixture("pcl/vfh_framework.txt");
  ASSERT_EQ(pcl_vfh.size(), 308u);
  for (std::size_t i = 0; i < 308; ++i) EXPECT_NEAR(vfh[i], pcl_vfh[i], 1e-5f * std::max(1.0f, pcl_vfh[i])) << "bin " << i;

  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& p : view.points) centroid += p;
  centroid /= static_cast<float>(view.size());
  const Crh crh = compute_crh(view.normals, centroid);
  const auto pcl_crh = repo_fixture("pcl/crh.txt");
  ASSERT_EQ(pcl_crh.size(), 90u);
  for (std::size_t i = 0; i < 90; ++i) EXPECT_NEAR(crh[i], pcl_crh[i], 1e-5f) << "coefficient " << i;

  // Normals from the points alone (radius 1.5 cm), ours and PCL's NormalEstimation.
  PointCloud points = PointCloud::from_points(view.points);
  estimate_normals(points);
  const auto pcl_n = repo_fixture("pcl/normals_pcl.txt");
  ASSERT_EQ(pcl_n.size(), 3 * view.size());
  double worst = 0;
  for (std::size_t i = 0; i < view.size(); ++i) {
    const Eigen::Vector3f theirs(pcl_n[3 * i], pcl_n[3 * i + 1], pcl_n[3 * i + 2]);
    ASSERT_EQ(theirs.allFinite(), points.normals[i].allFinite()) << i;
    if (!theirs.allFinite()) continue;
    worst = std::max(worst, std::acos(std::clamp(static_cast<double>(theirs.dot(points.normals[i])), -1.0, 1.0)));
  }
  EXPECT_LT(worst * 180 / M_PI, 0.05);
}

}  // namespace
}  // namespace viewpose
