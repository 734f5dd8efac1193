#pragma once
// A private header of the recognizer (src/recognize): how a region's stages spread their work over
// threads (the frame's clusters themselves are OpenMP tasks of recognizer.cpp).
#include <cstddef>

#include <omp.h>

#include "viewpose/core/threads.hpp"

namespace viewpose::detail {

// body(i) for every i in [0, n), on several threads when `parallel`. Within a parallel region (a
// frame's clusters searched side by side, RunOptions::parallel_clusters) as tasks of `grain`
// indices, which a thread with no cluster left takes up: a frame's largest cluster is often most
// of its work, and its stages no longer run on one thread while the other waits. (A thread that
// waits for its own tasks runs only those.) Outside one, a parallel loop of its own. Each index
// once, its result kept by index: the same whichever thread runs it.
template <class Body>
void for_each_index(std::ptrdiff_t n, bool parallel, std::ptrdiff_t grain, const Body& body) {
  if (!parallel || n <= 1) {
    for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
    return;
  }
  FirstException failed;
  if (omp_in_parallel()) {
    // (Unsigned: clang compares the loop's bound with its own unsigned count of iterations.)
    const auto count = static_cast<std::size_t>(n), chunk = static_cast<std::size_t>(grain);
#pragma omp taskloop grainsize(chunk) shared(body, failed)
    for (std::size_t i = 0; i < count; ++i) failed.run(static_cast<std::ptrdiff_t>(i), [&] { body(static_cast<std::ptrdiff_t>(i)); });
  } else {
#pragma omp parallel for schedule(dynamic, grain)
    for (std::ptrdiff_t i = 0; i < n; ++i) failed.run(i, [&] { body(i); });
  }
  failed.rethrow();
}

}  // namespace viewpose::detail
