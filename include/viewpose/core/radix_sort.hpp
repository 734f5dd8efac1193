#pragma once
// Sorting (key, index) pairs by key, for the grids that bin points into cells (voxel grid,
// clusters, normals): a least-significant-digit radix sort, 11 bits a pass, that skips the digits
// all keys share. Cells of one frame differ in few bits (bin_points sorts dense keys over the
// cells' box), so it makes two or three passes where a comparison sort makes log2(n). Stable:
// pairs with equal keys keep their order, so with indices pushed in increasing order the result
// equals std::sort's.
#include <cstdint>
#include <utility>
#include <vector>

namespace viewpose {

using KeyedIndex = std::pair<std::uint64_t, std::uint32_t>;

/// Each pass runs on every thread where the items are a frame's worth (core/threads.hpp,
/// on_every_thread: a frame's points binned into cells), with the same result.
void radix_sort(std::vector<KeyedIndex>& items);
/// The same, on every thread (`spread`) or not as the caller decided (bin_points: on the points it was given).
void radix_sort(std::vector<KeyedIndex>& items, bool spread);

}  // namespace viewpose
