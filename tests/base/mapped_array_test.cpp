// base/mapped_array.h: the replay's queues and the schedulers' per-node arrays. Every operation
// keeps the items and their order as std::vector would, below and across the size where blocks
// are mapped and grown with mremap.
#include "base/mapped_array.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "base/random.h"

namespace raycell {
namespace {

struct Item {  // 12 bytes, as a watching replay's queued unit: pages never hold whole items
  std::uint32_t a, b, c;
  bool operator==(const Item& o) const { return a == o.a && b == o.b && c == o.c; }
};

void ExpectSame(const MappedArray<Item>& got, const std::vector<Item>& want) {
  ASSERT_EQ(got.size(), want.size());
  ASSERT_GE(got.capacity(), got.size());
  for (std::size_t i = 0; i < want.size(); ++i) ASSERT_EQ(got[i], want[i]) << "item " << i;
}

TEST(MappedArray, GrowingPastTheMappedSizeKeepsEveryItemInOrder) {
  MappedArray<Item> a;
  std::vector<Item> want;
  // 300,000 items of 12 bytes: malloc'd, then mapped at 128 KiB and grown by mremap 5 times.
  for (std::uint32_t i = 0; i < 300000; ++i) {
    a.push_back({i, ~i, i * 7});
    want.push_back({i, ~i, i * 7});
  }
  ExpectSame(a, want);
  EXPECT_GE(a.capacity() * sizeof(Item), MappedBlocks::kFrom);
}

TEST(MappedArray, EveryOperationMatchesStdVector) {
  SplitMix64 rng(42);
  MappedArray<Item> a, b;
  std::vector<Item> wa, wb;
  std::uint32_t next = 0;
  for (int step = 0; step < 4000; ++step) {
    const std::uint64_t op = rng.Next() % 100;
    if (op < 58) {  // a run of pushes, sometimes long enough to cross the mapped size
      const std::uint64_t n = rng.Next() % (op < 5 ? 40000 : 300);
      for (std::uint64_t k = 0; k < n; ++k, ++next) {
        a.push_back({next, next ^ 0x5555u, std::uint32_t(step)});
        wa.push_back({next, next ^ 0x5555u, std::uint32_t(step)});
      }
    } else if (op < 66) {  // b's items appended to a (a queue taken into a worklist)
      a.append(b.begin(), b.end());
      wa.insert(wa.end(), wb.begin(), wb.end());
    } else if (op < 74) {  // worked units dropped from the front
      const std::size_t n = wa.empty() ? 0 : rng.Next() % (wa.size() + 1);
      a.erase_front(n);
      wa.erase(wa.begin(), wa.begin() + std::ptrdiff_t(n));
    } else if (op < 80) {  // the later part split off
      const std::size_t n = wa.empty() ? 0 : rng.Next() % (wa.size() + 1);
      a.truncate(n);
      wa.resize(n);
    } else if (op < 84) {  // resized, shorter or longer (a per-node array as nodes arrive)
      const std::size_t n = rng.Next() % (wa.size() + 40000);
      const Item fill{std::uint32_t(step), 7, next++};
      a.resize(n, fill);
      wa.resize(n, fill);
    } else if (op < 86) {  // refilled (a per-node array as a frame begins)
      const std::size_t n = rng.Next() % 40000;
      const Item fill{std::uint32_t(step), 9, next++};
      a.assign(n, fill);
      wa.assign(n, fill);
    } else if (op < 92) {
      a.swap(b);
      wa.swap(wb);
    } else if (op < 96) {
      a.clear();
      wa.clear();
    } else if (op < 97) {
      FreeRoom(a);
      wa.clear();
      EXPECT_EQ(a.capacity(), 0u);
    } else if (op < 98) {  // fitted to its items (a Cell Tree once built), then copied
      a.shrink_to_fit();
      ExpectSame(a, wa);
      // The room left is the items' (a mapped block's rounded up to whole pages, and never
      // under the mapped size).
      EXPECT_LE(a.capacity() * sizeof(Item),
                std::max<std::size_t>(wa.size() * sizeof(Item), MappedBlocks::kFrom) + 4096);
      MappedArray<Item> copy(a);
      ExpectSame(copy, wa);
      b = copy;
      wb = wa;
    } else if (op < 99) {  // room reserved, then value-initialised items (a tree's counts)
      const std::size_t n = wa.size() + rng.Next() % 60000;
      a.reserve(n);
      EXPECT_GE(a.capacity(), n);
      ExpectSame(a, wa);
      a.resize(n);
      wa.resize(n, Item{0, 0, 0});
    } else {  // moved out and back
      MappedArray<Item> moved(std::move(a));
      EXPECT_TRUE(a.empty());
      a = std::move(moved);
    }
    ExpectSame(a, wa);
    ExpectSame(b, wb);
  }
}

// A Cell Tree's arrays are reserved for a frame's visits and fitted to its nodes once built:
// the fit keeps every item and gives the room past them back, from a mapped block or a small one.
TEST(MappedArray, ShrinkToFitKeepsTheItemsAndGivesTheRoomBack) {
  for (const std::size_t n :
       {std::size_t{0}, std::size_t{10}, std::size_t{5000}, std::size_t{1} << 20}) {
    MappedArray<Item> a;
    std::vector<Item> want;
    a.reserve(std::size_t{4} << 20);  // 48 MiB reserved, mapped
    for (std::uint32_t i = 0; i < n; ++i) {
      a.push_back({i, 3 * i, ~i});
      want.push_back({i, 3 * i, ~i});
    }
    a.shrink_to_fit();
    ExpectSame(a, want);
    const std::size_t bytes = n * sizeof(Item);
    EXPECT_LE(a.capacity() * sizeof(Item), std::max(bytes, MappedBlocks::kFrom) + 4096) << n;
    a.push_back({1, 2, 3});  // and it grows again from there
    want.push_back({1, 2, 3});
    ExpectSame(a, want);
  }
}

TEST(MappedArray, ReleaseRoomAboveFreesOnlyARoomLargerThanKept) {
  MappedArray<Item> a;
  for (std::uint32_t i = 0; i < 100; ++i) a.push_back({i, i, i});
  const std::size_t room = a.capacity();
  ReleaseRoomAbove(a, room);
  EXPECT_EQ(a.capacity(), room);
  EXPECT_EQ(a.size(), 100u);
  ReleaseRoomAbove(a, room - 1);
  EXPECT_EQ(a.capacity(), 0u);
  EXPECT_TRUE(a.empty());
}

}  // namespace
}  // namespace raycell
