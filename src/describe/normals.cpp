#include "viewpose/describe/normals.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "viewpose/core/threads.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/cell_grid.hpp"

#include "core/clones.hpp"

namespace viewpose {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The count of the candidates within sqrt(r2) of p, and the sums of their offsets from p and of
// the offsets' products (x, y, z, xx, xy, xz, yy, yz, zz): one branch-free pass with a 0/1 weight
// from the sign bit of d2 - r2, which vectorizes. Compiled twice, for AVX2 (8 floats at once) and
// for any x86-64 (4), the processor picks at run time. Offsets of a few centimetres keep single
// precision exact enough.
struct NeighbourSums {
  float v[10];
};
VIEWPOSE_CLONES NeighbourSums neighbour_sums(const float* ax, const float* ay, const float* az,
                                                                       std::size_t m, float px, float py, float pz, float r2) {
  float count = 0, sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
#pragma omp simd reduction(+ : count, sx, sy, sz, sxx, sxy, sxz, syy, syz, szz)
  for (std::size_t j = 0; j < m; ++j) {
    const float dx = ax[j] - px, dy = ay[j] - py, dz = az[j] - pz;
    const float w = static_cast<float>(std::bit_cast<std::uint32_t>(dx * dx + dy * dy + dz * dz - r2) >> 31);
    const float wx = w * dx, wy = w * dy, wz = w * dz;
    count += w;
    sx += wx, sy += wy, sz += wz;
    sxx += wx * dx, sxy += wx * dy, sxz += wx * dz;
    syy += wy * dy, syz += wy * dz, szz += wz * dz;
  }
  return {{count, sx, sy, sz, sxx, sxy, sxz, syy, syz, szz}};
}

// The smallest eigenvalue of the scatter matrix `cov` divided by its trace, and its eigenvector,
// or false when that eigenvalue is not well separated from the middle one (then the eigenvector is
// ill-conditioned, and a general solver decides). A plane's smallest eigenvalue is near 0 and far
// from the others, so Newton's method on the characteristic polynomial, started at 0, finds it in
// a few steps: left of the smallest root the polynomial rises and is concave, so the iterates climb
// to the root without overshooting. Its eigenvector is the largest cross product of two rows of
// cov - l I. This costs a third of a general 3x3 eigensolver's trigonometry.
bool smallest_eigen(const Eigen::Matrix3d& cov, Eigen::Vector3d& vector, double& value_over_trace) {
  const double trace = cov.trace();
  if (!(trace > 0)) return false;
  const Eigen::Matrix3d a = cov * (1.0 / trace);  // eigenvalues in [0, 1], summing to 1
  const double c1 = a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1) + a(0, 0) * a(2, 2) - a(0, 2) * a(0, 2) + a(1, 1) * a(2, 2) - a(1, 2) * a(1, 2);
  const double c0 = a.determinant();
  if (!(c1 > 0)) return false;  // two eigenvalues are 0: a line
  // det(l I - a) = l^3 - l^2 + c1 l - c0, from Newton's first step from 0.
  double l = c0 / c1;
  for (int iteration = 0; iteration < 32; ++iteration) {
    // Halley's step: three correct digits become nine, so two or three steps are enough.
    const double f = ((l - 1) * l + c1) * l - c0, df = (3 * l - 2) * l + c1, ddf = 6 * l - 2;
    const double denominator = 2 * df * df - f * ddf;
    if (!(df > 0 && denominator > 0)) break;
    const double step = 2 * f * df / denominator;
    l -= step;
    if (std::abs(step) <= 1e-8) break;  // the normal then is within 1e-6 rad
  }
  const Eigen::Matrix3d m = a - l * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d c[3] = {m.row(0).cross(m.row(1)), m.row(0).cross(m.row(2)), m.row(1).cross(m.row(2))};
  const double n2[3] = {c[0].squaredNorm(), c[1].squaredNorm(), c[2].squaredNorm()};
  const int best = n2[0] >= n2[1] ? (n2[0] >= n2[2] ? 0 : 2) : (n2[1] >= n2[2] ? 1 : 2);
  // |c| is about (l1 - l0)(l2 - l0): small when the two smallest eigenvalues nearly coincide.
  if (!(n2[best] > 1e-8)) return false;
  vector = c[best] / std::sqrt(n2[best]);
  value_over_trace = std::max(0.0, l);
  return true;
}

