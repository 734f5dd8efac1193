#pragma once
// Points binned into cubic cells and sorted by cell: the layout the voxel grid, the Euclidean
// clusters and the normals share. A cell's key packs its integer coordinates, 21 bits each (about
// +-3 km at 3 mm cells), x highest, so that keys sort by x, then y, then z: the cells of one
// column (x, y) are consecutive, and a range of keys is a range of z.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/radix_sort.hpp"

namespace viewpose {

struct CellGrid {
  static constexpr std::int64_t kOffset = std::int64_t{1} << 20;  // added to each coordinate
  static constexpr std::int64_t kMask = (std::int64_t{1} << 21) - 1;

  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) << 42) | (static_cast<std::uint64_t>(y) << 21) | static_cast<std::uint64_t>(z);
  }
  static std::array<std::int64_t, 3> coordinates(std::uint64_t key) {
    return {static_cast<std::int64_t>(key >> 42), static_cast<std::int64_t>((key >> 21) & static_cast<std::uint64_t>(kMask)),
            static_cast<std::int64_t>(key & static_cast<std::uint64_t>(kMask))};
  }

  /// What a cell's key adds to reach its neighbour's at (dx, dy, dz), modulo 2^64: a negative
  /// step borrows from the field above, which the sum gives back. Valid where no coordinate leaves
  /// its field (bin_points's margin keeps every cell's neighbours within it).
  static std::uint64_t step(std::int64_t dx, std::int64_t dy, std::int64_t dz) {
    return key(kOffset + dx, kOffset + dy, kOffset + dz) - key(kOffset, kOffset, kOffset);
  }

  /// The smallest distance, in cell sides squared, between any points of two cells whose
  /// coordinates differ by (dx, dy, dz): neighbouring cells touch (0).
  static std::int64_t squared_gap(std::int64_t dx, std::int64_t dy, std::int64_t dz) {
    const auto g = [](std::int64_t d) { return d > 1 ? d - 1 : d < -1 ? -d - 1 : 0; };
    return g(dx) * g(dx) + g(dy) * g(dy) + g(dz) * g(dz);
  }

  std::vector<KeyedIndex> items;     ///< (cell key, the point's position in the input), sorted by key
  std::vector<std::uint64_t> cells;  ///< the occupied cells' keys, ascending
  std::vector<std::size_t> first;    ///< cells.size() + 1 entries: cell c's items are [first[c], first[c + 1])
};

/// Bins the finite points among points[indices[k]] (every point when `indices` is empty) into
/// cells of side `cell_m`. Points whose cell lies within `margin_cells` of the coordinate range's
/// ends are left out, so that neighbours up to that many cells away have valid keys. A frame's
/// points are binned on every thread (core/threads.hpp, on_every_thread), with the same result.
CellGrid bin_points(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, float cell_m,
                    int margin_cells);

}  // namespace viewpose
