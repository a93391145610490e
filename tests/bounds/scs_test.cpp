#include "bounds/scs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <set>

#include "graph/cell_tree.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using Strings = std::vector<CellString>;

constexpr CellId A{0}, B{1}, C{2};

bool Covers(const CellString& super, const CellString& s) {
  std::size_t i = 0;
  for (CellId c : super) {
    if (i < s.size() && s[i] == c) ++i;
  }
  return i == s.size();
}

bool CoversAll(const CellString& super, const Strings& strings) {
  return std::all_of(strings.begin(), strings.end(),
                     [&](const CellString& s) { return Covers(super, s); });
}

// Calls fn on every string over `alphabet` of length `length`.
template <typename F>
bool AnyString(const std::vector<CellId>& alphabet, std::size_t length, CellString& s, F fn) {
  if (s.size() == length) return fn(s);
  for (CellId c : alphabet) {
    s.push_back(c);
    const bool found = AnyString(alphabet, length, s, fn);
    s.pop_back();
    if (found) return true;
  }
  return false;
}

std::vector<CellId> Alphabet(const Strings& strings) {
  std::vector<CellId> a;
  for (const CellString& s : strings) a.insert(a.end(), s.begin(), s.end());
  std::sort(a.begin(), a.end());
  a.erase(std::unique(a.begin(), a.end()), a.end());
  return a;
}

// The SCS length by trying every string of length 0, 1, 2, ... over the alphabet.
std::size_t BruteForceScs(const Strings& strings) {
  const std::vector<CellId> alphabet = Alphabet(strings);
  for (std::size_t length = 0;; ++length) {
    CellString s;
    if (AnyString(alphabet, length, s, [&](const CellString& t) { return CoversAll(t, strings); }))
      return length;
  }
}

// Whether some common supersequence has at most budget[c] copies of each c, by trying every
// string within the budgets (no supersequence needs more copies than the budgets allow).
bool BruteForceFits(const Strings& strings, const std::vector<std::uint32_t>& budget) {
  const std::vector<CellId> alphabet = Alphabet(strings);
  std::size_t most = 0;
  for (CellId c : alphabet) most += budget[c.value()];
  for (std::size_t length = 0; length <= most; ++length) {
    CellString s;
    const bool found = AnyString(alphabet, length, s, [&](const CellString& t) {
      for (CellId c : alphabet) {
        if (std::count(t.begin(), t.end(), c) > budget[c.value()]) return false;
      }
      return CoversAll(t, strings);
    });
    if (found) return true;
  }
  return false;
}

// The SCS length by breadth-first search over position vectors (no heuristic, no pruning):
// each level appends every symbol of the alphabet. With `budget`, only within it (returns
// SIZE_MAX when nothing fits).
std::size_t BfsScs(const Strings& strings, const std::vector<std::uint32_t>* budget = nullptr) {
  const std::vector<CellId> alphabet = Alphabet(strings);
  using State = std::pair<std::vector<std::size_t>, std::vector<std::uint32_t>>;
  State start{std::vector<std::size_t>(strings.size(), 0),
              std::vector<std::uint32_t>(alphabet.size(), 0)};
  std::set<State> seen{start};
  std::vector<State> level{start};
  for (std::size_t depth = 0; !level.empty(); ++depth) {
    std::vector<State> next;
    for (const State& s : level) {
      bool done = true;
      for (std::size_t i = 0; i < strings.size(); ++i)
        done = done && s.first[i] == strings[i].size();
      if (done) return depth;
      for (std::size_t a = 0; a < alphabet.size(); ++a) {
        State t = s;
        if (budget != nullptr && ++t.second[a] > (*budget)[alphabet[a].value()]) continue;
        if (budget == nullptr) t.second.clear();
        for (std::size_t i = 0; i < strings.size(); ++i) {
          if (t.first[i] < strings[i].size() && strings[i][t.first[i]] == alphabet[a]) ++t.first[i];
        }
        if (seen.insert(t).second) next.push_back(t);
      }
    }
    level = std::move(next);
  }
  return SIZE_MAX;
}

Strings RandomStrings(std::mt19937& rng, std::uint32_t symbols, int count, int max_length) {
  Strings out;
  for (int i = 0; i < count; ++i) {
    CellString s;
    const int length = rng() % (max_length + 1);
    for (int j = 0; j < length; ++j) s.push_back(CellId(rng() % symbols));
    out.push_back(s);
  }
  return out;
}

