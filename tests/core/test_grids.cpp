#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "test_support.hpp"
#include "viewpose/core/cell_grid.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/nearest_grid.hpp"
#include "viewpose/core/occupancy_grid.hpp"
#include "viewpose/core/radix_sort.hpp"
#include "viewpose/core/threads.hpp"

namespace viewpose {
namespace {

// Points on a sphere of 10 cm radius with NaNs among them.
std::vector<Eigen::Vector3f> sphere_points(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> pts;
  for (std::size_t i = 0; i < n; ++i) pts.push_back(0.1f * Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized());
  pts[7] = Eigen::Vector3f::Constant(NAN);
  return pts;
}

TEST(NearestGrid, FindsAPointAtMostACellDiagonalFartherThanTheNearest) {
  const std::vector<Eigen::Vector3f> pts = sphere_points(5000, 1);
  const float cell = 0.004f, margin = 0.03f;
  const KdTree tree(pts);
  const NearestGrid grid(tree, pts, cell, margin);
  EXPECT_EQ(grid.filled(), 0u) << "cells fill on first use";
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<float> u(-0.13f, 0.13f);
  double worst = 0, mean = 0;
  int compared = 0;
  for (int q = 0; q < 20000; ++q) {
    const Eigen::Vector3f p(u(rng), u(rng), u(rng));
    std::uint32_t exact = 0, found = 0;
    float d_exact = 0, d_found = 0;
    ASSERT_TRUE(tree.nearest(p, exact, d_exact));
    if (!grid.nearest(p, found, d_found)) {
      // Outside the grid: farther than the margin from the points' bounding box, so from every point.
      EXPECT_GT(std::sqrt(d_exact), margin - 1e-6f);
      continue;
    }
    ASSERT_NE(found, 7u) << "the NaN point is never returned";
    EXPECT_FLOAT_EQ(d_found, (pts[found] - p).squaredNorm());
    const double extra = std::sqrt(d_found) - std::sqrt(d_exact);
    worst = std::max(worst, extra);
    mean += extra;
    ++compared;
  }
  ASSERT_GT(compared, 10000);
  EXPECT_LE(worst, std::sqrt(3.0) * cell + 1e-6);
  EXPECT_GT(grid.filled(), 1000u);
  EXPECT_LT(mean / compared, 0.1 * cell);
}

TEST(NearestGrid, FillingEveryCellAtOnceGivesEachItsExactNearestPoint) {
  // However fill_all fills the cells (a faster way by blocks was tried), each must hold a point
  // exactly as near the cell's centre as the tree's nearest to it (what the cell's own search would
  // store). A sparse sphere and a dense patch beside it, as a scanned view has.
  std::vector<Eigen::Vector3f> pts = sphere_points(3000, 3);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  for (int i = 0; i < 4000; ++i) pts.emplace_back(0.1f + u(rng), u(rng), 0.5f * u(rng));
  const float cell = 0.003f, margin = 0.02f;
  const KdTree tree(pts);
  const NearestGrid grid(tree, pts, cell, margin);
  grid.fill_all();
  const std::size_t all = grid.filled();
  // The grid's origin, as the class documents it: the finite points' lower corner less the margin.
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f);
  for (const auto& p : pts)
    if (p.allFinite()) lo = lo.cwiseMin(p);
  const Eigen::Vector3f origin = lo - Eigen::Vector3f::Constant(margin);
  std::mt19937_64 qrng(5);
  std::uniform_real_distribution<float> q(-0.13f, 0.14f);
  int checked = 0;
  for (int i = 0; i < 30000; ++i) {
    const Eigen::Vector3f p(q(qrng), q(qrng), q(qrng));
    std::uint32_t held = 0, exact = 0;
    float unused = 0, d_exact = 0;
    if (!grid.nearest(p, held, unused)) continue;
    const Eigen::Vector3f centre = origin + (((p - origin) / cell).array().floor() + 0.5f).matrix() * cell;
    ASSERT_TRUE(tree.nearest(centre, exact, d_exact));
    ASSERT_NEAR((pts[held] - centre).squaredNorm(), d_exact, 1e-9f) << "cell at " << centre.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 5000);
  EXPECT_EQ(grid.filled(), all) << "queries after fill_all fill nothing new";
}

TEST(NearestGrid, AGridMadeFromAnothersCellsAnswersAsItDoesAndRefusesCellsThatDoNotFit) {
  // What a view database stores (a filled grid's cells) and the recognizer makes its grid from.
  const std::vector<Eigen::Vector3f> pts = sphere_points(2000, 9);
  const float cell = 0.004f, margin = 0.02f;
  const KdTree tree(pts);
  const NearestGrid filled(tree, pts, cell, margin);
  filled.fill_all();
  const std::vector<std::uint32_t> cells = filled.cells();
  ASSERT_EQ(cells.size(), NearestGrid::cell_count(pts, cell, margin));
  ASSERT_EQ(filled.filled(), cells.size());
  const NearestGrid given(tree, pts, cell, margin, cells);
  EXPECT_EQ(given.filled(), cells.size()) << "nothing left to search for";
  EXPECT_EQ(given.cells(), cells);
  const NearestGrid lazy(tree, pts, cell, margin);
  std::mt19937_64 rng(10);
  std::uniform_real_distribution<float> u(-0.13f, 0.13f);
  for (int q = 0; q < 5000; ++q) {
    const Eigen::Vector3f p(u(rng), u(rng), u(rng));
    std::uint32_t a = 0, b = 0;
    float da = 0, db = 0;
    const bool inside = lazy.nearest(p, a, da);
    ASSERT_EQ(given.nearest(p, b, db), inside);
    if (inside) {
      ASSERT_EQ(a, b) << "query " << p.transpose();
    }
  }
  // Unfilled cells (0) are allowed and fill as queries ask; a wrong count or a point past the end is not.
  std::vector<std::uint32_t> partly = cells;
  std::fill(partly.begin(), partly.begin() + static_cast<std::ptrdiff_t>(partly.size() / 2), 0u);
  EXPECT_EQ(NearestGrid(tree, pts, cell, margin, partly).filled(), cells.size() - cells.size() / 2);
  test::expect_error([&] { NearestGrid(tree, pts, cell, margin, std::span(cells).subspan(1)); }, "cells given for a grid of");
  std::vector<std::uint32_t> past = cells;
  past[past.size() / 3] = static_cast<std::uint32_t>(pts.size() + 1);
  test::expect_error([&] { NearestGrid(tree, pts, cell, margin, past); }, "a cell holds a point past");
  EXPECT_TRUE(NearestGrid::fits(pts, cell, margin, cells));
  EXPECT_FALSE(NearestGrid::fits(pts, cell, margin, past));
  EXPECT_EQ(filled_nearest_cells(pts, cell, margin), cells);
  test::expect_error([&] { NearestGrid(tree, pts, cell * 2, margin, cells); }, "cells given for a grid of");
}

TEST(KdTree, NearestWithinABoundFindsTheNearestOrNothing) {
  // The same point as the unbounded search wherever the nearest lies within the bound, including
  // on a lattice, whose queries at cell centres have several points equally near; nothing beyond.
  std::vector<Eigen::Vector3f> pts = sphere_points(2000, 7);
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y) pts.emplace_back(0.2f + 0.01f * static_cast<float>(x), 0.01f * static_cast<float>(y), 0.0f);
  const KdTree tree(pts);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<float> q(-0.15f, 0.35f), scale(0.5f, 3.0f);
  int within = 0, beyond = 0;
  for (int i = 0; i < 20000; ++i) {
    Eigen::Vector3f p(q(rng), q(rng), q(rng));
    if (i % 4 == 0) p = Eigen::Vector3f(0.205f + 0.01f * static_cast<float>(i % 11), 0.005f + 0.01f * static_cast<float>(i % 7), 0.004f);
    std::uint32_t exact = 0, bounded = 0;
    float d_exact = 0, d_bounded = 0;
    ASSERT_TRUE(tree.nearest(p, exact, d_exact));
    const float bound = d_exact * scale(rng) * scale(rng) * 0.5f;  // below the nearest's distance or above it
    const bool found = tree.nearest_within(p, bound, bounded, d_bounded);
    ASSERT_EQ(found, d_exact < bound) << "query " << p.transpose();
    if (!found) {
      ++beyond;
      continue;
    }
    ++within;
    ASSERT_EQ(bounded, exact);
    ASSERT_EQ(d_bounded, d_exact);
  }
  EXPECT_GT(within, 5000);
  EXPECT_GT(beyond, 2000);
  std::uint32_t i = 0;
  float d = 0;
  EXPECT_FALSE(KdTree(std::vector<Eigen::Vector3f>{}).nearest_within(Eigen::Vector3f::Zero(), 1.0f, i, d));
}

