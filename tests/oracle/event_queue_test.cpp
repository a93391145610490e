#include "tests/oracle/event_queue.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "tests/oracle/calendar_queue.h"

namespace raycell {
namespace {

Event At(std::uint64_t ps, std::int32_t priority, std::uint64_t seq) {
  Event e;
  e.time = SimTime::Picoseconds(ps);
  e.priority = priority;
  e.seq = seq;
  e.payload = seq;
  return e;
}

std::vector<std::uint64_t> Drain(EventQueue& q) {
  std::vector<std::uint64_t> seqs;
  while (!q.Empty()) seqs.push_back(q.Pop().seq);
  return seqs;
}

// Every EventQueue implementation passes the same tests.
template <typename Queue>
class EventQueueTest : public ::testing::Test {};
using Queues = ::testing::Types<BinaryHeapQueue, QuaternaryHeapQueue, CalendarQueue>;
TYPED_TEST_SUITE(EventQueueTest, Queues);

TYPED_TEST(EventQueueTest, EqualTimesOrderByPriorityThenInsertion) {
  TypeParam q;
  q.Push(At(10, 1, 0));
  q.Push(At(10, 0, 1));
  q.Push(At(5, 9, 2));
  q.Push(At(10, 1, 3));
  q.Push(At(10, -1, 4));
  q.Push(At(10, 0, 5));
  EXPECT_EQ(q.Size(), 6u);
  EXPECT_EQ(q.Top().seq, 2u);
  EXPECT_EQ(Drain(q), (std::vector<std::uint64_t>{2, 4, 1, 5, 0, 3}));
  EXPECT_TRUE(q.Empty());
}

TEST(EventQueue, EachQueueReportsItsName) {
  EXPECT_EQ(BinaryHeapQueue().Name(), "binary-heap");
  EXPECT_EQ(QuaternaryHeapQueue().Name(), "4-ary-heap");
  EXPECT_EQ(CalendarQueue().Name(), "calendar");
}

TEST(EventQueue, EventBeforeIsAStrictOrder) {
  EXPECT_TRUE(EventBefore(At(1, 5, 9), At(2, 0, 0)));
  EXPECT_TRUE(EventBefore(At(2, 0, 9), At(2, 1, 0)));
  EXPECT_TRUE(EventBefore(At(2, 1, 3), At(2, 1, 4)));
  EXPECT_FALSE(EventBefore(At(2, 1, 4), At(2, 1, 4)));
}

// 100k events with many ties, pushed in seq order, must come out exactly in the order
// std::stable_sort by (time, priority) gives them.
TYPED_TEST(EventQueueTest, MatchesStableSortOnRandomEvents) {
  std::mt19937_64 rng(12345);
  std::uniform_int_distribution<std::uint64_t> time(0, 999);
  std::uniform_int_distribution<std::int32_t> priority(-2, 2);
  std::vector<Event> events;
  for (std::uint64_t seq = 0; seq < 100'000; ++seq) {
    events.push_back(At(time(rng), priority(rng), seq));
  }
  std::vector<Event> expected = events;
  std::stable_sort(expected.begin(), expected.end(), [](const Event& a, const Event& b) {
    return a.time != b.time ? a.time < b.time : a.priority < b.priority;
  });

  TypeParam q;
  for (const Event& e : events) q.Push(e);
  std::vector<std::uint64_t> got = Drain(q);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], expected[i].seq) << "at " << i;
}

// Interleaved push/pop in hold style: every popped event at time t is followed by a push at
// t + d >= t. Popped times must never decrease.
TYPED_TEST(EventQueueTest, HoldOrderIsMonotone) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::uint64_t> delay(0, 50);
  std::uniform_int_distribution<std::int32_t> priority(0, 3);
  TypeParam q;
  std::uint64_t seq = 0;
  for (; seq < 1000; ++seq) q.Push(At(delay(rng), priority(rng), seq));
  Event prev = q.Top();
  for (int i = 0; i < 100'000; ++i) {
    const Event e = q.Pop();
    ASSERT_LE(prev.time, e.time) << e.ToString() << " after " << prev.ToString();
    prev = e;
    q.Push(At(e.time.picoseconds() + delay(rng), priority(rng), seq++));
  }
  EXPECT_EQ(q.Size(), 1000u);
}

