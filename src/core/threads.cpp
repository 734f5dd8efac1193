#include "viewpose/core/threads.hpp"

#include <algorithm>
#include <cstdlib>

#include <omp.h>

namespace viewpose {

void set_thread_count(int threads) { omp_set_num_threads(std::max(1, threads)); }

int thread_count() { return omp_get_max_threads(); }

bool on_every_thread(std::size_t items) {
  return items >= kFrameSizedFrom && omp_get_max_threads() > 1 && !omp_in_parallel();
}

std::string openmp_wait() {
  std::string said;
  for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"})
    if (const char* value = std::getenv(name)) said += (said.empty() ? "" : ", ") + std::string(name) + "=" + value;
  return said.empty() ? "libgomp's default (spin 300000)" : said;
}

void FirstException::keep(std::ptrdiff_t index, std::exception_ptr e) noexcept {
  const std::lock_guard lock(mutex_);
  if (index < failed_index_.load(std::memory_order_relaxed)) {
    first_ = std::move(e);
    failed_index_.store(index, std::memory_order_relaxed);
  }
}

void FirstException::rethrow() {
  const std::lock_guard lock(mutex_);
  if (first_) std::rethrow_exception(first_);
}

}  // namespace viewpose
