#include "engine/slot_queue.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "base/random.h"
#include "tests/oracle/event_queue.h"

namespace raycell {
namespace {

enum class Kind : std::uint8_t { kNone, kA, kB };

// One handled event: which slot, when, its insertion number and kind.
struct Handled {
  std::uint32_t slot;
  std::uint64_t time, seq;
  Kind kind;
  bool operator==(const Handled& o) const {
    return slot == o.slot && time == o.time && seq == o.seq && kind == o.kind;
  }
};

// A random model of `slots` components, each with at most one pending event, run on the slot
// queue and, with the same events, on the engine's binary heap (Event: time, priority 0, seq,
// target = slot): the handled events must come in the same order with the same numbers. Small
// delays (0..span ps) make ties in time common, so the insertion order decides them; a
// handled component reschedules itself, sometimes goes quiet, and wakes others, as the
// replay's processors do.
std::vector<Handled> RunSlots(std::uint32_t slots, std::uint64_t span, std::uint64_t seed,
                              int steps) {
  SplitMix64 rng(seed);
  SlotQueue<Kind> q(slots);
  std::vector<bool> quiet(slots, false);
  for (std::uint32_t i = 0; i < slots; ++i) {
    q.Schedule(i, SimTime::Picoseconds(rng.Next() % (span + 1)), Kind::kA);
    q.Update(i);
  }
  std::vector<Handled> out;
  for (std::uint32_t p = q.top(); int(out.size()) < steps; p = q.Update(p)) {
    const auto& s = q.at(p);
    if (s.kind == Kind{}) break;
    out.push_back({p, s.time.picoseconds(), s.seq, s.kind});
    const SimTime now = s.time;
    q.Clear(p);
    const std::uint64_t r = rng.Next();
    if (r % 5 == 0) {
      quiet[p] = true;  // waits until woken
    } else {
      q.Schedule(p, now + SimTime::Picoseconds(rng.Next() % (span + 1)),
                 r % 2 ? Kind::kA : Kind::kB);
    }
    if (r % 3 == 0) {  // wakes every quiet component, in slot order, at now
      for (std::uint32_t o = 0; o < slots; ++o) {
        if (!quiet[o] || o == p) continue;
        quiet[o] = false;
        q.Schedule(o, now, Kind::kB);
        q.Update(o);
      }
    }
  }
  return out;
}

std::vector<Handled> RunHeap(std::uint32_t slots, std::uint64_t span, std::uint64_t seed,
                             int steps) {
  SplitMix64 rng(seed);
  BinaryHeapQueue q;
  std::uint64_t seq = 0;
  std::vector<bool> quiet(slots, false);
  const auto push = [&](std::uint32_t slot, SimTime when, Kind kind) {
    q.Push(Event{when, 0, seq++, slot, std::uint32_t(kind), 0});
  };
  for (std::uint32_t i = 0; i < slots; ++i) {
    push(i, SimTime::Picoseconds(rng.Next() % (span + 1)), Kind::kA);
  }
  std::vector<Handled> out;
  while (!q.Empty() && int(out.size()) < steps) {
    const Event e = q.Pop();
    const std::uint32_t p = e.target;
    out.push_back({p, e.time.picoseconds(), e.seq, Kind(e.kind)});
    const std::uint64_t r = rng.Next();
    if (r % 5 == 0) {
      quiet[p] = true;
    } else {
      push(p, e.time + SimTime::Picoseconds(rng.Next() % (span + 1)), r % 2 ? Kind::kA : Kind::kB);
    }
    if (r % 3 == 0) {
      for (std::uint32_t o = 0; o < slots; ++o) {
        if (!quiet[o] || o == p) continue;
        quiet[o] = false;
        push(o, e.time, Kind::kB);
      }
    }
  }
  return out;
}

// The selection of each tree level (written in asm on x86-64) against a plain comparison of
// (time, key) pairs, and the portable form likewise: random words, equal times, extremes.
TEST(SlotQueue, EachLevelKeepsTheEarlierKey) {
  using Q = SlotQueue<int>;
  SplitMix64 rng(23);
  const std::uint64_t extremes[] = {0, 1, 2, UINT64_MAX - 1, UINT64_MAX, 1ull << 63};
  for (int i = 0; i < 200000; ++i) {
    std::uint64_t t = rng.Next(), key = rng.Next(), bt = rng.Next(), bkey = rng.Next();
    if (i % 3 == 0) bt = t;  // ties on time: the key decides
    if (i % 7 == 0) t = extremes[rng.Next() % 6], bt = extremes[rng.Next() % 6];
    if (i % 11 == 0) key = extremes[rng.Next() % 6], bkey = extremes[rng.Next() % 6];
    if (t == bt && key == bkey) continue;  // keys are distinct in a queue
    const bool b_earlier = bt < t || (bt == t && bkey < key);
    std::uint64_t t1 = t, k1 = key, t2 = t, k2 = key;
    Q::KeepEarlier(t1, k1, bt, bkey);
    Q::KeepEarlierPortable(t2, k2, bt, bkey);
    ASSERT_EQ(t1, b_earlier ? bt : t) << i;
    ASSERT_EQ(k1, b_earlier ? bkey : key) << i;
    ASSERT_EQ(t2, t1) << i;
    ASSERT_EQ(k2, k1) << i;
  }
}

TEST(SlotQueue, HandsOutEventsInTheEnginesOrder) {
  // Slot counts around powers of two (padding slots), delays from "all ties" to spread out.
  for (std::uint32_t slots : {1u, 2u, 3u, 5u, 8u, 13u, 16u, 17u}) {
    for (std::uint64_t span : {0ull, 3ull, 2000ull}) {
      for (std::uint64_t seed : {1ull, 2ull, 3ull}) {
        const auto a = RunSlots(slots, span, seed, 5000);
        const auto b = RunHeap(slots, span, seed, 5000);
        ASSERT_FALSE(a.empty());
        ASSERT_EQ(a.size(), b.size()) << slots << " slots, span " << span << ", seed " << seed;
        for (std::size_t i = 0; i < a.size(); ++i) {
          ASSERT_TRUE(a[i] == b[i])
              << "event " << i << " of " << slots << " slots, span " << span << ", seed " << seed
              << ": slot " << a[i].slot << " t=" << a[i].time << " seq=" << a[i].seq
              << " against slot " << b[i].slot << " t=" << b[i].time << " seq=" << b[i].seq;
        }
      }
    }
  }
}

TEST(SlotQueue, EmptyMeansNothingPendingAndTiesGoToTheEarlierInsertion) {
  SlotQueue<Kind> q(6);
  EXPECT_EQ(q.at(q.top()).kind, Kind::kNone);
  q.Schedule(4, SimTime::Picoseconds(7), Kind::kA);
  q.Update(4);
  q.Schedule(1, SimTime::Picoseconds(7), Kind::kB);  // same time, inserted later
  EXPECT_EQ(q.Update(1), 4u);
  q.Schedule(5, SimTime::Picoseconds(6), Kind::kB);
  EXPECT_EQ(q.Update(5), 5u);
  EXPECT_EQ(q.scheduled(), 3u);
  q.Clear(5);
  EXPECT_EQ(q.Update(5), 4u);
  q.Clear(4);
  EXPECT_EQ(q.Update(4), 1u);
  EXPECT_EQ(q.at(1).seq, 1u);
  q.Clear(1);
  EXPECT_EQ(q.at(q.Update(1)).kind, Kind::kNone);
}

TEST(SlotQueueDeathTest, ASlotHoldsOneEventAtATime) {
  SlotQueue<Kind> q(3);
  q.Schedule(2, SimTime::Picoseconds(1), Kind::kA);
  EXPECT_DEATH(q.Schedule(2, SimTime::Picoseconds(2), Kind::kB), "CHECK");
}

TEST(SlotQueue, NumbersEnoughEventsForAnyReplay) {
  // The slot index takes the low bits of the key: 1024 processors (the configuration's
  // limit) leave 2^54 insertion numbers, far beyond a replay's event count.
  EXPECT_EQ(SlotQueue<Kind>(1024).max_events(), (std::uint64_t{1} << 54) - 1);
  EXPECT_EQ(SlotQueue<Kind>(1).max_events(), UINT64_MAX);
}

}  // namespace
}  // namespace raycell
