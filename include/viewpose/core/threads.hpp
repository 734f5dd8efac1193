#pragma once
// How many threads the parallel stages (OpenMP underneath) use. Results do not depend on it.
namespace viewpose {

/// Threads for every later parallel region of this process (at least 1).
void set_thread_count(int threads);
/// The threads a parallel region would use now.
int thread_count();

}  // namespace viewpose
