#include "viewpose/segment/convex_segments.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {

struct Cell {
  Eigen::Vector3i coord;
  std::vector<std::uint32_t> points;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero when the cell has too few points
};

std::uint64_t pack(const Eigen::Vector3i& c) {
  constexpr std::int64_t kOffset = 1 << 20, kMask = (1 << 21) - 1;
  std::uint64_t key = 0;
  for (int k = 0; k < 3; ++k) key = (key << 21) | static_cast<std::uint64_t>((c[k] + kOffset) & kMask);
  return key;
}

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Whether the surface runs on from cell a to cell b without a concave crease or a step.
bool joined(const Cell& a, const Cell& b, const ConvexSegmentOptions& o, double smooth_cos, double fold_cos) {
  const Eigen::Vector3d gap = a.centroid - b.centroid;
  const double length = gap.norm();
  if (length <= 0) return true;
  const Eigen::Vector3d d = gap / length;
  if (a.normal.dot(b.normal) >= smooth_cos) {
    // Nearly parallel: the same surface if the gap runs along it, a step (one face hiding another
    // behind it) if the gap runs across it.
    return std::abs(a.normal.dot(d)) < o.step_cosine && std::abs(b.normal.dot(d)) < o.step_cosine;
  }
  // On a convex surface the normals open up along the gap between two points.
  if (!(a.normal.dot(b.normal) > fold_cos && (a.normal - b.normal).dot(d) > o.convex_margin)) return false;
  // LCCP's sanity criterion: two faces meeting at an edge straddle it, so the gap runs across the
  // edge line (n_a x n_b). A gap along that line (a face beside a curved surface, not meeting it)
  // makes the convexity test meaningless. The allowed angle to the edge line grows from 0 to 60
  // degrees as the normals part (Stein et al.'s sigmoid: 25 degrees centre, slope 0.25 per degree).
  const Eigen::Vector3d edge = a.normal.cross(b.normal).normalized();
  const double normals_deg = std::acos(std::clamp(a.normal.dot(b.normal), -1.0, 1.0)) * 180.0 / M_PI;
  const double min_angle_deg = 60.0 / (1.0 + std::exp(-0.25 * (normals_deg - 25.0)));
  return std::abs(edge.dot(d)) <= std::cos(min_angle_deg * M_PI / 180.0);
}

}  // namespace

std::vector<Cluster> convex_segments(const PointCloud& cloud, const ConvexSegmentOptions& o) {
  if (!(o.cell_m > 0)) throw Error(fmt::format("convex segments: cell size {} must be positive", o.cell_m));
  std::vector<Cell> cells;
  std::unordered_map<std::uint64_t, std::uint32_t> cell_of_key;
  const float inv = 1.0f / o.cell_m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() * inv > float(1 << 19)) continue;
    const Eigen::Vector3i c((p * inv).array().floor().cast<int>());
    const auto [it, added] = cell_of_key.try_emplace(pack(c), static_cast<std::uint32_t>(cells.size()));
    if (added) cells.push_back(Cell{c, {}});
    cells[it->second].points.push_back(static_cast<std::uint32_t>(i));
  }
  const double incidence_cos = std::cos(o.max_incidence_deg * M_PI / 180.0);
  for (Cell& cell : cells) {
    if (cell.points.size() < std::max<std::size_t>(o.min_cell_points, 3)) continue;
    for (std::uint32_t i : cell.points) cell.centroid += cloud.points[i].cast<double>();
    cell.centroid /= static_cast<double>(cell.points.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : cell.points) {
      const Eigen::Vector3d q = cloud.points[i].cast<double>() - cell.centroid;
      cov += q * q.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    cell.normal = eig.eigenvectors().col(0);
    if (cell.normal.dot(cell.centroid) > 0) cell.normal = -cell.normal;  // towards the camera
    if (-cell.normal.dot(cell.centroid.normalized()) < incidence_cos) cell.normal.setZero();  // seen edge-on
  }

  const double smooth_cos = std::cos(o.smooth_angle_deg * M_PI / 180.0), fold_cos = std::cos(o.max_fold_deg * M_PI / 180.0);
  std::vector<std::uint32_t> parent(cells.size());
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::uint32_t a = 0; a < cells.size(); ++a) {
    if (cells[a].normal.isZero()) continue;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = cell_of_key.find(pack(cells[a].coord + Eigen::Vector3i(dx, dy, dz)));
          if (it == cell_of_key.end() || it->second <= a) continue;  // each pair once
          const Cell& b = cells[it->second];
          if (b.normal.isZero() || !joined(cells[a], b, o, smooth_cos, fold_cos)) continue;
          parent[find_root(parent, it->second)] = find_root(parent, a);
        }
      }
    }
  }

  std::unordered_map<std::uint32_t, Cluster> by_root;
  for (std::uint32_t c = 0; c < cells.size(); ++c) {
    if (cells[c].normal.isZero()) continue;
    Cluster& segment = by_root[find_root(parent, c)];
    segment.insert(segment.end(), cells[c].points.begin(), cells[c].points.end());
  }
  std::vector<Cluster> segments;
  for (auto& [root, segment] : by_root) {
    if (segment.size() < o.min_points) continue;
    std::sort(segment.begin(), segment.end());
    segments.push_back(std::move(segment));
  }
  // Largest first; ties by first index, so the order does not depend on the hash map's.
  std::sort(segments.begin(), segments.end(), [](const Cluster& a, const Cluster& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return segments;
}

}  // namespace viewpose
