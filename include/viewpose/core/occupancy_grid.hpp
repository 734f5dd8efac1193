#pragma once
// Which cells of a regular grid hold points, and which touch one that does: one byte per cell over
// the points' box, widened by a cell. "Is there a point within about a cell of here?" is then one
// memory read where a tree search takes a microsecond: the overlap of two point sets at a guessed
// pose, asked for a thousand guesses per scene region (pose/coarse_fit), is made of such questions.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace viewpose {

class OccupancyGrid {
 public:
  OccupancyGrid() = default;
  /// Cells of side `cell_m` (widened so that no side holds more than kMaxCellsPerSide cells: a grid
  /// over a room-sized cloud stays small). Non-finite points are left out.
  OccupancyGrid(std::span<const Eigen::Vector3f> points, float cell_m);

  /// 2: a point lies in p's cell; 1: none there, but one in a cell touching it (of the 26); 0: none
  /// within a cell, p outside the grid, or p not finite.
  int level(const Eigen::Vector3f& p) const {
    const Eigen::Vector3f c = (p - origin_) * inv_cell_;
    // Compared as floats before the cast: a point far outside would overflow it. NaN fails too.
    if (!(c.x() >= 0 && c.y() >= 0 && c.z() >= 0 && c.x() < extent_.x() && c.y() < extent_.y() && c.z() < extent_.z())) return 0;
    const auto x = static_cast<std::uint32_t>(c.x()), y = static_cast<std::uint32_t>(c.y()), z = static_cast<std::uint32_t>(c.z());
    return cells_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x];
  }
  float cell_m() const { return cell_; }
  bool empty() const { return cells_.empty(); }

  static constexpr std::uint32_t kMaxCellsPerSide = 256;

 private:
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  Eigen::Vector3f extent_ = Eigen::Vector3f::Zero();  // (nx_, ny_, nz_) as floats
  float cell_ = 1, inv_cell_ = 1;
  std::uint32_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<std::uint8_t> cells_;
};

}  // namespace viewpose