TEST(NearestGrid, EmptyOrNonFinitePointsFindNothingAndBadSizesThrow) {
  const std::vector<Eigen::Vector3f> none;
  std::uint32_t i = 0;
  float d = 0;
  const KdTree no_tree(none);
  EXPECT_FALSE(NearestGrid(no_tree, none, 0.003f, 0.01f).nearest(Eigen::Vector3f::Zero(), i, d));
  const std::vector<Eigen::Vector3f> nan(3, Eigen::Vector3f::Constant(NAN));
  const KdTree nan_tree(nan);
  EXPECT_FALSE(NearestGrid(nan_tree, nan, 0.003f, 0.01f).nearest(Eigen::Vector3f::Zero(), i, d));
  const std::vector<Eigen::Vector3f> one(1, Eigen::Vector3f(1, 2, 3));
  const KdTree one_tree(one);
  const NearestGrid grid(one_tree, one, 0.003f, 0.01f);
  EXPECT_TRUE(grid.nearest(Eigen::Vector3f(1, 2, 3.005f), i, d));
  EXPECT_FALSE(grid.nearest(Eigen::Vector3f(NAN, 2, 3), i, d));
  EXPECT_FALSE(grid.nearest(Eigen::Vector3f(1, 2, 3.5f), i, d));
  // Far outside, or infinite: outside the grid, not a cell the float-to-integer cast made up (the
  // sanitizer build checks the cast, in the look-up and in the prefetch).
  for (const float far : {1e20f, -1e20f, INFINITY, -INFINITY}) {
    EXPECT_FALSE(grid.nearest(Eigen::Vector3f(far, 2, 3), i, d)) << far;
    EXPECT_FALSE(grid.nearest(Eigen::Vector3f(1, far, 3), i, d)) << far;
    EXPECT_FALSE(grid.nearest(Eigen::Vector3f(1, 2, far), i, d)) << far;
    grid.prefetch(Eigen::Vector3f(far, far, far));
    grid.prefetch(Eigen::Vector3f(NAN, 2, 3));
  }
  EXPECT_THROW(NearestGrid(one_tree, one, 0.0f, 0.01f), Error);
  EXPECT_THROW(NearestGrid(one_tree, one, 1e-6f, 10.0f), Error) << "a grid of 10^19 cells is refused, not allocated";
  EXPECT_EQ(NearestGrid::cell_count(one, 1e-6f, 10.0f), std::numeric_limits<std::size_t>::max()) << "counted, not thrown";
  EXPECT_EQ(NearestGrid::cell_count(none, 0.003f, 0.01f), 0u);
}

