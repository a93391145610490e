// The pending-event set behind an interface (SST), so a faster structure can replace the
// binary heap without touching the simulation loop. Implementations order events by
// EventBefore (time, priority, seq).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "engine/event.h"

namespace raycell {

class EventQueue {
 public:
  virtual ~EventQueue() = default;
  virtual void Push(const Event& event) = 0;
  // The earliest event. CHECK-fails when empty.
  virtual const Event& Top() const = 0;
  // Removes and returns the earliest event. CHECK-fails when empty.
  virtual Event Pop() = 0;
  virtual std::size_t Size() const = 0;
  bool Empty() const { return Size() == 0; }
  // For logs and benchmark tables: "binary-heap".
  virtual std::string Name() const = 0;
};

// An implicit binary min-heap in a vector: O(log n) push and pop.
class BinaryHeapQueue final : public EventQueue {
 public:
  BinaryHeapQueue() = default;
  explicit BinaryHeapQueue(std::size_t reserve) { heap_.reserve(reserve); }
  void Push(const Event& event) override;
  const Event& Top() const override;
  Event Pop() override;
  std::size_t Size() const override { return heap_.size(); }
  std::string Name() const override { return "binary-heap"; }

 private:
  std::vector<Event> heap_;
};

// An implicit 4-ary min-heap with hole-based sifting: half the depth of the binary heap and
// children on adjacent cache lines, so fewer cache misses per pop at large sizes.
class QuaternaryHeapQueue final : public EventQueue {
 public:
  QuaternaryHeapQueue() = default;
  explicit QuaternaryHeapQueue(std::size_t reserve) { heap_.reserve(reserve); }
  void Push(const Event& event) override;
  const Event& Top() const override;
  Event Pop() override;
  std::size_t Size() const override { return heap_.size(); }
  std::string Name() const override { return "4-ary-heap"; }

 private:
  void SiftDown(std::size_t hole, const Event& event);
  std::vector<Event> heap_;
};

}  // namespace raycell