// Interleaved random pushes and pops: both implementations give the same sequence, and
// each pop is the minimum of what is pending (checked against a sorted reference).
TYPED_TEST(EventQueueTest, InterleavedMatchesReference) {
  std::mt19937_64 rng(99);
  TypeParam q;
  std::vector<Event> reference;  // kept sorted by EventBefore
  std::uint64_t seq = 0;
  for (int step = 0; step < 20'000; ++step) {
    if (rng() % 3 != 0 || reference.empty()) {
      const Event e = At(rng() % 200, std::int32_t(rng() % 3), seq++);
      q.Push(e);
      reference.insert(std::upper_bound(reference.begin(), reference.end(), e, EventBefore), e);
    } else {
      ASSERT_EQ(q.Pop().seq, reference.front().seq) << "step " << step;
      reference.erase(reference.begin());
    }
    ASSERT_EQ(q.Size(), reference.size());
  }
}

// Sizes that grow and shrink by orders of magnitude, spacings from 1 ps to 2^40 ps that
// change while events are pending, events at SimTime::Max() and pushes before the last
// pop: every pop is the minimum of what is pending.
TYPED_TEST(EventQueueTest, ChangingSizesAndSpacingsMatchReference) {
  std::mt19937_64 rng(4242);
  TypeParam q;
  std::multiset<std::pair<std::pair<std::uint64_t, std::int32_t>, std::uint64_t>> reference;
  std::uint64_t seq = 0, now = 0;
  auto push = [&](std::uint64_t t) {
    const Event e = At(t, std::int32_t(rng() % 2), seq++);
    q.Push(e);
    reference.insert({{t, e.priority}, e.seq});
  };
  auto pop = [&] {
    ASSERT_FALSE(reference.empty());
    const Event e = q.Pop();
    const auto expected = *reference.begin();
    reference.erase(reference.begin());
    ASSERT_EQ(e.seq, expected.second) << "at " << e.ToString();
    now = e.time.picoseconds();
  };
  for (const unsigned spacing_log2 : {0u, 10u, 3u, 40u, 20u, 1u}) {
    const std::uint64_t spacing = std::uint64_t{1} << spacing_log2;
    const std::size_t target = 1 + rng() % 20'000;
    while (reference.size() < target) {
      const std::uint64_t delay = rng() % 4096 * spacing;
      if (rng() % 8 == 0) {  // some in the past: just before now, or anywhere before it
        push(rng() % 64 == 0 ? rng() % (now + 1) : now - std::min(now, rng() % 4096 * spacing));
      } else {
        push(now + std::min(delay, ~now));
      }
    }
    if (spacing_log2 == 40) push(SimTime::Max().picoseconds());
    for (std::size_t i = 0; i < target / 2; ++i) pop();
    while (reference.size() > 3) pop();
    ASSERT_EQ(q.Size(), reference.size());
  }
  while (!reference.empty()) pop();
  EXPECT_TRUE(q.Empty());
}

TYPED_TEST(EventQueueTest, PopOnEmptyIsACheckFailure) {
  TypeParam q;
  EXPECT_DEATH(q.Pop(), "CHECK failed");
  EXPECT_DEATH(q.Top(), "CHECK failed");
}

// The calendar adapts its day to the events' spacing: after a hold at 1 ps spacing and one
// at 2^20 ps, days are short and long respectively (about an event a day).
TEST(CalendarQueue, DayLengthFollowsTheSpacing) {
  for (const std::uint64_t spacing : {std::uint64_t{1}, std::uint64_t{1} << 20}) {
    CalendarQueue q;
    std::mt19937_64 rng(1);
    std::uint64_t seq = 0;
    for (; seq < 1000; ++seq) q.Push(At(seq * spacing, 0, seq));
    for (int i = 0; i < 20'000; ++i) {
      const Event e = q.Pop();
      q.Push(At(e.time.picoseconds() + (500 + rng() % 1000) * spacing, 0, seq++));
    }
    EXPECT_GE(q.bucket_count(), 256u);
    EXPECT_LE(q.day_length(), 8 * spacing) << spacing;
    EXPECT_GE(q.day_length(), spacing / 2) << spacing;
  }
}

// Events in pairs 1 ps apart, the pairs 2^12 ps apart: the median gap (1 ps) makes days far
// too short, so pops would walk thousands of empty days; the queue lengthens them until a
// pop walks a few (days of 2^10 ps or more).
TEST(CalendarQueue, TooShortDaysAreLengthened) {
  CalendarQueue q;
  std::uint64_t seq = 0;
  for (std::uint64_t pair = 0; pair < 500; ++pair) {
    q.Push(At(pair << 12, 0, seq++));
    q.Push(At((pair << 12) + 1, 0, seq++));
  }
  for (int i = 0; i < 40'000; ++i) {  // each pair, once popped, comes back 500 pairs later
    const Event e = q.Pop();
    q.Push(At(e.time.picoseconds() + (std::uint64_t{500} << 12), 0, seq++));
  }
  EXPECT_GE(q.day_length(), std::uint64_t{1} << 10);
  EXPECT_EQ(q.Size(), 1000u);
}

}  // namespace
}  // namespace raycell