TEST(OccupancyGrid, LevelsAreTwoInAPointsCellOneBesideItAndZeroFarther) {
  const std::vector<Eigen::Vector3f> pts = sphere_points(3000, 4);  // NaN at 7
  const float cell = 0.01f;
  const OccupancyGrid grid(pts, cell);
  ASSERT_FALSE(grid.empty());
  EXPECT_FLOAT_EQ(grid.cell_m(), cell);
  const KdTree tree(pts);
  // Every point's own cell is occupied.
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (i != 7) {
      ASSERT_EQ(grid.level(pts[i]), 2) << i;
    }
  }
  // Against the exact distance to the nearest point: level 2 means one within a cell's diagonal,
  // level 1 within two, and a point nearer than a cell's side always gives a nonzero level.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-0.15f, 0.15f);
  const float diagonal = std::sqrt(3.0f) * cell;
  int levels[3] = {0, 0, 0};
  for (int q = 0; q < 20000; ++q) {
    const Eigen::Vector3f p(u(rng), u(rng), u(rng));
    std::uint32_t nearest = 0;
    float d2 = 0;
    ASSERT_TRUE(tree.nearest(p, nearest, d2));
    const float d = std::sqrt(d2);
    const int level = grid.level(p);
    ++levels[level];
    if (level == 2) {
      EXPECT_LE(d, diagonal * 1.0001f);
    } else if (level == 1) {
      EXPECT_LE(d, 2 * diagonal * 1.0001f);
    } else {
      // A point nearer than a cell's side lies in this cell or one that touches it.
      EXPECT_GE(d, cell * 0.999f);
    }
  }
  EXPECT_GT(levels[0], 0);
  EXPECT_GT(levels[1], 0);
  EXPECT_GT(levels[2], 0);
  EXPECT_EQ(grid.level(Eigen::Vector3f::Constant(NAN)), 0);
  EXPECT_EQ(grid.level(Eigen::Vector3f(1e30f, 0, 0)), 0) << "far outside, no overflowing index";
  EXPECT_EQ(grid.level(Eigen::Vector3f(-1e30f, 0, 0)), 0);
}

