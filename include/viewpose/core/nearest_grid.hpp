#pragma once
// Nearest-neighbour look-up in constant time for a fixed point set queried many times (a model
// surface under ICP): a grid over the points' bounding box, widened by a margin, whose cells each
// hold the point nearest the cell's centre. A query returns its cell's point, at most a cell
// diagonal farther than the nearest point (on average a tenth of that). Queries outside the grid
// (farther than the margin from every point) find nothing.
//
// Cells are filled on first use, by one exact search of the k-d tree: making the grid costs
// nothing, and ICP only ever asks about the cells near the model's surface it is pulled onto. The
// cells live in zero-filled memory the system hands out page by page, so untouched parts of the
// grid take no memory either. Queries may run on several threads at once: two threads filling the
// same cell write the same value.
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/kdtree.hpp"

namespace viewpose {

class NearestGrid {
 public:
  /// Indexes the points `tree` was built on (non-finite ones are left out); both must outlive the grid.
  NearestGrid(const KdTree& tree, std::span<const Eigen::Vector3f> points, float cell_m, float margin_m);
  /// The same grid with its cells as cells() gave them for the same points, cell and margin (a view
  /// database stores them filled, so that a process run per frame makes no search). Throws unless
  /// they fit: cell_count() of them, each 0 or a point's index + 1.
  NearestGrid(const KdTree& tree, std::span<const Eigen::Vector3f> points, float cell_m, float margin_m,
              std::span<const std::uint32_t> cells);
  /// The cells of a grid over these points: what cells() returns and the constructor above takes
  /// (the largest size_t where there would be more than the constructors allow).
  static std::size_t cell_count(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m);
  static constexpr double kMaxCells = 2e8;  ///< the constructors refuse grids of more (800 MB)
  /// Whether `cells` are a grid of these points, cell and margin, as the constructor above takes
  /// them: cell_count() of them, each 0 or a point's index + 1.
  static bool fits(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m, std::span<const std::uint32_t> cells);

  /// The point held by the query's cell and its squared distance to the query; false outside the grid.
  bool nearest(const Eigen::Vector3f& query, std::uint32_t& index, float& squared_distance) const {
    if (!held(query, index)) return false;
    squared_distance = (points_[index] - query).squaredNorm();
    return true;
  }
  /// The index of the point held by the query's cell, without reading the point; false outside the
  /// grid. (For callers that keep their own copy of the points beside other data.)
  bool held(const Eigen::Vector3f& query, std::uint32_t& index) const {
    std::uint32_t x = 0, y = 0, z = 0;
    if (!cell_of(query, x, y, z)) return false;
    std::atomic<std::uint32_t>& cell = cells_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x];
    std::uint32_t stored = cell.load(std::memory_order_relaxed);
    if (stored == 0) stored = fill(cell, x, y, z);
    index = stored - 1;
    return true;
  }
  /// Asks the processor to fetch the query's cell into its cache, without waiting for it (nothing
  /// outside the grid). A caller with many queries prefetches them all, then asks held() of each:
  /// the cells lie at random places in megabytes of grid, and a look-up that waits on each miss in
  /// turn spent most of its time waiting (ICP's correspondences on real frames).
  void prefetch(const Eigen::Vector3f& query) const {
    std::size_t offset = 0;
    if (cell_offset(query, offset)) __builtin_prefetch(&cells_[offset]);
  }
  /// The sizes it was made with: a query's cell point is at most a cell diagonal (sqrt(3) cell_m)
  /// farther than the nearest point, and a query outside the grid lies farther than margin_m from
  /// every point.
  float cell_m() const { return cell_; }
  float margin_m() const { return margin_; }
  /// Cells filled so far.
  std::size_t filled() const;
  /// Every cell, x fastest, then y, then z: 0 where not filled yet, else the held point's index + 1.
  std::vector<std::uint32_t> cells() const;
  /// Fills every cell now (on all threads), with what queries would fill them with: the first
  /// queries then cost no search. Tens of milliseconds for an object of 30 cm.
  void fill_all() const;

 private:
  // The query's cell; false outside the grid (or where the grid has no cells).
  bool cell_of(const Eigen::Vector3f& query, std::uint32_t& x, std::uint32_t& y, std::uint32_t& z) const {
    if (!cells_) return false;
    const Eigen::Vector3f c = (query - origin_) * inv_cell_;
    // Compared as floats before the cast: a point far outside (or infinite) would overflow it.
    // NaN fails too.
    if (!(c.x() >= 0 && c.y() >= 0 && c.z() >= 0 && c.x() < static_cast<float>(nx_) && c.y() < static_cast<float>(ny_) &&
          c.z() < static_cast<float>(nz_))) {
      return false;
    }
    x = static_cast<std::uint32_t>(c.x()), y = static_cast<std::uint32_t>(c.y()), z = static_cast<std::uint32_t>(c.z());
    return x < nx_ && y < ny_ && z < nz_;
  }
  bool cell_offset(const Eigen::Vector3f& query, std::size_t& offset) const {
    std::uint32_t x = 0, y = 0, z = 0;
    if (!cell_of(query, x, y, z)) return false;
    offset = (static_cast<std::size_t>(z) * ny_ + y) * nx_ + x;
    return true;
  }
  // Searches the tree for the point nearest the cell's centre and stores it (index + 1).
  std::uint32_t fill(std::atomic<std::uint32_t>& cell, std::uint32_t x, std::uint32_t y, std::uint32_t z) const;
  // The grid's corner and size in cells (nothing where no point is finite), as the constructors make it.
  struct Extent {
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    std::uint32_t nx = 0, ny = 0, nz = 0;
    double too_many = 0;  // the cells there would be, where more than kMaxCells (then no size)
    std::size_t cells() const { return static_cast<std::size_t>(nx) * ny * nz; }
  };
  static Extent extent(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m);
  struct FreeDeleter {
    void operator()(void* p) const;
  };
  const KdTree* tree_;
  std::span<const Eigen::Vector3f> points_;
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  float cell_ = 1, inv_cell_ = 1, margin_ = 0;
  std::uint32_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::unique_ptr<std::atomic<std::uint32_t>[], FreeDeleter> cells_;  // 0: not filled yet; else index + 1
};

/// The cells of a grid over `points` with every cell filled (NearestGrid::cells() after fill_all()),
/// on all threads: what a view database stores for each object.
std::vector<std::uint32_t> filled_nearest_cells(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m);

}  // namespace viewpose
