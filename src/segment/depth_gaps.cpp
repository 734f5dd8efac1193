#include "viewpose/segment/depth_gaps.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace viewpose {

std::vector<DepthGap> missing_depth_gaps(const DepthImage& depth, const CameraIntrinsics& K,
                                         std::span<const std::span<const Eigen::Vector3f>> pieces, float point_spacing_m,
                                         float depth_tolerance_m, int max_unmeasured_px) {
  const int W = depth.width, H = depth.height;
  if (W <= 0 || H <= 0 || pieces.size() < 2 || max_unmeasured_px < 1 || static_cast<std::size_t>(W) * H != depth.depth_m.size() ||
      K.width != W || K.height != H || !(K.fx > 0) || !(K.fy > 0)) {
    return {};
  }
  const auto measured = [](float z) { return std::isfinite(z) && z > 0; };  // (0: no measurement, as a driver writes it)
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const auto index = [W](int u, int v) { return static_cast<std::size_t>(v) * static_cast<std::size_t>(W) + static_cast<std::size_t>(u); };
  // Each piece's measured pixels: those near a point's projection at the point's depth. A pixel two
  // pieces claim keeps the first's (they touch there: no gap to find).
  std::vector<std::uint32_t> label(depth.depth_m.size(), kNone);
  std::vector<int> steps(depth.depth_m.size(), 0);
  std::vector<std::size_t> front;
  for (std::uint32_t k = 0; k < pieces.size(); ++k) {
    for (const Eigen::Vector3f& p : pieces[k]) {
      if (!p.allFinite() || !(p.z() > 0)) continue;
      const Eigen::Vector2d uv = K.project(p.cast<double>());
      if (!(uv.x() > -0.5 && uv.y() > -0.5 && uv.x() < W - 0.5 && uv.y() < H - 0.5)) continue;
      const int cu = static_cast<int>(std::lround(uv.x())), cv = static_cast<int>(std::lround(uv.y()));
      const int r = std::max(0, static_cast<int>(std::ceil(0.5 * point_spacing_m * K.fx / p.z())));
      for (int v = std::max(0, cv - r); v <= std::min(H - 1, cv + r); ++v)
        for (int u = std::max(0, cu - r); u <= std::min(W - 1, cu + r); ++u) {
          const std::size_t i = index(u, v);
          const float z = depth.depth_m[i];
          if (label[i] != kNone || !measured(z) || std::abs(z - p.z()) > depth_tolerance_m) continue;
          label[i] = k;
          front.push_back(i);
        }
    }
  }
  // Every piece grows through unmeasured pixels, one ring a step (a breadth-first search from all
  // of them at once): an unmeasured pixel belongs to the piece that reaches it first, at `steps`.
  // Where a pixel of one piece's growth (or the piece) borders another's, a path of
  // steps_a + steps_b unmeasured pixels joins them; with growth up to half the bound on each side
  // (one more on the first), every such meeting within the bound is seen.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> best;
  const auto meet = [&](std::size_t i, std::size_t j) {
    const std::uint32_t a = label[i], b = label[j];
    if (a == kNone || b == kNone || a == b) return;
    const int length = steps[i] + steps[j];
    if (length < 1 || length > max_unmeasured_px) return;
    const auto key = std::minmax(a, b);
    const auto [at, fresh] = best.emplace(std::pair(key.first, key.second), length);
    if (!fresh) at->second = std::min(at->second, length);
  };
  const int reach = (max_unmeasured_px + 1) / 2;
  std::vector<std::size_t> next;
  for (int step = 1; step <= reach && !front.empty(); ++step) {
    next.clear();
    for (const std::size_t i : front) {
      const int u = static_cast<int>(i % static_cast<std::size_t>(W)), v = static_cast<int>(i / static_cast<std::size_t>(W));
      const std::pair<int, int> around[4] = {{u + 1, v}, {u - 1, v}, {u, v + 1}, {u, v - 1}};
      for (const auto& [nu, nv] : around) {
        if (nu < 0 || nv < 0 || nu >= W || nv >= H) continue;
        const std::size_t j = index(nu, nv);
        if (label[j] != kNone) {
          meet(i, j);
          continue;
        }
        if (measured(depth.depth_m[j])) continue;  // measured, and no piece's: a path ends here
        label[j] = label[i];
        steps[j] = step;
        next.push_back(j);
      }
    }
    front.swap(next);
  }
  // The last ring's pixels may border one another's growth without having been looked from.
  for (const std::size_t i : front) {
    const int u = static_cast<int>(i % static_cast<std::size_t>(W)), v = static_cast<int>(i / static_cast<std::size_t>(W));
    if (u + 1 < W) meet(i, index(u + 1, v));
    if (u > 0) meet(i, index(u - 1, v));
    if (v + 1 < H) meet(i, index(u, v + 1));
    if (v > 0) meet(i, index(u, v - 1));
  }
  std::vector<DepthGap> gaps;
  for (const auto& [pair, length] : best) gaps.push_back({pair.first, pair.second, length});
  return gaps;
}

}  // namespace viewpose
