#include "viewpose/segment/planes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>

#include "viewpose/core/threads.hpp"

namespace viewpose {

namespace {

std::vector<std::uint32_t> inliers_of(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices,
                                      const Eigen::Vector4f& plane, float threshold) {
  std::vector<std::uint32_t> in;
  for (std::uint32_t i : indices) {
    if (std::abs(plane.head<3>().dot(points[i]) + plane[3]) <= threshold) in.push_back(i);
  }
  return in;
}

// The spread of values from their 2nd to their 98th percentile (the extremes ignored).
float spread_2_to_98(std::vector<double>& s) {
  const auto lo = s.begin() + static_cast<std::ptrdiff_t>(s.size() * 2 / 100),
             hi = s.begin() + static_cast<std::ptrdiff_t>(s.size() * 98 / 100);
  std::nth_element(s.begin(), hi, s.end());
  std::nth_element(s.begin(), lo, hi);
  return static_cast<float>(*hi - *lo);
}

// Least-squares plane of a set of points.
Eigen::Vector4f refit(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> in) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::uint32_t i : in) mean += points[i].cast<double>();
  mean /= static_cast<double>(in.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::uint32_t i : in) {
    const Eigen::Vector3d d = points[i].cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.dot(-mean) < 0) n = -n;  // face the sensor at the origin
  return {static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()), static_cast<float>(-n.dot(mean))};
}

}  // namespace

bool PlanePatch::covers(const Eigen::Vector3f& p) const {
  if (covered.empty() || !(cell_m > 0)) return false;
  const float x = (axis_u.dot(p) - origin.x()) / cell_m, y = (axis_v.dot(p) - origin.y()) / cell_m;
  if (!(x > -1 && y > -1 && x < static_cast<float>(width) + 1 && y < static_cast<float>(height) + 1)) return false;  // NaN too
  const int cx = static_cast<int>(std::floor(x)), cy = static_cast<int>(std::floor(y));
  for (int yy = std::max(0, cy - 1); yy <= std::min(height - 1, cy + 1); ++yy)
    for (int xx = std::max(0, cx - 1); xx <= std::min(width - 1, cx + 1); ++xx) {
      if (covered[static_cast<std::size_t>(yy) * static_cast<std::size_t>(width) + static_cast<std::size_t>(xx)]) return true;
    }
  return false;
}

Plane fit_plane(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, const PlaneOptions& o) {
  Plane best;
  if (indices.size() < 3) return best;
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<std::size_t> pick(0, indices.size() - 1);
  // Hypotheses are scored on a fixed random subsample (a few thousand points estimate the inlier
  // share to within a percent); only the winner is counted on every point.
  constexpr std::size_t kScoreSample = 2000;
  std::vector<std::uint32_t> sample;
  if (indices.size() <= kScoreSample) {
    sample.assign(indices.begin(), indices.end());
  } else {
    for (std::size_t k = 0; k < kScoreSample; ++k) sample.push_back(indices[pick(rng)]);
  }
  // The sample's coordinates, each in an array of its own: every hypothesis counts its inliers
  // among them, and read through the indices those counts were a loop the compiler could not
  // vectorize (most of the planes' time on a room's frame, where a far wall's noise keeps RANSAC
  // from stopping early). The same sums in the order Eigen's dot adds them, so the same counts
  // (where multiplies and adds are not fused: a VIEWPOSE_NATIVE build may differ in the last bit).
  std::vector<float> xs(sample.size()), ys(sample.size()), zs(sample.size());
  for (std::size_t k = 0; k < sample.size(); ++k) {
    const Eigen::Vector3f& p = points[sample[k]];
    xs[k] = p.x();
    ys[k] = p.y();
    zs[k] = p.z();
  }
  std::size_t best_count = 0;
  double needed = o.max_iterations;
  for (int it = 0; it < o.max_iterations && it < needed; ++it) {
    const Eigen::Vector3f a = points[indices[pick(rng)]], b = points[indices[pick(rng)]], c = points[indices[pick(rng)]];
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (!(n.norm() > 1e-9f)) continue;  // collinear or repeated sample
    n.normalize();
    const Eigen::Vector4f plane(n.x(), n.y(), n.z(), -n.dot(a));
    std::size_t count = 0;
    const float nx = n.x(), ny = n.y(), nz = n.z(), d = plane[3], band = o.distance_threshold_m;
    for (std::size_t k = 0; k < xs.size(); ++k) count += std::abs(nx * xs[k] + (ny * ys[k] + nz * zs[k]) + d) <= band ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best.coefficients = plane;
      // Samples still needed for 99 % confidence of an all-inlier sample (PCL's RANSAC rule).
      const double w = static_cast<double>(count) / static_cast<double>(sample.size());
      const double p_fail = 1.0 - w * w * w;
      needed = p_fail <= 0 ? 0 : std::log(0.01) / std::log(std::max(p_fail, 1e-12));
    }
  }
  if (best_count < 3) return best;
  best.inliers = inliers_of(points, indices, best.coefficients, o.distance_threshold_m);
  best.coefficients = refit(points, best.inliers);
  best.inliers = inliers_of(points, indices, best.coefficients, o.distance_threshold_m);
  return best;
}

