#pragma once
// How many threads the parallel stages (OpenMP underneath) use, and how their idle threads wait.
// Results depend on neither.
#include <atomic>
#include <exception>
#include <mutex>
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

/// The first exception thrown in the iterations or tasks of a parallel region, kept to be thrown
/// again once the region is over: an exception may not leave an OpenMP region or task (the process
/// would end in std::terminate, with nothing a user could act on, rather than a one-line error).
///
///     FirstException failed;
///     #pragma omp parallel for
///     for (int i = 0; i < n; ++i) failed.run([&] { work(i); });
///     failed.rethrow();
class FirstException {
 public:
  /// Runs `f`, keeping what it throws if nothing was kept before. Once something has been, runs
  /// nothing more: the region's results will not be used.
  template <class F>
  void run(F&& f) noexcept {
    if (failed_.load(std::memory_order_relaxed)) return;
    try {
      f();
    } catch (...) {
      keep(std::current_exception());
    }
  }
  bool failed() const noexcept { return failed_.load(std::memory_order_relaxed); }
  /// Throws the exception kept, if any. Called after the region (its threads joined).
  void rethrow();

 private:
  void keep(std::exception_ptr e) noexcept;
  std::mutex mutex_;
  std::exception_ptr first_;
  std::atomic<bool> failed_{false};
};

}  // namespace viewpose
