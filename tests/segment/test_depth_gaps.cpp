#include <algorithm>
#include <cmath>
#include <vector>

#include "test_support.hpp"
#include "viewpose/segment/depth_gaps.hpp"

namespace viewpose {
namespace {

// A 100 x 60 image at 100 px focal length of a wall 3 m away; each case puts pieces in front of it
// (in rows 20 to 39) and unmeasured bands between them.
struct Scene {
  CameraIntrinsics K{100, 100, 49.5, 29.5, 100, 60};
  DepthImage depth = wall();
  static DepthImage wall() {
    DepthImage d(100, 60);
    std::fill(d.depth_m.begin(), d.depth_m.end(), 3.0f);
    return d;
  }
  void blank(int u0, int u1) {
    for (int v = 20; v < 40; ++v)
      for (int u = u0; u < u1; ++u) depth.at(u, v) = NAN;
  }
  // Columns [u0, u1) of rows 20 to 39 measured at z; their points, as a piece.
  std::vector<Eigen::Vector3f> measure(int u0, int u1, float z) {
    std::vector<Eigen::Vector3f> points;
    for (int v = 20; v < 40; ++v)
      for (int u = u0; u < u1; ++u) {
        depth.at(u, v) = z;
        points.push_back(K.unproject(u, v, z).cast<float>());
      }
    return points;
  }
  std::vector<DepthGap> gaps(const std::vector<std::vector<Eigen::Vector3f>>& pieces, int max_px, float spacing_m = 0.0f) const {
    std::vector<std::span<const Eigen::Vector3f>> spans(pieces.begin(), pieces.end());
    return missing_depth_gaps(depth, K, spans, spacing_m, 0.02f, max_px);
  }
};

TEST(DepthGaps, TwoPiecesAcrossABandOfMissingDepthAreJoinedByItsWidth) {
  // A mug's inside and outside with the rim between them unmeasured: ten columns of nothing.
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  s.blank(30, 40);
  const std::vector<DepthGap> gaps = s.gaps({a, b}, 10);
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0].a, 0u);
  EXPECT_EQ(gaps[0].b, 1u);
  EXPECT_EQ(gaps[0].unmeasured_px, 10);
  EXPECT_EQ(s.gaps({a, b}, 11).at(0).unmeasured_px, 10) << "an odd bound and an even one see the same path";
  EXPECT_TRUE(s.gaps({a, b}, 9).empty()) << "a band wider than the bound joins nothing";
}

TEST(DepthGaps, PiecesMeetingAtMeasuredPixelsAreNotJoined) {
  // The wall seen between them: the sensor saw what lies there.
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  EXPECT_TRUE(s.gaps({a, b}, 20).empty());
  // Unmeasured around them, the band measured: a path around it, through the missing depth.
  s.depth.depth_m.assign(s.depth.depth_m.size(), NAN);
  const auto a2 = s.measure(10, 30, 1.0f), b2 = s.measure(40, 60, 1.1f);
  s.measure(30, 40, 2.0f);
  const std::vector<DepthGap> around = s.gaps({a2, b2}, 20);
  ASSERT_EQ(around.size(), 1u);
  EXPECT_EQ(around[0].unmeasured_px, 12) << "up a row, along it over the band, and down";
  // Touching each other directly (a depth step and no missing pixel between): not a gap either.
  Scene t;
  const auto c = t.measure(10, 30, 1.0f), d = t.measure(30, 50, 1.2f);
  EXPECT_TRUE(t.gaps({c, d}, 20).empty());
}

TEST(DepthGaps, APieceBetweenTwoHidesThePairBehindIt) {
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), c = s.measure(35, 45, 1.0f), b = s.measure(50, 70, 1.0f);
  s.blank(30, 35);
  s.blank(45, 50);
  const std::vector<DepthGap> gaps = s.gaps({a, b, c}, 40);
  ASSERT_EQ(gaps.size(), 2u);
  EXPECT_EQ(gaps[0].a, 0u);  // a-c
  EXPECT_EQ(gaps[0].b, 2u);
  EXPECT_EQ(gaps[0].unmeasured_px, 5);
  EXPECT_EQ(gaps[1].a, 1u);  // b-c
  EXPECT_EQ(gaps[1].b, 2u);
  EXPECT_EQ(gaps[1].unmeasured_px, 5);
}

