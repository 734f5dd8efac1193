#include "viewpose/core/radix_sort.hpp"

#include <algorithm>
#include <array>

#include "viewpose/core/threads.hpp"

namespace viewpose {

namespace {

constexpr int kBits = 11;
constexpr std::uint64_t kMask = (1u << kBits) - 1;
constexpr std::size_t kDigits = std::size_t{1} << kBits;
// Items per chunk of a parallel pass: each chunk counts its digits, then scatters its items after
// those of the chunks before it, so that a thread the system has paused holds up the others by one
// chunk at most.
constexpr std::size_t kChunk = 16384;

std::size_t digit(const KeyedIndex& item, int shift) { return static_cast<std::size_t>((item.first >> shift) & kMask); }

// One pass, on one thread.
void pass(const std::vector<KeyedIndex>& items, std::vector<KeyedIndex>& buffer, int shift) {
  std::array<std::size_t, kDigits + 1> offset{};
  for (const KeyedIndex& item : items) ++offset[digit(item, shift) + 1];
  for (std::size_t d = 1; d < offset.size(); ++d) offset[d] += offset[d - 1];
  for (const KeyedIndex& item : items) buffer[offset[digit(item, shift)]++] = item;
}

// One pass on every thread: the same result, as each chunk's items of a digit go after the
// earlier chunks' items of that digit, in their order.
void parallel_pass(const std::vector<KeyedIndex>& items, std::vector<KeyedIndex>& buffer, int shift,
                   std::vector<std::array<std::size_t, kDigits>>& counts) {
  const std::size_t n = items.size(), chunks = counts.size();
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 1)
    for (std::size_t c = 0; c < chunks; ++c) {
      std::array<std::size_t, kDigits>& count = counts[c];
      count.fill(0);
      for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) ++count[digit(items[i], shift)];
    }
#pragma omp single
    {
      std::size_t next = 0;
      for (std::size_t d = 0; d < kDigits; ++d) {
        for (std::size_t c = 0; c < chunks; ++c) {
          const std::size_t here = counts[c][d];
          counts[c][d] = next;
          next += here;
        }
      }
    }
#pragma omp for schedule(dynamic, 1)
    for (std::size_t c = 0; c < chunks; ++c) {
      std::array<std::size_t, kDigits>& offset = counts[c];
      for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) buffer[offset[digit(items[i], shift)]++] = items[i];
    }
  }
}

}  // namespace

void radix_sort(std::vector<KeyedIndex>& items) { radix_sort(items, on_every_thread(items.size())); }

void radix_sort(std::vector<KeyedIndex>& items, bool spread) {
  if (items.size() < 64) {
    std::sort(items.begin(), items.end());  // small: the comparison sort wins
    return;
  }
  std::uint64_t all_and = ~std::uint64_t{0}, all_or = 0;
  for (const KeyedIndex& item : items) {
    all_and &= item.first;
    all_or |= item.first;
  }
  const std::uint64_t varying = all_and ^ all_or;  // bits that are not the same in every key
  const bool parallel = spread && items.size() >= kChunk;  // (fewer: one chunk, no parallel pass)
  std::vector<std::array<std::size_t, kDigits>> counts(parallel ? (items.size() + kChunk - 1) / kChunk : 0);
  std::vector<KeyedIndex> buffer(items.size());
  for (int shift = 0; shift < 64; shift += kBits) {
    if (((varying >> shift) & kMask) == 0) continue;
    if (parallel) parallel_pass(items, buffer, shift, counts);
    else pass(items, buffer, shift);
    items.swap(buffer);
  }
}

}  // namespace viewpose