// Normal (towards the viewpoint) and curvature of the plane whose scatter matrix is `cov`.
void plane_of_covariance(const Eigen::Matrix3d& cov, const Eigen::Vector3f& point, const Eigen::Vector3f& viewpoint,
                         Eigen::Vector3f& normal, float& curvature) {
  Eigen::Vector3f n;
  Eigen::Vector3d nd;
  double l0;
  if (smallest_eigen(cov, nd, l0)) {
    n = nd.cast<float>();
    curvature = static_cast<float>(l0);
  } else {
    // Nearly a line or a ball: the general solver, in single precision as PCL's own.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig;
    eig.computeDirect(cov.cast<float>());  // eigenvalues in increasing order
    const Eigen::Vector3f l = eig.eigenvalues();
    n = eig.eigenvectors().col(0);
    const float sum = l.sum();
    curvature = sum > 0 ? std::max(0.0f, l[0]) / sum : 0.0f;
  }
  if (n.dot(viewpoint - point) < 0) n = -n;
  normal = n;
}

// Plane through the neighbours of point i; writes its normal and curvature.
template <typename Neighbours>
void fit_normal(const PointCloud& cloud, std::size_t i, const Neighbours& neighbours, std::size_t count,
                const Eigen::Vector3f& viewpoint, Eigen::Vector3f& normal, float& curvature) {
  if (count < 3) {
    normal = Eigen::Vector3f::Constant(kNaN);
    curvature = kNaN;
    return;
  }
  // Mean-centred covariance in double: small neighbourhoods far from the origin stay accurate.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < count; ++k) mean += cloud.points[neighbours(k)].template cast<double>();
  mean /= static_cast<double>(count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d d = cloud.points[neighbours(k)].template cast<double>() - mean;
    cov.noalias() += d * d.transpose();
  }
  plane_of_covariance(cov, cloud.points[i], viewpoint, normal, curvature);
}

}  // namespace

