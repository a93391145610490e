// The one way raycell runs work on threads (CONTRIBUTING.md "Determinism": threads split work,
// never decide results). Every place that starts threads goes through here:
//  - ParallelFor(n, threads, f): f(0) .. f(n - 1), each index once, on up to `threads` threads
//    (the calling one among them). A caller that writes f(i)'s result into slot i gets the
//    same results, in the same order, for any thread count (the search's chains, the study's
//    brackets).
//  - WorkerPool: the same, on threads that live as long as the pool, for a loop that runs
//    many small ParallelFors (the replay driver: every configuration of one frame, frame after
//    frame) without starting threads each time.
//  - Background: one function on a thread of its own beside the caller's work, joined when
//    asked or when it goes out of scope (the bracket's lower bound beside the search, the
//    recorder's sink beside the tracing).
// In all three, the first exception a call throws is rethrown on the calling thread once
// every thread has stopped; the other calls of a ParallelFor stop after their current one.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace raycell {

// The machine's hardware threads, at least 1 (std::thread::hardware_concurrency may say 0).
unsigned HardwareThreads();

// Runs f(0) .. f(n - 1) on `threads` threads (at least 1, at most n; the caller's among them),
// for as long as the pool lives.
class WorkerPool {
 public:
  explicit WorkerPool(unsigned threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Calls f(i) once for each i < n, spread over the pool's threads; returns when all are done.
  // Rethrows the first exception a call threw (the others stop after their current call).
  void ParallelFor(std::size_t n, const std::function<void(std::size_t)>& f);
  unsigned threads() const { return unsigned(workers_.size()) + 1; }

 private:
  void Loop();
  void Work();

  std::vector<std::thread> workers_;
  std::mutex mu_;
  std::condition_variable start_, done_;
  std::uint64_t generation_ = 0;
  bool quit_ = false;
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::size_t n_ = 0, busy_ = 0;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr error_;
};

// f(0) .. f(n - 1) on min(threads, n) threads (the caller's among them; threads = 0 means 1),
// each index once; returns when all are done, rethrowing the first exception a call threw.
void ParallelFor(std::size_t n, unsigned threads, const std::function<void(std::size_t)>& f);

// Runs `f` on a thread of its own from construction. Join() waits for it and rethrows what it
// threw; the destructor waits for it too (an exception then is dropped: the caller is already
// leaving by another one).
class Background {
 public:
  explicit Background(std::function<void()> f);
  ~Background();
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  void Join();

 private:
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace raycell
