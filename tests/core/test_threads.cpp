// FirstException: what an iteration or task of a parallel region throws reaches the caller after
// the region, as an exception, instead of ending the process in std::terminate; always the lowest
// index's, whatever the threads. on_every_thread: a frame's worth of work outside a parallel region.
#include <gtest/gtest.h>
#include <omp.h>

#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/core/threads.hpp"

namespace viewpose {
namespace {

// The message of what `failed` throws again ("" when nothing).
std::string rethrown(FirstException& failed) {
  try {
    failed.rethrow();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(FirstException, AnIterationsErrorIsThrownAfterTheParallelLoop) {
  const int threads = thread_count();
  set_thread_count(2);
  FirstException failed;
  std::vector<int> done(1000, 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < 1000; ++i) {
    failed.run(i, [&] {
      if (i == 37) throw Error("iteration 37 failed");
      done[static_cast<std::size_t>(i)] = 1;
    });
  }
  set_thread_count(threads);
  EXPECT_TRUE(failed.failed());
  // Every index below the one that threw still ran.
  for (int i = 0; i < 37; ++i) EXPECT_EQ(done[static_cast<std::size_t>(i)], 1) << i;
  EXPECT_EQ(rethrown(failed), "iteration 37 failed");
}

TEST(FirstException, TheLowestIndexThatThrowsIsKeptWhateverTheThreadsOrOrder) {
  // Every tenth index from 300 on throws; the threads meet them in any order, the high ones
  // possibly first. The one kept is always index 300's.
  for (const int threads : {1, 2, 4}) {
    for (int repeat = 0; repeat < 5; ++repeat) {
      const int before = thread_count();
      set_thread_count(threads);
      FirstException failed;
#pragma omp parallel for schedule(dynamic, 1)
      for (int i = 999; i >= 0; --i) {
        failed.run(i, [&] {
          if (i >= 300 && i % 10 == 0) throw Error("index " + std::to_string(i));
        });
      }
      set_thread_count(before);
      EXPECT_EQ(rethrown(failed), "index 300") << threads << " threads";
    }
  }
  // Called one after the other: a higher index after a lower one runs nothing; a lower one replaces it.
  FirstException failed;
  int ran = 0;
  failed.run(5, [] { throw std::runtime_error("five"); });
  failed.run(7, [&] { ++ran; });
  failed.run(9, [] { throw std::runtime_error("nine"); });
  EXPECT_EQ(ran, 0);
  failed.run(2, [] { throw std::runtime_error("two"); });
  EXPECT_EQ(rethrown(failed), "two");
}

TEST(FirstException, TasksThatThrowReachTheCaller) {
  const int threads = thread_count();
  set_thread_count(2);
  FirstException failed;
#pragma omp parallel
#pragma omp single
  for (int t = 0; t < 8; ++t) {
#pragma omp task firstprivate(t) shared(failed)
    failed.run(t, [&] {
      if (t == 5) throw std::bad_alloc();
    });
  }
  set_thread_count(threads);
  EXPECT_THROW(failed.rethrow(), std::bad_alloc);
}

TEST(FirstException, AThreadsSetUpFailingSkipsEveryIteration) {
  // As the vote loop and the shadow pass allocate each thread's buffers: index -1, below every
  // iteration, so that no thread runs an iteration without them.
  FirstException failed;
  int ran = 0;
  failed.run(-1, [] { throw std::bad_alloc(); });
  for (int i = 0; i < 10; ++i) failed.run(i, [&] { ++ran; });
  EXPECT_EQ(ran, 0);
  EXPECT_THROW(failed.rethrow(), std::bad_alloc);
}

TEST(FirstException, NothingThrownRethrowsNothing) {
  FirstException failed;
  int sum = 0;
  for (int i = 1; i <= 4; ++i) failed.run(i, [&] { sum += i; });
  EXPECT_EQ(sum, 10);
  EXPECT_FALSE(failed.failed());
  EXPECT_NO_THROW(failed.rethrow());
}

// A frame's points are spread over the threads; a cluster's, or any work inside a parallel region
// (a frame's clusters searched side by side), stay on the calling thread.
TEST(OnEveryThread, AFramesWorthOutsideAParallelRegionOnly) {
  const int threads = thread_count();
  set_thread_count(2);
  const bool at_threshold = on_every_thread(kFrameSizedFrom), below = on_every_thread(kFrameSizedFrom - 1),
             vga = on_every_thread(640 * 480), none = on_every_thread(0);
  // (Asked from inside a team of two; a team the runtime cut to one thread is no parallel region.)
  int threads_in_a_team_of_two = 0, spread = 0;
#pragma omp parallel num_threads(2) reduction(+ : threads_in_a_team_of_two, spread)
  if (omp_get_num_threads() == 2) {
    ++threads_in_a_team_of_two;
    spread += on_every_thread(640 * 480) ? 1 : 0;
  }
  // One thread: nothing to spread over.
  set_thread_count(1);
  const bool one_thread = on_every_thread(640 * 480);
  set_thread_count(threads);
  EXPECT_TRUE(at_threshold);
  EXPECT_TRUE(vga);
  EXPECT_FALSE(below);
  EXPECT_FALSE(none);
  EXPECT_FALSE(one_thread);
  EXPECT_EQ(spread, 0);
  if (threads_in_a_team_of_two == 0) GTEST_SKIP() << "the OpenMP runtime gave no team of two threads";
}

}  // namespace
}  // namespace viewpose
