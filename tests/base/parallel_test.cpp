// base/parallel.h: every index is run exactly once whatever the thread count, results written
// by index are the same on 1 and on many threads, the first exception reaches the caller after
// every thread stopped, a pool runs many rounds on the same threads, and Background runs its
// function beside the caller and hands its exception over at Join.
#include "base/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace raycell {
namespace {

// A result that depends only on its index (and some work, so that threads interleave).
std::uint64_t Work(std::size_t i) {
  std::uint64_t x = i + 1;
  for (int k = 0; k < 1000; ++k) x = x * 6364136223846793005ULL + 1442695040888963407ULL;
  return x;
}

TEST(ParallelFor, EveryIndexOnceAndTheSameResultsOnAnyThreadCount) {
  const std::size_t n = 257;
  std::vector<std::uint64_t> one(n);
  for (std::size_t i = 0; i < n; ++i) one[i] = Work(i);  // by hand, no ParallelFor
  for (unsigned threads : {0u, 1u, 2u, 3u, 8u, 1000u}) {
    std::vector<std::uint64_t> out(n, 0);
    std::vector<std::atomic<int>> calls(n);
    ParallelFor(n, threads, [&](std::size_t i) {
      ++calls[i];
      out[i] = Work(i);
    });
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(calls[i].load(), 1) << threads << " " << i;
    EXPECT_EQ(out, one) << threads;
  }
  ParallelFor(0, 4, [](std::size_t) { FAIL() << "no task to run"; });
}

TEST(ParallelFor, TheFirstExceptionReachesTheCaller) {
  for (unsigned threads : {1u, 4u}) {
    std::atomic<int> after{0};
    try {
      ParallelFor(100, threads, [&](std::size_t i) {
        if (i == 10) throw std::runtime_error("task 10");
        if (i > 10) ++after;
      });
      ADD_FAILURE() << "no exception on " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "task 10");
    }
    // The others stop after their current call: with one thread nothing after 10 runs.
    if (threads == 1) EXPECT_EQ(after.load(), 0);
  }
}

TEST(WorkerPool, RunsManyRoundsOnTheSameThreads) {
  WorkerPool pool(4);
  EXPECT_EQ(pool.threads(), 4u);
  for (std::size_t round = 0; round < 50; ++round) {
    std::vector<std::uint64_t> out(round, 0);
    pool.ParallelFor(round, [&](std::size_t i) { out[i] = Work(i + round); });
    for (std::size_t i = 0; i < round; ++i) ASSERT_EQ(out[i], Work(i + round)) << round;
  }
  // An exception in one round leaves the pool usable for the next.
  EXPECT_THROW(pool.ParallelFor(8,
                                [](std::size_t i) {
                                  if (i == 3) throw std::logic_error("3");
                                }),
               std::logic_error);
  std::atomic<int> ran{0};
  pool.ParallelFor(8, [&](std::size_t) { ++ran; });
  EXPECT_EQ(ran.load(), 8);
}

TEST(Background, RunsBesideTheCallerAndHandsOverItsException) {
  // The caller waits for a flag only the background sets: the two run at the same time.
  std::atomic<bool> started{false}, release{false};
  Background b([&] {
    started = true;
    while (!release) std::this_thread::yield();
  });
  while (!started) std::this_thread::yield();
  release = true;
  b.Join();
  Background failing([] { throw std::runtime_error("sink full"); });
  try {
    failing.Join();
    ADD_FAILURE() << "Join did not rethrow";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "sink full");
  }
  // Not joined by hand: the destructor waits for it.
  std::atomic<int> done{0};
  {
    Background c([&] { ++done; });
  }
  EXPECT_EQ(done.load(), 1);
}

}  // namespace
}  // namespace raycell
