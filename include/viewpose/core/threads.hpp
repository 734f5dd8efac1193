#pragma once
// How many threads the parallel stages (OpenMP underneath) use, and how their idle threads wait.
// Results depend on neither.
#include <string>

namespace viewpose {

/// The GOMP_SPINCOUNT the `viewpose` command sets for itself when the user has set neither it nor
/// OMP_WAIT_POLICY (libgomp's default, 300,000 turns, makes a frame 2-4 times slower when other
/// programs keep the cores busy; docs/BENCHMARK.md). A program linking the library sets it in its
/// environment before it starts: libgomp reads it once, before main.
inline constexpr const char* kSpinCountUnderLoad = "1000";

/// Threads for every later parallel region of this process (at least 1).
void set_thread_count(int threads);
/// The threads a parallel region would use now.
int thread_count();
/// How OpenMP's idle threads wait in this process, as its environment set it: "GOMP_SPINCOUNT=1000",
/// "OMP_WAIT_POLICY=passive", or "libgomp's default (spin 300000)".
std::string openmp_wait();

}  // namespace viewpose
