// FirstException: what an iteration or task of a parallel region throws reaches the caller after
// the region, as an exception, instead of ending the process in std::terminate.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/core/threads.hpp"

namespace viewpose {
namespace {

TEST(FirstException, AnIterationsErrorIsThrownAfterTheParallelLoop) {
  const int threads = thread_count();
  set_thread_count(2);
  FirstException failed;
  std::vector<int> done(1000, 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < 1000; ++i) {
    failed.run([&] {
      if (i == 37) throw Error("iteration 37 failed");
      done[static_cast<std::size_t>(i)] = 1;
    });
  }
  set_thread_count(threads);
  EXPECT_TRUE(failed.failed());
  EXPECT_EQ(done[37], 0);
  try {
    failed.rethrow();
    ADD_FAILURE() << "nothing was thrown";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "iteration 37 failed");
  }
}

TEST(FirstException, OnlyTheFirstIsKeptAndNothingRunsAfterIt) {
  FirstException failed;
  int ran = 0;
  failed.run([] { throw std::runtime_error("first"); });
  failed.run([&] { ++ran; });
  failed.run([] { throw std::runtime_error("second"); });
  EXPECT_EQ(ran, 0);
  try {
    failed.rethrow();
    ADD_FAILURE() << "nothing was thrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "first");
  }
}

TEST(FirstException, TasksThatThrowReachTheCaller) {
  const int threads = thread_count();
  set_thread_count(2);
  FirstException failed;
  std::atomic<int> ran{0};
#pragma omp parallel
#pragma omp single
  for (int t = 0; t < 8; ++t) {
#pragma omp task firstprivate(t) shared(failed, ran)
    failed.run([&] {
      ++ran;
      if (t == 5) throw std::bad_alloc();
    });
  }
  set_thread_count(threads);
  EXPECT_GE(ran.load(), 1);
  EXPECT_THROW(failed.rethrow(), std::bad_alloc);
}

TEST(FirstException, NothingThrownRethrowsNothing) {
  FirstException failed;
  int sum = 0;
  for (int i = 1; i <= 4; ++i) failed.run([&] { sum += i; });
  EXPECT_EQ(sum, 10);
  EXPECT_FALSE(failed.failed());
  EXPECT_NO_THROW(failed.rethrow());
}

}  // namespace
}  // namespace viewpose