TEST(ScsTest, SmallCasesHaveTheirKnownShortestLength) {
  EXPECT_EQ(ShortestCommonSupersequence({}).lower_bound, 0u);
  EXPECT_TRUE(ShortestCommonSupersequence({{}, {}}).exact);
  const ScsResult crossed = ShortestCommonSupersequence({{A, B}, {B, A}});
  EXPECT_TRUE(crossed.exact);
  EXPECT_EQ(crossed.lower_bound, 3u);
  EXPECT_EQ(crossed.supersequence.size(), 3u);
  EXPECT_TRUE(CoversAll(crossed.supersequence, {{A, B}, {B, A}}));
  // The three rotations of A B C need 5.
  EXPECT_EQ(ShortestCommonSupersequence({{A, B, C}, {B, C, A}, {C, A, B}}).lower_bound, 5u);
  // Repeats count: A A and A need 2 copies of A.
  EXPECT_EQ(ShortestCommonSupersequence({{A, A}, {A}}).lower_bound, 2u);
}

TEST(ScsTest, ExactAgainstBruteForceOnRandomSets) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 600; ++trial) {
    const std::uint32_t symbols = 1 + rng() % 3;
    const Strings strings = RandomStrings(rng, symbols, 1 + rng() % 5, 5);
    const ScsResult r = ShortestCommonSupersequence(strings);
    ASSERT_TRUE(r.exact) << r.ToString();
    const std::size_t expected = BruteForceScs(strings);
    ASSERT_EQ(r.lower_bound, expected) << trial;
    ASSERT_EQ(r.upper_bound, expected);
    ASSERT_EQ(r.supersequence.size(), expected);
    ASSERT_TRUE(CoversAll(r.supersequence, strings)) << trial;
  }
}

// Four to six symbols: the pair heuristic and its memo tables are in play.
TEST(ScsTest, ExactWithThePairHeuristicAgainstBreadthFirstSearch) {
  std::mt19937 rng(16);
  for (int trial = 0; trial < 100; ++trial) {
    const std::uint32_t symbols = 4 + rng() % 2;
    const Strings strings = RandomStrings(rng, symbols, 2 + rng() % 4, 6);
    const ScsSolver solver(strings);
    const ScsResult r = solver.Shortest();
    ASSERT_TRUE(r.exact);
    ASSERT_EQ(r.lower_bound, BfsScs(strings)) << trial;
    ASSERT_TRUE(CoversAll(r.supersequence, strings));
    // And a budget search with the same heuristic tables.
    std::vector<std::uint32_t> budget(symbols);
    for (auto& b : budget) b = rng() % 3 + 1;
    const BudgetResult fits = solver.FitsBudget(budget);
    ASSERT_EQ(fits.answer == Realisability::kRealisable, BfsScs(strings, &budget) != SIZE_MAX)
        << trial;
  }
}

// Eight to nine symbols: pairs of the heuristic are merged into parts of up to four symbols.
// Searches stopped after a few states report the heuristic's own value at the start, which
// must never exceed the SCS; unlimited ones must find it.
TEST(ScsTest, MergedPartsStayAdmissible) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 60; ++trial) {
    // Orders of the same symbols that disagree: pairs, and groups of pairs, gain.
    const std::uint32_t symbols = 8 + rng() % 2;
    Strings strings;
    for (int i = 3 + rng() % 2; i > 0; --i) {
      CellString s;
      for (CellId c : CellRange(symbols)) s.push_back(c);
      std::shuffle(s.begin(), s.end(), rng);
      s.resize(5 + rng() % 3);
      strings.push_back(s);
    }
    const std::size_t expected = BfsScs(strings);
    const ScsSolver solver(strings, /*merge_parts=*/true);
    ScsLimits limits;
    limits.max_states = 1 + rng() % 3;
    const ScsResult stopped = solver.Shortest(limits);
    ASSERT_LE(stopped.lower_bound, expected) << trial;
    const ScsResult r = solver.Shortest();
    ASSERT_TRUE(r.exact);
    ASSERT_EQ(r.lower_bound, expected) << trial;
    ASSERT_TRUE(CoversAll(r.supersequence, strings));
  }
}

TEST(ScsTest, LimitedSearchStillBracketsTheOptimum) {
  std::mt19937 rng(12);
  int stopped = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Strings strings = RandomStrings(rng, 3, 2 + rng() % 5, 6);
    ScsLimits limits;
    limits.max_states = 1 + rng() % 6;
    const ScsResult r = ShortestCommonSupersequence(strings, limits);
    const std::size_t expected = BruteForceScs(strings);
    ASSERT_LE(r.lower_bound, expected) << trial;
    ASSERT_GE(r.upper_bound, expected) << trial;
    ASSERT_EQ(r.supersequence.size(), r.upper_bound);
    ASSERT_TRUE(CoversAll(r.supersequence, strings));
    if (!r.exact) ++stopped;
  }
  EXPECT_GT(stopped, 10);  // the limit did stop some searches
}

