#pragma once
// How many threads the parallel stages (OpenMP underneath) use, and how their idle threads wait.
// Results depend on neither.
#include <atomic>
#include <cstddef>
#include <exception>
#include <limits>
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
/// A frame's worth of points: from this many, work over them is spread over every thread (a frame's
/// points binned into cells, their sort and their voxels' means); fewer, inside a parallel region
/// (a frame's clusters searched side by side), or with one thread, the calling thread does it
/// alone. The same results either way.
inline constexpr std::size_t kFrameSizedFrom = 32768;
/// Whether work over `items` items is spread over every thread (kFrameSizedFrom). A stage decides
/// once, on its input's count, and hands the decision to the steps within it (bin_points to its
/// sort): a frame with many pixels without depth keeps fewer points than it was given.
bool on_every_thread(std::size_t items);
/// How OpenMP's idle threads wait in this process, as its environment set it: "GOMP_SPINCOUNT=1000",
/// "OMP_WAIT_POLICY=passive", or "libgomp's default (spin 300000)".
std::string openmp_wait();

/// The exception thrown by the lowest-numbered iteration or task of a parallel region that threw,
/// kept to be thrown again once the region is over: an exception may not leave an OpenMP region or
/// task (the process would end in std::terminate, with nothing a user could act on, rather than a
/// one-line error). The lowest index, not the first in time: the same error whatever the threads.
///
///     FirstException failed;
///     #pragma omp parallel for
///     for (int i = 0; i < n; ++i) failed.run(i, [&] { work(i); });
///     failed.rethrow();
class FirstException {
 public:
  /// Runs `f` as the work of `index`, keeping what it throws if no lower index has thrown. Once an
  /// index has thrown, higher ones run nothing more (the region's results will not be used); lower
  /// ones still run, so that the lowest that throws is the one kept.
  template <class F>
  void run(std::ptrdiff_t index, F&& f) noexcept {
    if (index > failed_index_.load(std::memory_order_relaxed)) return;
    try {
      f();
    } catch (...) {
      keep(index, std::current_exception());
    }
  }
  bool failed() const noexcept { return failed_index_.load(std::memory_order_relaxed) != kNone; }
  /// Throws the exception kept, if any. Called after the region (its threads joined).
  void rethrow();

 private:
  static constexpr std::ptrdiff_t kNone = std::numeric_limits<std::ptrdiff_t>::max();
  void keep(std::ptrdiff_t index, std::exception_ptr e) noexcept;
  std::mutex mutex_;
  std::exception_ptr first_;
  std::atomic<std::ptrdiff_t> failed_index_{kNone};
};

}  // namespace viewpose