TEST(DepthGaps, APieceBesideTheBandCanTakeItsPixels) {
  // Each unmeasured pixel goes to the piece that reaches it first: a small piece just beside the
  // band (on no path between the two) takes the pixels next to it, and the two are no longer seen
  // joined within the bound. Asked one pair at a time, as the recognizer asks, they are.
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  // The band is 3 rows high (28-30), the wall elsewhere; a piece of 3 x 3 pixels just below it.
  for (int v = 20; v < 40; ++v)
    for (int u = 30; u < 40; ++u) s.depth.at(u, v) = (v >= 28 && v <= 30) ? NAN : 3.0f;
  std::vector<Eigen::Vector3f> c;
  for (int v = 31; v < 34; ++v)
    for (int u = 33; u < 36; ++u) s.depth.at(u, v) = 1.05f, c.push_back(s.K.unproject(u, v, 1.05f).cast<float>());
  const std::vector<DepthGap> alone = s.gaps({a, b}, 10);
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone[0].unmeasured_px, 10);
  for (const DepthGap& g : s.gaps({a, b, c}, 10)) EXPECT_FALSE(g.a == 0 && g.b == 1) << "the third piece took the band's middle";
}

TEST(DepthGaps, ZeroDepthIsMissingDepth) {
  // A driver's buffer marks missing pixels with 0, as depth_from_units keeps them if not converted.
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  for (int v = 20; v < 40; ++v)
    for (int u = 30; u < 40; ++u) s.depth.at(u, v) = 0.0f;
  ASSERT_EQ(s.gaps({a, b}, 10).size(), 1u);
  EXPECT_EQ(s.gaps({a, b}, 10)[0].unmeasured_px, 10);
}

TEST(DepthGaps, APointClaimsOnlyPixelsAtItsOwnDepth) {
  // Points 5 cm off the image's depth (another surface, or a piece from another frame) stand for
  // no pixel: nothing to grow from.
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  s.blank(30, 40);
  std::vector<Eigen::Vector3f> b_off;
  for (const Eigen::Vector3f& p : b) b_off.push_back(p * (1.15f / 1.1f));
  EXPECT_TRUE(s.gaps({a, b_off}, 20).empty());
  // Sparse points (every third column, as a voxelized cloud's) stand for the pixels around them
  // within half their spacing: the same gap as the dense piece's.
  std::vector<Eigen::Vector3f> a_sparse;
  for (std::size_t i = 0; i < a.size(); i += 3) a_sparse.push_back(a[i]);
  const std::vector<DepthGap> gaps = s.gaps({a_sparse, b}, 20, 0.03f);
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0].unmeasured_px, 10);
}

TEST(DepthGaps, DegenerateInputsGiveNoGaps) {
  Scene s;
  const auto a = s.measure(10, 30, 1.0f), b = s.measure(40, 60, 1.1f);
  s.blank(30, 40);
  ASSERT_EQ(s.gaps({a, b}, 20).size(), 1u);
  EXPECT_TRUE(s.gaps({a}, 20).empty());
  EXPECT_TRUE(s.gaps({a, b}, 0).empty());
  EXPECT_TRUE(s.gaps({a, {}}, 20).empty());
  std::vector<Eigen::Vector3f> broken = {{NAN, 0, 1}, {0, 0, -1}, {1e6f, 0, 1}};
  EXPECT_TRUE(s.gaps({a, broken}, 20).empty());
  DepthImage wrong(10, 10);
  wrong.depth_m.resize(5);
  const std::vector<std::span<const Eigen::Vector3f>> spans = {a, b};
  EXPECT_TRUE(missing_depth_gaps(wrong, s.K, spans, 0.0f, 0.02f, 20).empty());
  EXPECT_TRUE(missing_depth_gaps(DepthImage(50, 60), s.K, spans, 0.0f, 0.02f, 20).empty()) << "an image of another size than K's";
  CameraIntrinsics no_focal = s.K;
  no_focal.fx = 0;
  EXPECT_TRUE(missing_depth_gaps(s.depth, no_focal, spans, 0.0f, 0.02f, 20).empty());
}

}  // namespace
}  // namespace viewpose