TEST(OccupancyGrid, ARoomSizedCloudGetsWiderCellsAndBadInputNoGrid) {
  // 20 m wide: cells widened so that no side exceeds the cap.
  const std::vector<Eigen::Vector3f> wide = {{-10, 0, 1}, {10, 0, 1}, {0, 0.5f, 1}};
  const OccupancyGrid grid(wide, 0.01f);
  EXPECT_GE(grid.cell_m(), 20.0f / OccupancyGrid::kMaxCellsPerSide);
  for (const Eigen::Vector3f& p : wide) EXPECT_EQ(grid.level(p), 2);
  // Far from the origin, where float rounding eats the grid's margin: still every point's cell.
  const std::vector<Eigen::Vector3f> far = {{1e6f, 1e6f, 1e6f}, {1e6f + 0.5f, 1e6f, 1e6f}};
  const OccupancyGrid far_grid(far, 0.01f);
  for (const Eigen::Vector3f& p : far) EXPECT_EQ(far_grid.level(p), 2);
  // Nothing finite, a bad cell, or an extent that overflows a float: an empty grid, level 0 everywhere.
  const std::vector<Eigen::Vector3f> nan = {Eigen::Vector3f::Constant(NAN)};
  EXPECT_TRUE(OccupancyGrid(nan, 0.01f).empty());
  EXPECT_TRUE(OccupancyGrid(std::vector<Eigen::Vector3f>{}, 0.01f).empty());
  EXPECT_TRUE(OccupancyGrid(wide, 0.0f).empty());
  EXPECT_TRUE(OccupancyGrid(wide, NAN).empty());
  const std::vector<Eigen::Vector3f> huge = {{-3e38f, 0, 0}, {3e38f, 0, 0}};
  const OccupancyGrid none(huge, 0.01f);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.level(Eigen::Vector3f::Zero()), 0);
}

TEST(CellGrid, AKeyPlusAStepIsTheNeighboursKeyAndGapsAreCountedInWholeCells) {
  // Cells at both ends of each field that bin_points keeps with a margin of two (the steps of
  // -2 there are the edge cases), and about the field's middle, where coordinates cross zero.
  const std::int64_t m = 2, top = CellGrid::kMask - m;
  const std::int64_t coords[] = {m, m + 1, CellGrid::kOffset - 1, CellGrid::kOffset, CellGrid::kOffset + 1, top - 1, top};
  int checked = 0;
  for (std::int64_t x : coords)
    for (std::int64_t y : coords)
      for (std::int64_t z : coords) {
        const std::uint64_t k = CellGrid::key(x, y, z);
        EXPECT_EQ(CellGrid::coordinates(k), (std::array<std::int64_t, 3>{x, y, z}));
        for (std::int64_t dx = -m; dx <= m; ++dx)
          for (std::int64_t dy = -m; dy <= m; ++dy)
            for (std::int64_t dz = -m; dz <= m; ++dz) {
              ASSERT_EQ(k + CellGrid::step(dx, dy, dz), CellGrid::key(x + dx, y + dy, z + dz)) << x << " " << y << " " << z;
              ++checked;
            }
      }
  EXPECT_EQ(checked, 7 * 7 * 7 * 125);
  // Keys sort by x, then y, then z.
  EXPECT_LT(CellGrid::key(5, 9, 9), CellGrid::key(6, 0, 0));
  EXPECT_LT(CellGrid::key(5, 5, 9), CellGrid::key(5, 6, 0));
  // Neighbours touch; cells two apart leave one cell's side between them on that axis.
  EXPECT_EQ(CellGrid::squared_gap(1, -1, 1), 0);
  EXPECT_EQ(CellGrid::squared_gap(2, 0, 0), 1);
  EXPECT_EQ(CellGrid::squared_gap(-2, 2, 1), 2);
  EXPECT_EQ(CellGrid::squared_gap(-2, -2, -2), 3);
  EXPECT_EQ(CellGrid::squared_gap(0, 3, 0), 4);
}

TEST(RadixSort, EqualsTheComparisonSortIncludingTheOrderOfEqualKeys) {
  std::mt19937_64 rng(9);
  const int threads = thread_count();
  // (From kFrameSizedFrom items, with two threads, each pass runs on every thread: the sizes about
  // it, and one of several chunks with a short last one. A caller may ask for it at any size, as
  // bin_points does for the points it kept of a frame's: its chunks then run on one thread too.)
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{63}, std::size_t{64}, std::size_t{1000}, std::size_t{16385},
                        std::size_t{50000}, kFrameSizedFrom - 1, kFrameSizedFrom, std::size_t{200001}}) {
    for (int bits : {3, 20, 64}) {  // few distinct keys, some, any 64-bit value
      for (int t : {1, 2}) {
        for (bool asked : {false, true}) {
          SCOPED_TRACE(testing::Message() << n << " keys of " << bits << " bits on " << t << " threads"
                                          << (asked ? ", spread as asked" : ""));
          std::vector<KeyedIndex> items;
          for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint64_t key = bits == 64 ? rng() : (rng() & ((std::uint64_t{1} << bits) - 1)) << 17;
            items.emplace_back(key, i);
          }
          std::vector<KeyedIndex> expected = items;
          std::sort(expected.begin(), expected.end());
          set_thread_count(t);
          if (asked) radix_sort(items, true);
          else radix_sort(items);
          set_thread_count(threads);
          EXPECT_EQ(items, expected);
        }
      }
    }
  }
}

}  // namespace
}  // namespace viewpose
