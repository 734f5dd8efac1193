#include "viewpose/core/radix_sort.hpp"

#include <algorithm>
#include <array>

namespace viewpose {

void radix_sort(std::vector<KeyedIndex>& items) {
  if (items.size() < 64) {
    std::sort(items.begin(), items.end());  // small: the comparison sort wins
    return;
  }
  constexpr int kBits = 11;
  constexpr std::uint64_t kMask = (1u << kBits) - 1;
  std::uint64_t all_and = ~std::uint64_t{0}, all_or = 0;
  for (const KeyedIndex& item : items) {
    all_and &= item.first;
    all_or |= item.first;
  }
  const std::uint64_t varying = all_and ^ all_or;  // bits that are not the same in every key
  std::vector<KeyedIndex> buffer(items.size());
  std::array<std::size_t, (1u << kBits) + 1> offset{};
  for (int shift = 0; shift < 64; shift += kBits) {
    if (((varying >> shift) & kMask) == 0) continue;
    offset.fill(0);
    for (const KeyedIndex& item : items) ++offset[((item.first >> shift) & kMask) + 1];
    for (std::size_t d = 1; d < offset.size(); ++d) offset[d] += offset[d - 1];
    for (const KeyedIndex& item : items) buffer[offset[(item.first >> shift) & kMask]++] = item;
    items.swap(buffer);
  }
}

}  // namespace viewpose