void estimate_normals(PointCloud& cloud, const NormalOptions& options) {
  if (!(options.radius_m > 0)) throw Error(fmt::format("normals: radius {} must be positive", options.radius_m));
  cloud.normals.assign(cloud.size(), Eigen::Vector3f::Constant(kNaN));
  cloud.curvature.assign(cloud.size(), kNaN);
  // Points binned into cubes half the radius wide: a point's neighbours are among the points of
  // the cubes whose nearest corner lies within the radius of its own cube. The candidates are
  // gathered once per cube and shared by all its points, which makes this several times faster
  // than a radius search per point in a tree, with the same neighbours.
  const float r2 = options.radius_m * options.radius_m;
  // Cubes of a half radius: with a third or a quarter a point meets fewer candidates (271 or 222
  // instead of 368 for 123 neighbours on a noisy jug), but the cubes and their columns cost more
  // than that saves (2x and 4x slower, measured).
  constexpr int kDiv = 2;
  const CellGrid grid = bin_points(cloud.points, {}, options.radius_m / kDiv, kDiv);
  const std::vector<KeyedIndex>& keyed = grid.items;
  const std::vector<std::uint64_t>& cubes = grid.cells;
  const std::vector<std::size_t>& first = grid.first;
  const auto key = CellGrid::key;
  // The points' coordinates in cube order, so that a cube's points are copied as one run.
  std::vector<float> sorted_x(keyed.size()), sorted_y(keyed.size()), sorted_z(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    const Eigen::Vector3f& q = cloud.points[keyed[k].second];
    sorted_x[k] = q.x(), sorted_y[k] = q.y(), sorted_z[k] = q.z();
  }
  // The columns (x + ox, y + oy) around a cube, and how far along z each reaches: the largest |oz|
  // whose cube can hold a neighbour, or -1.
  constexpr int kSide = 2 * kDiv + 1, kColumns = kSide * kSide;
  std::int64_t column_reach[kColumns];
  for (int column = 0; column < kColumns; ++column) {
    const std::int64_t ox = column / kSide - kDiv, oy = column % kSide - kDiv;
    column_reach[column] = -1;
    for (std::int64_t oz = 0; oz <= kDiv; ++oz)
      if (CellGrid::squared_gap(ox, oy, oz) <= kDiv * kDiv) column_reach[column] = oz;
  }
  // Where each column around each cube starts (at z - reach) in the sorted cubes: those positions
  // only grow from cube to cube, so one forward pass per column finds them.
  std::vector<std::uint32_t> column_start(cubes.size() * kColumns);
#pragma omp parallel for schedule(dynamic, 1)
  for (int column = 0; column < kColumns; ++column) {
    if (column_reach[column] < 0) continue;
    const std::int64_t ox = column / kSide - kDiv, oy = column % kSide - kDiv;
    std::size_t b = 0;
    for (std::size_t a = 0; a < cubes.size(); ++a) {
      const auto [x, y, z] = CellGrid::coordinates(cubes[a]);
      const std::uint64_t lo = key(x + ox, y + oy, z - column_reach[column]);
      while (b < cubes.size() && cubes[b] < lo) ++b;
      column_start[a * kColumns + static_cast<std::size_t>(column)] = static_cast<std::uint32_t>(b);
    }
  }
  const auto n = static_cast<std::ptrdiff_t>(cubes.size());
  FirstException failed;
#pragma omp parallel
  {
    std::vector<float> cx, cy, cz;  // the candidates, one array per coordinate
    std::vector<std::pair<std::size_t, std::size_t>> runs;  // runs of sorted points to copy
#pragma omp for schedule(dynamic, 8)
    for (std::ptrdiff_t a = 0; a < n; ++a) {
      failed.run(a, [&] {
        const auto [x, y, z] = CellGrid::coordinates(cubes[static_cast<std::size_t>(a)]);
        runs.clear();
        std::size_t m = 0;
        for (int column = 0; column < kColumns; ++column) {
          const std::int64_t oz_max = column_reach[static_cast<std::size_t>(column)];
          if (oz_max < 0) continue;  // no cube of this column comes within the radius
          const std::int64_t ox = column / kSide - kDiv, oy = column % kSide - kDiv;
          // The cubes of a column that can hold neighbours (z - oz_max .. z + oz_max) are
          // consecutive in the sorted order, and so are their points: one run to copy.
          const std::uint64_t hi = key(x + ox, y + oy, z + oz_max);
          const std::size_t b = column_start[static_cast<std::size_t>(a) * kColumns + static_cast<std::size_t>(column)];
          std::size_t e = b;
          while (e < cubes.size() && cubes[e] <= hi) ++e;
          if (e == b) continue;
          runs.emplace_back(first[b], first[e]);
          m += first[e] - first[b];
        }
        if (cx.size() < m) cx.resize(m), cy.resize(m), cz.resize(m);
        std::size_t filled = 0;
        for (const auto& [from, to] : runs) {
          std::copy(sorted_x.begin() + static_cast<std::ptrdiff_t>(from), sorted_x.begin() + static_cast<std::ptrdiff_t>(to), cx.begin() + static_cast<std::ptrdiff_t>(filled));
          std::copy(sorted_y.begin() + static_cast<std::ptrdiff_t>(from), sorted_y.begin() + static_cast<std::ptrdiff_t>(to), cy.begin() + static_cast<std::ptrdiff_t>(filled));
          std::copy(sorted_z.begin() + static_cast<std::ptrdiff_t>(from), sorted_z.begin() + static_cast<std::ptrdiff_t>(to), cz.begin() + static_cast<std::ptrdiff_t>(filled));
          filled += to - from;
        }
        for (std::size_t k = first[static_cast<std::size_t>(a)]; k < first[static_cast<std::size_t>(a) + 1]; ++k) {
          const std::uint32_t i = keyed[k].second;
          const Eigen::Vector3f& p = cloud.points[i];
          const float px = p.x(), py = p.y(), pz = p.z();
          const float* ax = cx.data();
          const float* ay = cy.data();
          const float* az = cz.data();
          const NeighbourSums sums = neighbour_sums(ax, ay, az, m, px, py, pz, r2);
          const float count = sums.v[0], sx = sums.v[1], sy = sums.v[2], sz = sums.v[3], sxx = sums.v[4], sxy = sums.v[5],
                      sxz = sums.v[6], syy = sums.v[7], syz = sums.v[8], szz = sums.v[9];
          if (count < 3) continue;  // stays NaN
          const double nn = count, mx = sx / nn, my = sy / nn, mz = sz / nn;
          Eigen::Matrix3d cov;
          cov << sxx - nn * mx * mx, sxy - nn * mx * my, sxz - nn * mx * mz,
                 sxy - nn * mx * my, syy - nn * my * my, syz - nn * my * mz,
                 sxz - nn * mx * mz, syz - nn * my * mz, szz - nn * mz * mz;
          plane_of_covariance(cov, p, options.viewpoint, cloud.normals[i], cloud.curvature[i]);
        }
      });
    }
  }
  failed.rethrow();
}