namespace {

std::vector<std::uint32_t> minus(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
  std::vector<std::uint32_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

struct Patch {
  std::vector<std::uint32_t> points;  ///< ascending
  std::size_t cells = 0;
  float cell_m = 0;
  float extent_m = 0;  ///< smaller in-plane spread of the cells (2nd to 98th percentile)
  PlanePatch seen;     ///< the cells of every component of at least `min_cells`
};

// The largest connected patch of a plane's inliers: the inliers binned into square cells of the
// plane's own 2-D coordinates (a dense grid over their extent), cells joined to their 8 neighbours.
// Every component of at least `min_cells` cells (of the cell asked for) is kept in `seen`.
Patch largest_patch(std::span<const Eigen::Vector3f> points, const Plane& plane, float cell, double min_cells) {
  Patch best;
  if (plane.inliers.empty()) return best;
  const Eigen::Vector3f n = plane.coefficients.head<3>();
  const Eigen::Vector3f a = (std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY()).cross(n).normalized();
  const Eigen::Vector3f b = n.cross(a);
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (std::uint32_t i : plane.inliers) {
    const Eigen::Vector2f q(a.dot(points[i]), b.dot(points[i]));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  // At most 4 M cells: a plane wider than 20 m (nothing a depth camera sees) gets coarser cells.
  constexpr double kMaxCells = 4e6;
  const Eigen::Vector2f span = hi - lo;
  const float cell_asked = cell;
  cell = std::max(cell, static_cast<float>(std::sqrt(static_cast<double>(span.x()) * span.y() / kMaxCells)));
  min_cells *= static_cast<double>(cell_asked) * cell_asked / (static_cast<double>(cell) * cell);
  const int W = static_cast<int>(span.x() / cell) + 1, H = static_cast<int>(span.y() / cell) + 1;
  std::vector<std::uint32_t> cell_of(plane.inliers.size());
  std::vector<std::int32_t> label(static_cast<std::size_t>(W) * static_cast<std::size_t>(H), -1);  // -1 empty, -2 occupied
  for (std::size_t k = 0; k < plane.inliers.size(); ++k) {
    const Eigen::Vector3f& p = points[plane.inliers[k]];
    const int x = std::min(W - 1, static_cast<int>((a.dot(p) - lo.x()) / cell)), y = std::min(H - 1, static_cast<int>((b.dot(p) - lo.y()) / cell));
    cell_of[k] = static_cast<std::uint32_t>(y * W + x);
    label[cell_of[k]] = -2;
  }
  std::vector<std::size_t> size;
  std::vector<std::uint32_t> queue, largest_cells;
  for (std::uint32_t start = 0; start < label.size(); ++start) {
    if (label[start] != -2) continue;
    const auto id = static_cast<std::int32_t>(size.size());
    label[start] = id;
    queue.assign(1, start);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int x = static_cast<int>(queue[q] % static_cast<std::uint32_t>(W)), y = static_cast<int>(queue[q] / static_cast<std::uint32_t>(W));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
          const auto j = static_cast<std::uint32_t>(yy * W + xx);
          if (label[j] == -2) {
            label[j] = id;
            queue.push_back(j);
          }
        }
    }
    size.push_back(queue.size());
    if (queue.size() > largest_cells.size()) largest_cells.swap(queue);
  }
  const auto largest = static_cast<std::int32_t>(std::max_element(size.begin(), size.end()) - size.begin());
  best.cells = size[static_cast<std::size_t>(largest)];
  best.cell_m = cell;
  // The spread is measured on the cells, not the points: a sensor samples near parts of a table
  // more densely than far ones, and the extent must not depend on that.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> centres;
  for (std::uint32_t c : largest_cells) {
    centres.emplace_back((c % static_cast<std::uint32_t>(W) + 0.5) * cell, (c / static_cast<std::uint32_t>(W) + 0.5) * cell);
    mean += centres.back();
  }
  mean /= static_cast<double>(centres.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& c : centres) cov.noalias() += (c - mean) * (c - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  best.extent_m = std::numeric_limits<float>::infinity();
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> s;
    s.reserve(centres.size());
    for (const Eigen::Vector2d& c : centres) s.push_back((c - mean).dot(eig.eigenvectors().col(axis)));
    best.extent_m = std::min(best.extent_m, spread_2_to_98(s));
  }
  for (std::size_t k = 0; k < plane.inliers.size(); ++k) {
    if (label[cell_of[k]] == largest) best.points.push_back(plane.inliers[k]);
  }
  PlanePatch& seen = best.seen;
  seen.axis_u = a;
  seen.axis_v = b;
  seen.origin = lo;
  seen.cell_m = cell;
  seen.width = W;
  seen.height = H;
  seen.covered.resize(label.size());
  for (std::size_t j = 0; j < label.size(); ++j) {
    seen.covered[j] = label[j] >= 0 && (label[j] == largest || static_cast<double>(size[static_cast<std::size_t>(label[j])]) >= min_cells);
  }
  return best;  // ascending, as the inliers are
}

}  // namespace

