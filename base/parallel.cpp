#include "base/parallel.h"

#include <algorithm>
#include <utility>

namespace raycell {

unsigned HardwareThreads() { return std::max(1u, std::thread::hardware_concurrency()); }

WorkerPool::WorkerPool(unsigned threads) {
  for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this] { Loop(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    quit_ = true;
    ++generation_;
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::ParallelFor(std::size_t n, const std::function<void(std::size_t)>& f) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    job_ = &f;
    n_ = n;
    next_ = 0;
    error_ = nullptr;
    busy_ = workers_.size();
    ++generation_;
  }
  start_.notify_all();
  Work();
  std::unique_lock<std::mutex> lock(mu_);
  done_.wait(lock, [this] { return busy_ == 0; });
  job_ = nullptr;
  if (error_) std::rethrow_exception(error_);
}

void WorkerPool::Loop() {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      start_.wait(lock, [&] { return generation_ != seen; });
      seen = generation_;
      if (quit_) return;
    }
    Work();
    {
      std::lock_guard<std::mutex> lock(mu_);
      --busy_;
    }
    done_.notify_one();
  }
}

void WorkerPool::Work() {
  for (std::size_t i; (i = next_++) < n_;) {
    try {
      (*job_)(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu_);
      if (!error_) error_ = std::current_exception();
      next_ = n_;  // the others stop after their current call
    }
  }
}

void ParallelFor(std::size_t n, unsigned threads, const std::function<void(std::size_t)>& f) {
  const unsigned t = unsigned(std::clamp<std::size_t>(threads, 1, std::max<std::size_t>(n, 1)));
  if (t == 1) {  // no thread started, no lock taken
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  WorkerPool(t).ParallelFor(n, f);
}

Background::Background(std::function<void()> f)
    : thread_([this, f = std::move(f)] {
        try {
          f();
        } catch (...) {
          error_ = std::current_exception();
        }
      }) {}

Background::~Background() {
  if (thread_.joinable()) thread_.join();
}

void Background::Join() {
  thread_.join();
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

}  // namespace raycell
