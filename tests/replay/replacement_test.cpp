// Replacement policies behind CellStore, on hand-worked request sequences (the expected
// victims worked out by hand from each policy's definition).
#include "replay/replacement.h"

#include <gtest/gtest.h>

#include "replay/config.h"
#include "replay/memory.h"
#include "tests/cell_list.h"

namespace raycell {
namespace {

LevelConfig Cells(std::uint64_t capacity, const ReplacementEntry* r) {
  LevelConfig l;
  l.name = "cache";
  l.capacity_unit = LevelConfig::CapacityUnit::kCells;
  l.capacity = capacity;
  l.replacement = r;
  return l;
}

// Looks `cell` up and, on a miss, inserts it; returns whether it was a hit.
bool Access(CellStore& s, CellId cell) {
  if (s.Lookup(cell)) return true;
  EXPECT_TRUE(s.Insert(cell));
  return false;
}

const std::vector<std::uint64_t> kFootprints(8, 100);

TEST(Replacement, LruEvictsTheLeastRecentlyUsed) {
  CellStore s(Cells(2, &kLruReplacement), &kFootprints);
  Access(s, CellId(0)), Access(s, CellId(1));
  EXPECT_TRUE(Access(s, CellId(0)));   // 0 is now the most recent
  EXPECT_FALSE(Access(s, CellId(2)));  // evicts 1
  EXPECT_TRUE(s.Contains(CellId(0)));
  EXPECT_FALSE(s.Contains(CellId(1)));
  EXPECT_TRUE(s.Contains(CellId(2)));
}

TEST(Replacement, FifoEvictsTheOldestArrivalWhateverTheHits) {
  CellStore s(Cells(2, &kFifoReplacement), &kFootprints);
  Access(s, CellId(0)), Access(s, CellId(1));
  EXPECT_TRUE(Access(s, CellId(0)));   // a hit does not refresh 0
  EXPECT_FALSE(Access(s, CellId(2)));  // evicts 0, the first in
  EXPECT_FALSE(s.Contains(CellId(0)));
  EXPECT_TRUE(s.Contains(CellId(1)));
}

TEST(Replacement, PinnedCellsAreNeverEvicted) {
  CellStore s(Cells(2, &kLruReplacement), &kFootprints);
  Access(s, CellId(0)), Access(s, CellId(1));
  EXPECT_TRUE(s.Insert(CellId(2), CellId{0}));  // 0 is the least recent but pinned: 1 goes
  EXPECT_TRUE(s.Contains(CellId(0)));
  EXPECT_FALSE(s.Contains(CellId(1)));
  CellStore one(Cells(1, &kLruReplacement), &kFootprints);
  Access(one, CellId(3));
  EXPECT_FALSE(one.Insert(CellId(4), CellId{3}));  // no room beside the pinned cell
  EXPECT_TRUE(one.Contains(CellId(3)));
}

TEST(Replacement, MinEvictsTheCellUsedFarthestAhead) {
  // Requests 0 1 2 0 1 3 0 with two cells: at the request of 2, 0 is next used at 3 and 1 at
  // 4, so 1 goes; at 3, 0 is next used at 6 and 2 never again, so 2 goes. Hits: 0 (at 3),
  // 0 (at 6): 5 misses, where LRU misses on all 7.
  const testing::CellList requests = {0, 1, 2, 0, 1, 3, 0};
  CellStore min(Cells(2, &kMinReplacement), &kFootprints, requests);
  CellStore lru(Cells(2, &kLruReplacement), &kFootprints);
  int min_misses = 0, lru_misses = 0;
  for (CellId c : requests) {
    min_misses += !Access(min, c);
    lru_misses += !Access(lru, c);
  }
  EXPECT_EQ(min_misses, 5);
  EXPECT_EQ(lru_misses, 7);
  EXPECT_FALSE(min.diverged());
}

TEST(Replacement, MinTiesGoToTheLowestCellAndStrayingIsReported) {
  // Neither 0 nor 1 is requested again: the lowest, 0, is evicted.
  CellStore s(Cells(2, &kMinReplacement), &kFootprints, testing::CellList{0, 1, 2});
  Access(s, CellId(0)), Access(s, CellId(1)), Access(s, CellId(2));
  EXPECT_FALSE(s.Contains(CellId(0)));
  EXPECT_TRUE(s.Contains(CellId(1)));
  EXPECT_FALSE(s.diverged());
  Access(s, CellId(5));  // not in the future it was given
  EXPECT_TRUE(s.diverged());
}

TEST(Replacement, BytesCapacityEvictsUntilTheCellFits) {
  const std::vector<std::uint64_t> sizes = {40, 40, 70};
  LevelConfig l = Cells(100, &kLruReplacement);
  l.capacity_unit = LevelConfig::CapacityUnit::kBytes;
  CellStore s(l, &sizes);
  Access(s, CellId(0)), Access(s, CellId(1));
  EXPECT_EQ(s.used(), 80u);
  Access(s, CellId(2));  // 70 bytes: after evicting 0, 40 + 70 is still over 100, so 1 goes too
  EXPECT_FALSE(s.Contains(CellId(0)));
  EXPECT_FALSE(s.Contains(CellId(1)));
  EXPECT_TRUE(s.Contains(CellId(2)));
  EXPECT_EQ(s.used(), 70u);
}

// The registry is the one list of policies, in the order the key's meaning names them: each
// entry once, with a distinct name that configurations parse to the entry and print back; only
// MIN needs its future requests.
TEST(ReplacementRegistry, EachPolicyOnceByNameThroughTheConfiguration) {
  const std::vector<std::pair<const ReplacementEntry*, std::string>> expected = {
      {&kLruReplacement, "lru"}, {&kFifoReplacement, "fifo"}, {&kMinReplacement, "min"}};
  ASSERT_EQ(ReplacementRegistry().size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const auto& [entry, name] = expected[i];
    EXPECT_EQ(&ReplacementRegistry()[i].get(), entry) << name;
    EXPECT_EQ(entry->name, name);
    EXPECT_EQ(entry->needs_future, entry == &kMinReplacement) << name;
    ReplayConfig c = DefaultConfig();
    ApplyOverride(c, "level.board.replacement", name);
    EXPECT_EQ(c.levels[1].replacement, entry) << name;
    EXPECT_NE(ToToml(c).find("replacement = \"" + name + "\""), std::string::npos) << name;
    EXPECT_NE(MakeReplacement(*entry, 4, testing::CellList{0, 1}), nullptr);
  }
  ReplayConfig c = DefaultConfig();
  try {
    ApplyOverride(c, "level.board.replacement", "random");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "override 'level.board.replacement': unknown replacement 'random' "
                 "(expected lru, fifo or min)");
  }
  EXPECT_NE(ToToml(c).find("# Lru | fifo | min (Belady's MIN, a bound)."), std::string::npos);
}

}  // namespace
}  // namespace raycell
