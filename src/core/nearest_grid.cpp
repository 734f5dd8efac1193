#include "viewpose/core/nearest_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <vector>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

void NearestGrid::FreeDeleter::operator()(void* p) const { std::free(p); }

NearestGrid::NearestGrid(const KdTree& tree, std::span<const Eigen::Vector3f> points, float cell_m, float margin_m)
    : tree_(&tree), points_(points) {
  if (!(cell_m > 0) || !(margin_m >= 0)) throw Error(fmt::format("nearest grid: cell {} and margin {} must be positive", cell_m, margin_m));
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (!(lo.x() <= hi.x()) || tree.size() == 0) return;  // no finite point: every query finds nothing
  origin_ = lo - Eigen::Vector3f::Constant(margin_m);
  cell_ = cell_m;
  inv_cell_ = 1.0f / cell_m;
  const Eigen::Vector3f size = (hi - lo + Eigen::Vector3f::Constant(2 * margin_m)) * inv_cell_;
  const double cells = (std::floor(size.x()) + 1.0) * (std::floor(size.y()) + 1.0) * (std::floor(size.z()) + 1.0);
  if (cells > 2e8) throw Error(fmt::format("nearest grid: {:.0f} cells of {} m is too many; use larger cells", cells, cell_m));
  nx_ = static_cast<std::uint32_t>(size.x()) + 1;
  ny_ = static_cast<std::uint32_t>(size.y()) + 1;
  nz_ = static_cast<std::uint32_t>(size.z()) + 1;
  // calloc: zero pages on demand. std::atomic<uint32_t> of all-zero bytes is the value 0.
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free && sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));
  void* memory = std::calloc(static_cast<std::size_t>(cells), sizeof(std::atomic<std::uint32_t>));
  if (!memory) throw std::bad_alloc();
  cells_.reset(static_cast<std::atomic<std::uint32_t>*>(memory));
}

void NearestGrid::fill_all() const {
  if (!cells_) return;
  // Block by block (2 x 2 x 2 cells) instead of one tree search per cell: a scanned view of 30 cm
  // took 300 ms, now half that (larger blocks gather too many candidates from a dense scan). With q
  // the block's centre, d the distance from q to its nearest point and h the distance from q to the
  // block's farthest cell centre, every cell's nearest point lies within d + 2h of q (it is at most d + h from the cell, the cell at most h from q). So one nearest
  // and one radius search per block give every candidate, and the cells choose among them exactly as
  // their own searches would (ties aside: then either point is as near).
  constexpr std::uint32_t kBlock = 2;
  const std::uint32_t bx = (nx_ + kBlock - 1) / kBlock, by = (ny_ + kBlock - 1) / kBlock, bz = (nz_ + kBlock - 1) / kBlock;
  const auto blocks = static_cast<std::ptrdiff_t>(bx) * by * bz;
  const auto cell_centre = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return Eigen::Vector3f(origin_ + (Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)) +
                                      Eigen::Vector3f::Constant(0.5f)) * cell_);
  };
#pragma omp parallel
  {
    std::vector<std::uint32_t> candidates;
#pragma omp for schedule(dynamic, 8)
    for (std::ptrdiff_t b = 0; b < blocks; ++b) {
      const auto block = static_cast<std::uint64_t>(b);
      const auto x0 = static_cast<std::uint32_t>(block % bx) * kBlock, y0 = static_cast<std::uint32_t>(block / bx % by) * kBlock,
                 z0 = static_cast<std::uint32_t>(block / (static_cast<std::uint64_t>(bx) * by)) * kBlock;
      const std::uint32_t x1 = std::min(x0 + kBlock, nx_), y1 = std::min(y0 + kBlock, ny_), z1 = std::min(z0 + kBlock, nz_);
      const Eigen::Vector3f first = cell_centre(x0, y0, z0), last = cell_centre(x1 - 1, y1 - 1, z1 - 1);
      const Eigen::Vector3f q = 0.5f * (first + last);
      const float h = 0.5f * (last - first).norm();
      std::uint32_t nearest_to_q = 0;
      float d2 = 0;
      tree_->nearest(q, nearest_to_q, d2);
      // A little more than d + 2h, so that rounding cannot leave a cell's nearest point out.
      tree_->radius_search(q, (std::sqrt(d2) + 2 * h) * 1.0001f + 1e-6f, candidates);
      for (std::uint32_t z = z0; z < z1; ++z)
        for (std::uint32_t y = y0; y < y1; ++y)
          for (std::uint32_t x = x0; x < x1; ++x) {
            const Eigen::Vector3f c = cell_centre(x, y, z);
            std::uint32_t best = nearest_to_q;
            float best_d2 = (points_[best] - c).squaredNorm();
            for (const std::uint32_t k : candidates) {
              const float dk = (points_[k] - c).squaredNorm();
              if (dk < best_d2) best_d2 = dk, best = k;
            }
            cells_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x].store(best + 1, std::memory_order_relaxed);
          }
    }
  }
}

std::uint32_t NearestGrid::fill(std::atomic<std::uint32_t>& cell, std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  const Eigen::Vector3f centre =
      origin_ + (Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)) + Eigen::Vector3f::Constant(0.5f)) * cell_;
  std::uint32_t found = 0;
  float unused = 0;
  tree_->nearest(centre, found, unused);
  cell.store(found + 1, std::memory_order_relaxed);
  return found + 1;
}

std::size_t NearestGrid::filled() const {
  std::size_t n = 0;
  if (!cells_) return n;
  const std::size_t all = static_cast<std::size_t>(nx_) * ny_ * nz_;
  for (std::size_t i = 0; i < all; ++i) n += cells_[i].load(std::memory_order_relaxed) != 0 ? 1 : 0;
  return n;
}

}  // namespace viewpose
