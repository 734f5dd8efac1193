// The frame as a whole: each measured pixel is explained by at most one detection. Checked on plain
// pixel sets, where the answer is counted by hand, and on a drawn frame of two objects side by side
// with a second pose of one of them.
#include <numeric>
#include <vector>

#include "test_support.hpp"
#include "viewpose/pose/scene_claims.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {
namespace {

std::vector<std::uint32_t> range(std::uint32_t begin, std::uint32_t end) {
  std::vector<std::uint32_t> r(end - begin);
  std::iota(r.begin(), r.end(), begin);
  return r;
}

TEST(SceneClaims, APoseIsKeptOnlyWhereMostOfWhatItExplainsIsItsOwn) {
  const std::vector<std::vector<std::uint32_t>> claims = {
      range(0, 1000),      // kept first
      range(0, 1000),      // the same pixels again: a second pose of the same object
      range(600, 1600),    // 400 of its 1000 shared: touching the first, kept
      range(1200, 2000),   // 400 of 800 shared with the third: exactly half, kept
      range(1900, 2100),   // 200 claimed, 100 shared (half) but only 100 its own: too little evidence
      range(5000, 5150)};  // 150 its own: as much as verification asks, kept
  const std::vector<ClaimVerdict> v = resolve_claims(claims);
  ASSERT_EQ(v.size(), claims.size());
  const bool kept[] = {true, false, true, true, false, true};
  const std::size_t shared[] = {0, 1000, 400, 400, 100, 0};
  for (std::size_t k = 0; k < claims.size(); ++k) {
    EXPECT_EQ(v[k].kept, kept[k]) << "claim " << k;
    EXPECT_EQ(v[k].claimed, claims[k].size()) << "claim " << k;
    EXPECT_EQ(v[k].shared, shared[k]) << "claim " << k;
  }
  // A stricter share drops the touching one too; what a dropped pose claimed is not owned.
  SceneClaimOptions strict;
  strict.max_shared_fraction = 0.3;
  const std::vector<ClaimVerdict> s = resolve_claims(claims, strict);
  EXPECT_FALSE(s[2].kept);
  EXPECT_TRUE(s[3].kept);
  EXPECT_EQ(s[3].shared, 0u);
}

TEST(SceneClaims, TwoPosesOfOneObjectClaimTheSamePixelsAndTheSecondIsDropped) {
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const TriangleMesh jug = make_jug();
  const TriangleMesh can = make_can();
  const TriangleMesh table = test::square(3.0f);
  const Transform T_camera_jug =
      make_transform(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.1, 1, 0.2).normalized()).toRotationMatrix(), {-0.08, 0.0, 0.9});
  const Transform T_camera_can = make_transform(Eigen::Matrix3d::Identity(), {0.12, 0.0, 0.92});
  const MeshInstance all[] = {{&jug, T_camera_jug}, {&can, T_camera_can},
                              {&table, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1.5})}};
  const RenderedFrame f = render(all, K, {});
  std::size_t jug_pixels = 0, can_pixels = 0;
  for (const std::int32_t i : f.instance) jug_pixels += i == 0, can_pixels += i == 1;
  ASSERT_GT(jug_pixels, 5000u);
  ASSERT_GT(can_pixels, 1000u);

  const VerifyModel jug_model{&jug, {}, 0.003f, closed_mesh_winding(jug), {}};
  const VerifyModel can_model{&can, {}, 0.003f, closed_mesh_winding(can), {}};
  // The true poses claim what they show (and nothing of the other object or the wall).
  const std::vector<std::uint32_t> jug_claim = claimed_pixels(jug_model, T_camera_jug, f.depth, K);
  const std::vector<std::uint32_t> can_claim = claimed_pixels(can_model, T_camera_can, f.depth, K);
  EXPECT_EQ(jug_claim.size(), jug_pixels);
  EXPECT_EQ(can_claim.size(), can_pixels);
  for (const std::uint32_t p : jug_claim) ASSERT_EQ(f.instance[p], 0);
  // A second pose of the jug, 4 mm and a degree off, as found in another piece of its cluster:
  // within the tolerance of most of the same pixels.
  const Transform T_second = make_transform(Eigen::Matrix3d::Identity(), {0.004, 0, 0}) * T_camera_jug *
                             make_transform(Eigen::AngleAxisd(0.017, Eigen::Vector3d::UnitY()).toRotationMatrix(), {0, 0, 0});
  const std::vector<std::uint32_t> second = claimed_pixels(jug_model, T_second, f.depth, K);
  EXPECT_GT(second.size(), jug_pixels * 8 / 10);

  const std::vector<std::vector<std::uint32_t>> claims = {jug_claim, second, can_claim};
  const std::vector<ClaimVerdict> v = resolve_claims(claims);
  EXPECT_TRUE(v[0].kept);
  EXPECT_FALSE(v[1].kept);
  EXPECT_GT(v[1].shared, second.size() * 9 / 10);
  EXPECT_TRUE(v[2].kept) << "the can shares " << v[2].shared << " of " << v[2].claimed << " pixels";
  EXPECT_EQ(v[2].shared, 0u);
  // Ordered the other way, the second pose is kept and the true one dropped: the order is the trust.
  const std::vector<std::vector<std::uint32_t>> reversed = {second, jug_claim};
  const std::vector<ClaimVerdict> r = resolve_claims(reversed);
  EXPECT_TRUE(r[0].kept);
  EXPECT_FALSE(r[1].kept);
}

TEST(SceneClaims, AFrameOfAnotherSizeClaimsNothing) {
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const TriangleMesh jug = make_jug();
  const VerifyModel model{&jug, {}, 0.003f, closed_mesh_winding(jug), {}};
  const DepthImage small(320, 240);
  EXPECT_TRUE(claimed_pixels(model, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 1}), small, K).empty());
}

}  // namespace
}  // namespace viewpose
