#include "tests/oracle/event_queue.h"

#include <algorithm>

#include "base/check.h"

namespace raycell {
namespace {

// std heaps are max-heaps: "a comes after b" puts the earliest event on top.
bool After(const Event& a, const Event& b) { return EventBefore(b, a); }

}  // namespace

void BinaryHeapQueue::Push(const Event& event) {
  heap_.push_back(event);
  std::push_heap(heap_.begin(), heap_.end(), After);
}

const Event& BinaryHeapQueue::Top() const {
  RAYCELL_CHECK(!heap_.empty());
  return heap_.front();
}

Event BinaryHeapQueue::Pop() {
  RAYCELL_CHECK(!heap_.empty());
  std::pop_heap(heap_.begin(), heap_.end(), After);
  const Event top = heap_.back();
  heap_.pop_back();
  return top;
}

void QuaternaryHeapQueue::Push(const Event& event) {
  std::size_t hole = heap_.size();
  heap_.push_back(event);
  while (hole > 0) {
    const std::size_t parent = (hole - 1) / 4;
    if (!EventBefore(event, heap_[parent])) break;
    heap_[hole] = heap_[parent];
    hole = parent;
  }
  heap_[hole] = event;
}

const Event& QuaternaryHeapQueue::Top() const {
  RAYCELL_CHECK(!heap_.empty());
  return heap_.front();
}

Event QuaternaryHeapQueue::Pop() {
  RAYCELL_CHECK(!heap_.empty());
  const Event top = heap_.front();
  const Event last = heap_.back();
  heap_.pop_back();
  if (!heap_.empty()) SiftDown(0, last);
  return top;
}

// Moves the hole at `hole` down to where `event` belongs and stores it there.
void QuaternaryHeapQueue::SiftDown(std::size_t hole, const Event& event) {
  const std::size_t n = heap_.size();
  for (std::size_t first = 4 * hole + 1; first < n; first = 4 * hole + 1) {
    std::size_t best = first;
    const std::size_t end = std::min(first + 4, n);
    for (std::size_t c = first + 1; c < end; ++c) {
      if (EventBefore(heap_[c], heap_[best])) best = c;
    }
    if (!EventBefore(heap_[best], event)) break;
    heap_[hole] = heap_[best];
    hole = best;
  }
  heap_[hole] = event;
}

}  // namespace raycell