PlaneRemoval remove_large_planes(const PointCloud& cloud, const PlaneOptions& o) {
  PlaneRemoval out;
  // Planes are searched for among `pool`, an even sample of the cloud's finite points; a plane that
  // is not large is left in the cloud but taken out of the pool, so that a smaller wall behind it
  // can still be found.
  std::vector<std::uint32_t> pool;
  if (cloud.organized() && o.max_sample_points > 0) {
    // An image: every s-th pixel of every s-th row, a square lattice. (Every k-th pixel in raster
    // order is not: when k divides the width it samples whole columns and nothing between them,
    // and the plane's patch falls apart into strips.)
    const auto s = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(cloud.size()) / static_cast<double>(o.max_sample_points))));
    for (int v = s / 2; v < cloud.height; v += s)
      for (int u = s / 2; u < cloud.width; u += s) {
        const auto i = static_cast<std::uint32_t>(v * cloud.width + u);
        if (cloud.points[i].allFinite()) pool.push_back(i);
      }
  } else if (o.max_sample_points > 0 && cloud.size() > o.max_sample_points) {
    // Any other cloud: points drawn at random (seeded), as a file's order may be a grid of its own
    // that a fixed stride would alias with.
    std::mt19937_64 rng(o.seed);
    std::uniform_int_distribution<std::size_t> pick(0, cloud.size() - 1);
    for (std::size_t k = 0; k < o.max_sample_points; ++k) {
      const std::size_t i = pick(rng);
      if (cloud.points[i].allFinite()) pool.push_back(static_cast<std::uint32_t>(i));
    }
    std::sort(pool.begin(), pool.end());
    pool.erase(std::unique(pool.begin(), pool.end()), pool.end());
  } else {
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (cloud.points[i].allFinite()) pool.push_back(static_cast<std::uint32_t>(i));
    }
  }
  PlaneOptions round = o;
  // Cells of the inlier band's width: neighbouring cells link points up to about 2.8 cells apart.
  const float patch_cell = o.distance_threshold_m;
  for (int attempt = 0; attempt < 2 * o.max_planes && static_cast<int>(out.removed.size()) < o.max_planes && pool.size() >= 3;
       ++attempt) {
    round.seed = o.seed + static_cast<std::uint64_t>(attempt);
    Plane plane = fit_plane(cloud.points, pool, round);
    // A patch of min_area covers that many cells, each holding a point at least: the best plane
    // left has fewer inliers, so no plane left is large.
    if (static_cast<double>(plane.inliers.size()) < o.min_area_m2 / (patch_cell * patch_cell) || plane.inliers.size() < 3) break;
    // Large means one connected patch spans min_extent in both directions: a table or a wall does;
    // coplanar faces of boxes (apart, or in a row) and object faces do not.
    Patch patch = largest_patch(cloud.points, plane, patch_cell, o.min_area_m2 / (patch_cell * patch_cell));
    const float patch_extent = patch.extent_m;
    pool = minus(pool, plane.inliers);
    plane.area_m2 = static_cast<float>(patch.cells) * patch.cell_m * patch.cell_m;
    if (plane.area_m2 < o.min_area_m2 || patch_extent < o.min_extent_m) continue;
    plane.extent_m = patch_extent;
    plane.patch = std::move(patch.seen);
    out.removed.push_back(std::move(plane));
  }
  // Every point, not just the sample, is tested against the planes found: in one pass, split
  // into contiguous chunks across threads whose results are joined in order.
  const std::size_t planes = out.removed.size();
  const int chunks = std::max(1, thread_count());
  std::vector<std::vector<std::vector<std::uint32_t>>> found(static_cast<std::size_t>(chunks),
                                                             std::vector<std::vector<std::uint32_t>>(planes + 1));
  FirstException failed;
#pragma omp parallel for schedule(static, 1) num_threads(chunks)
  for (int chunk = 0; chunk < chunks; ++chunk) {
    failed.run(chunk, [&] {
      auto& lists = found[static_cast<std::size_t>(chunk)];  // one per plane, then the remaining points
      const std::size_t begin = cloud.size() * static_cast<std::size_t>(chunk) / static_cast<std::size_t>(chunks),
                        end = cloud.size() * static_cast<std::size_t>(chunk + 1) / static_cast<std::size_t>(chunks);
      for (std::size_t i = begin; i < end; ++i) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) continue;
        bool on_plane = false;
        for (std::size_t k = 0; k < planes; ++k) {
          const Eigen::Vector4f& c = out.removed[k].coefficients;
          if (std::abs(c.head<3>().dot(p) + c[3]) <= o.distance_threshold_m) {
            lists[k].push_back(static_cast<std::uint32_t>(i));
            on_plane = true;
          }
        }
        if (!on_plane) lists[planes].push_back(static_cast<std::uint32_t>(i));
      }
    });
  }
  failed.rethrow();
  for (std::size_t k = 0; k <= planes; ++k) {
    std::vector<std::uint32_t>& all = k < planes ? out.removed[k].inliers : out.remaining;
    all.clear();
    for (const auto& lists : found) all.insert(all.end(), lists[k].begin(), lists[k].end());
  }
  return out;
}

}  // namespace viewpose
