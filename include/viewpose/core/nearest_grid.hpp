#pragma once
// Nearest-neighbour look-up in constant time for a fixed point set queried many times (a model
// surface under ICP): a dense grid over the points' bounding box, widened by a margin, in which
// each cell holds the point nearest its centre. A query returns its cell's point, at most a cell
// diagonal farther than the nearest point (on average a tenth of that). Queries outside the grid
// (farther than the margin from every point) find nothing.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace viewpose {

class NearestGrid {
 public:
  /// Indexes `points` (non-finite ones are left out), which must outlive the grid.
  NearestGrid(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m);

  /// The point held by the query's cell and its squared distance to the query; false outside the grid.
  bool nearest(const Eigen::Vector3f& query, std::uint32_t& index, float& squared_distance) const {
    const Eigen::Vector3f c = (query - origin_) * inv_cell_;
    if (!(c.x() >= 0 && c.y() >= 0 && c.z() >= 0)) return false;  // NaN fails too
    const auto x = static_cast<std::uint32_t>(c.x()), y = static_cast<std::uint32_t>(c.y()), z = static_cast<std::uint32_t>(c.z());
    if (x >= nx_ || y >= ny_ || z >= nz_) return false;
    index = cells_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x];
    if (index == kEmpty) return false;
    squared_distance = (points_[index] - query).squaredNorm();
    return true;
  }
  std::size_t bytes() const { return cells_.size() * sizeof(std::uint32_t); }

 private:
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  std::span<const Eigen::Vector3f> points_;
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  float inv_cell_ = 1;
  std::uint32_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<std::uint32_t> cells_;
};

}  // namespace viewpose