void estimate_normals_organized(PointCloud& cloud, const NormalOptions& options) {
  if (!cloud.organized()) throw Error("normals: the organized path needs an organized cloud (height > 1)");
  if (!(options.radius_m > 0 && options.focal_px > 0)) throw Error("normals: radius and focal length must be positive");
  cloud.normals.assign(cloud.size(), Eigen::Vector3f::Constant(kNaN));
  cloud.curvature.assign(cloud.size(), kNaN);
  const int W = cloud.width, H = cloud.height;
  const float r2 = options.radius_m * options.radius_m;
  FirstException failed;
#pragma omp parallel
  {
    std::vector<std::uint32_t> neighbours;
#pragma omp for schedule(dynamic, 16)
    for (int v = 0; v < H; ++v) {
      failed.run(v, [&] {
        for (int u = 0; u < W; ++u) {
          const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(W) + static_cast<std::size_t>(u);
          const Eigen::Vector3f& p = cloud.points[i];
          if (!p.allFinite() || !(p.z() > 0)) continue;
          // The radius covers about focal * radius / z pixels at depth z.
          const int half = std::clamp(static_cast<int>(std::ceil(options.focal_px * options.radius_m / p.z())), 1, options.max_window_px);
          neighbours.clear();
          for (int dv = -half; dv <= half; ++dv) {
            const int vv = v + dv;
            if (vv < 0 || vv >= H) continue;
            for (int du = -half; du <= half; ++du) {
              const int uu = u + du;
              if (uu < 0 || uu >= W) continue;
              const std::size_t j = static_cast<std::size_t>(vv) * static_cast<std::size_t>(W) + static_cast<std::size_t>(uu);
              if ((cloud.points[j] - p).squaredNorm() <= r2) neighbours.push_back(static_cast<std::uint32_t>(j));  // NaN fails
            }
          }
          fit_normal(cloud, i, [&](std::size_t k) { return neighbours[k]; }, neighbours.size(), options.viewpoint,
                     cloud.normals[i], cloud.curvature[i]);
        }
      });
    }
  }
  failed.rethrow();
}

}  // namespace viewpose