TEST(ScsTest, DominatedStringsChangeNothing) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 200; ++trial) {
    const Strings strings = RandomStrings(rng, 3, 1 + rng() % 4, 6);
    Strings more = strings;
    for (const CellString& s : strings) {  // add subsequences of the given strings
      CellString sub;
      for (CellId c : s) {
        if (rng() % 2) sub.push_back(c);
      }
      more.push_back(sub);
    }
    std::shuffle(more.begin(), more.end(), rng);
    ASSERT_EQ(BruteForceScs(more), ShortestCommonSupersequence(strings).lower_bound);
    ASSERT_EQ(ScsSolver(more).strings(), ScsSolver(strings).strings());
  }
}

TEST(ScsTest, ProjectionsWithAndWithoutDominanceHaveTheSameScs) {
  std::mt19937 rng(14);
  for (int trial = 0; trial < 200; ++trial) {
    const CellTree t = testing::RandomTree(rng, 3, 1 + rng() % 6, 5);
    const testing::CellList cells = {0, 2};
    Strings raw;  // every leaf's projection, nothing removed
    for (const CellString& p : TreePaths(t)) {
      CellString s;
      for (CellId c : p) {
        if (c == CellId(0) || c == CellId(2)) s.push_back(c);
      }
      raw.push_back(s);
    }
    ASSERT_EQ(BruteForceScs(raw), ShortestCommonSupersequence(ProjectPaths(t, cells)).lower_bound);
  }
}

TEST(ScsTest, BudgetAgainstBruteForce) {
  std::mt19937 rng(15);
  int yes = 0, no = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Strings strings = RandomStrings(rng, 3, 1 + rng() % 4, 4);
    std::vector<std::uint32_t> budget(3);
    for (auto& b : budget) b = rng() % 4;
    const ScsSolver solver(strings);
    const BudgetResult r = solver.FitsBudget(budget);
    const bool expected = BruteForceFits(strings, budget);
    ASSERT_NE(r.answer, Realisability::kUnknown);
    ASSERT_EQ(r.answer == Realisability::kRealisable, expected) << trial;
    if (expected) {
      ++yes;
      ASSERT_TRUE(CoversAll(r.witness, strings));
      for (CellId c : CellRange(3)) {
        ASSERT_LE(std::count(r.witness.begin(), r.witness.end(), c), budget[c.value()]);
      }
    } else {
      ++no;
    }
  }
  EXPECT_GT(yes, 50);
  EXPECT_GT(no, 50);
}

TEST(ScsTest, BudgetsOfTheCrossedPair) {
  // A B and B A: A B A and B A B are the shortest; A B needs a second A or a second B.
  const ScsSolver s({{A, B}, {B, A}});
  EXPECT_EQ(s.FitsBudget({1, 1}).answer, Realisability::kNotRealisable);
  EXPECT_EQ(s.FitsBudget({2, 1}).answer, Realisability::kRealisable);
  EXPECT_EQ(s.FitsBudget({1, 2}).answer, Realisability::kRealisable);
  EXPECT_EQ(s.MostUseful(A), 2u);
  EXPECT_EQ(s.MostUseful(C), 0u);
  ScsLimits tiny;
  tiny.max_states = 1;
  EXPECT_EQ(ScsSolver({{A, B, C}, {C, B, A}, {B, A, C}}).FitsBudget({2, 2, 2}, tiny).answer,
            Realisability::kUnknown);
}

TEST(ScsTest, ManySymbolsAndLongStrings) {
  // 300 distinct symbols, one string each way: the reverse needs 2n - 1.
  CellString up, down;
  for (CellId c : CellRange(300)) up.push_back(c), down.insert(down.begin(), c);
  const ScsResult r = ShortestCommonSupersequence({up, down});
  EXPECT_GE(r.lower_bound, 300u);
  EXPECT_LE(r.lower_bound, 599u);
  // A string longer than 255.
  CellString alternating;
  for (int i = 0; i < 600; ++i) alternating.push_back(CellId(i % 2));
  const ScsResult l = ShortestCommonSupersequence({alternating, {C}});
  EXPECT_TRUE(l.exact);
  EXPECT_EQ(l.lower_bound, 601u);
}

}  // namespace
}  // namespace raycell
