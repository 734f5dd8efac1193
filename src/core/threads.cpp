#include "viewpose/core/threads.hpp"

#include <algorithm>

#include <omp.h>

namespace viewpose {

void set_thread_count(int threads) { omp_set_num_threads(std::max(1, threads)); }

int thread_count() { return omp_get_max_threads(); }

}  // namespace viewpose
