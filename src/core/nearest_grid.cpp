#include "viewpose/core/nearest_grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

void NearestGrid::FreeDeleter::operator()(void* p) const { std::free(p); }

NearestGrid::Extent NearestGrid::extent(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m) {
  if (!(cell_m > 0) || !(margin_m >= 0)) throw Error(fmt::format("nearest grid: cell {} and margin {} must be positive", cell_m, margin_m));
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Extent e;
  if (!(lo.x() <= hi.x())) return e;  // no finite point: every query finds nothing
  e.origin = lo - Eigen::Vector3f::Constant(margin_m);
  const Eigen::Vector3f size = (hi - lo + Eigen::Vector3f::Constant(2 * margin_m)) * (1.0f / cell_m);
  const double cells = (std::floor(size.x()) + 1.0) * (std::floor(size.y()) + 1.0) * (std::floor(size.z()) + 1.0);
  if (cells > kMaxCells) {
    e.too_many = cells;
    return e;
  }
  e.nx = static_cast<std::uint32_t>(size.x()) + 1;
  e.ny = static_cast<std::uint32_t>(size.y()) + 1;
  e.nz = static_cast<std::uint32_t>(size.z()) + 1;
  return e;
}

std::size_t NearestGrid::cell_count(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m) {
  const Extent e = extent(points, cell_m, margin_m);
  return e.too_many > 0 ? std::numeric_limits<std::size_t>::max() : e.cells();
}

NearestGrid::NearestGrid(const KdTree& tree, std::span<const Eigen::Vector3f> points, float cell_m, float margin_m)
    : tree_(&tree), points_(points) {
  const Extent e = extent(points, cell_m, margin_m);
  if (e.too_many > 0) throw Error(fmt::format("nearest grid: {:.0f} cells of {} m is too many; use larger cells", e.too_many, cell_m));
  cell_ = cell_m;
  margin_ = margin_m;
  if (e.cells() == 0 || tree.size() == 0) return;  // every query finds nothing
  origin_ = e.origin;
  inv_cell_ = 1.0f / cell_m;
  nx_ = e.nx;
  ny_ = e.ny;
  nz_ = e.nz;
  // calloc: zero pages on demand. std::atomic<uint32_t> of all-zero bytes is the value 0.
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free && sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));
  void* memory = std::calloc(e.cells(), sizeof(std::atomic<std::uint32_t>));
  if (!memory) throw std::bad_alloc();
  cells_.reset(static_cast<std::atomic<std::uint32_t>*>(memory));
}

NearestGrid::NearestGrid(const KdTree& tree, std::span<const Eigen::Vector3f> points, float cell_m, float margin_m,
                         std::span<const std::uint32_t> cells)
    : NearestGrid(tree, points, cell_m, margin_m) {
  const std::size_t n = static_cast<std::size_t>(nx_) * ny_ * nz_;
  if (cells.size() != n) throw Error(fmt::format("nearest grid: {} cells given for a grid of {}", cells.size(), n));
  if (!fits(points, cell_m, margin_m, cells)) throw Error(fmt::format("nearest grid: a cell holds a point past the {} given", points.size()));
  if (n > 0) std::memcpy(static_cast<void*>(cells_.get()), cells.data(), n * sizeof(std::uint32_t));
}

bool NearestGrid::fits(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m, std::span<const std::uint32_t> cells) {
  if (cells.size() != cell_count(points, cell_m, margin_m)) return false;
  std::uint32_t largest = 0;
  for (std::uint32_t c : cells) largest = std::max(largest, c);
  return largest <= points.size();
}

std::vector<std::uint32_t> filled_nearest_cells(std::span<const Eigen::Vector3f> points, float cell_m, float margin_m) {
  const KdTree tree(points);
  const NearestGrid grid(tree, points, cell_m, margin_m);
  grid.fill_all();
  return grid.cells();
}

void NearestGrid::fill_all() const {
  if (!cells_) return;
  const auto slices = static_cast<std::ptrdiff_t>(nz_);
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t z = 0; z < slices; ++z) {
    for (std::uint32_t y = 0; y < ny_; ++y)
      for (std::uint32_t x = 0; x < nx_; ++x) {
        std::atomic<std::uint32_t>& cell = cells_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x];
        if (cell.load(std::memory_order_relaxed) == 0) fill(cell, x, y, static_cast<std::uint32_t>(z));
      }
  }
}

std::uint32_t NearestGrid::fill(std::atomic<std::uint32_t>& cell, std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  const Eigen::Vector3f centre =
      origin_ + (Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)) + Eigen::Vector3f::Constant(0.5f)) * cell_;
  std::uint32_t found = 0;
  float unused = 0;
  // A filled neighbour's point bounds the distance to the nearest: the search skips every branch
  // of the tree farther than that. fill_all's rows fill in order, each cell bounded by the one
  // before (the YCB-V database's seven grids 500 -> 330 ms); cells filled as ICP asks for them may
  // have filled neighbours on any side, so the nearest of the six is taken. Widened a little, so
  // that no point as near as the nearest is skipped: the point found is the unbounded search's.
  const std::ptrdiff_t row = nx_, slice = static_cast<std::ptrdiff_t>(nx_) * ny_;
  const std::array<std::pair<bool, std::ptrdiff_t>, 6> sides = {
      {{x > 0, -1}, {x + 1 < nx_, 1}, {y > 0, -row}, {y + 1 < ny_, row}, {z > 0, -slice}, {z + 1 < nz_, slice}}};
  float bound = std::numeric_limits<float>::infinity();
  for (const auto& [inside, offset] : sides) {
    if (!inside) continue;
    const std::uint32_t held = (&cell + offset)->load(std::memory_order_relaxed);
    if (held != 0) bound = std::min(bound, (points_[held - 1] - centre).norm() * 1.001f + 1e-6f);
  }
  if (!(bound < std::numeric_limits<float>::infinity()) || !tree_->nearest_within(centre, bound * bound, found, unused))
    tree_->nearest(centre, found, unused);
  cell.store(found + 1, std::memory_order_relaxed);
  return found + 1;
}

std::vector<std::uint32_t> NearestGrid::cells() const {
  std::vector<std::uint32_t> out(static_cast<std::size_t>(nx_) * ny_ * nz_);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = cells_[i].load(std::memory_order_relaxed);
  return out;
}

std::size_t NearestGrid::filled() const {
  std::size_t n = 0;
  if (!cells_) return n;
  const std::size_t all = static_cast<std::size_t>(nx_) * ny_ * nz_;
  for (std::size_t i = 0; i < all; ++i) n += cells_[i].load(std::memory_order_relaxed) != 0 ? 1 : 0;
  return n;
}

}  // namespace viewpose
