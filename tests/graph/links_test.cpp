#include "graph/links.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "base/check.h"
#include "graph/dependency_graph.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::FromPaths;
using testing::RandomTree;

constexpr CellId A{0}, B{1}, C{2}, D{3}, E{4}, F{5};
using Schedule = testing::CellList;
using Links = std::vector<Link>;

// The node reached from the root along `path`.
NodeId At(const CellTree& t, const Schedule& path) {
  NodeId n = kRootNode;
  for (CellId c : path) n = t.FindChild(n, c);
  RAYCELL_CHECK(n != kNoNode);
  return n;
}

Link L(NodeId x, NodeId y) { return Link::Create(x, y); }
Link L(std::uint32_t x, std::uint32_t y) { return L(NodeId(x), NodeId(y)); }
// The link between nodes a and b as written, a < b.
Link N(std::uint32_t a, std::uint32_t b) { return {NodeId(a), NodeId(b)}; }

// ------------------------------------------------------------------- brute force

// Does some schedule realise every link? Breadth-first search over the sets of processed
// nodes (bit n - 1 for node n). A fetch of cell c processes a non-empty set S of the ready
// nodes of c (exact rule: any subset; greedy rule: all of them) and is allowed only when no
// link has exactly one end in S. Every step processes a node, so the search covers every
// schedule of up to `nodes` useful fetches. Trees of at most 16 nodes.
bool Realisable(const CellTree& t, const Links& links, bool greedy) {
  RAYCELL_CHECK_LE(t.node_count(), 16u);
  const auto bit = [](NodeId n) { return std::uint32_t{1} << (n.index() - 1); };
  const std::uint32_t all = (std::uint32_t{1} << t.node_count()) - 1;
  std::vector<bool> seen(all + 1, false);
  std::vector<std::uint32_t> queue{0};
  seen[0] = true;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::uint32_t done = queue[q];
    if (done == all) return true;
    for (CellId c : CellRange(t.cell_count())) {
      std::uint32_t ready = 0;
      for (NodeId n : t.nodes()) {
        const NodeId p = t.parent(n);
        if (t.cell(n) == c && !(done & bit(n)) && (p == kRootNode || (done & bit(p)))) {
          ready |= bit(n);
        }
      }
      // Non-empty subsets of `ready` (only `ready` itself under the greedy rule).
      for (std::uint32_t s = ready; s != 0; s = greedy ? 0 : (s - 1) & ready) {
        const bool closed = std::all_of(links.begin(), links.end(), [&](const Link& l) {
          return !(s & bit(l.a)) == !(s & bit(l.b));
        });
        if (closed && !seen[done | s]) seen[done | s] = true, queue.push_back(done | s);
      }
    }
  }
  return false;
}

// ------------------------------------------------------------------- random trees

// `count` seeded random trees with at most `max_nodes` nodes.
template <typename Fn>
void ForRandomTrees(int count, std::size_t max_nodes, Fn fn) {
  std::mt19937 rng(20020902);
  for (int i = 0; i < count;) {
    const std::uint32_t cells = 2 + rng() % 3;
    const int rays = 1 + static_cast<int>(rng() % (max_nodes <= 12 ? 5 : 14));
    const CellTree t = RandomTree(rng, cells, rays, max_nodes <= 12 ? 4 : 6);
    if (t.node_count() > max_nodes) continue;
    ++i;
    SCOPED_TRACE(t.ToString());
    fn(t, rng);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

// Every pair of distinct nodes of one cell, ancestor pairs included.
Links SameCellPairs(const CellTree& t) {
  Links out;
  for (NodeId a : t.nodes()) {
    for (NodeId b : t.nodes()) {
      if (a < b && t.cell(a) == t.cell(b)) out.push_back({a, b});
    }
  }
  return out;
}

Links RandomSubset(const Links& links, std::mt19937& rng, unsigned keep_percent) {
  Links out;
  for (const Link& l : links) {
    if (rng() % 100 < keep_percent) out.push_back(l);
  }
  return out;
}

// The largest number of links of `links` that are feasible together (exhaustive).
std::size_t LargestFeasibleSubset(const CellTree& t, const Links& links) {
  std::size_t best = 0;
  for (std::uint32_t m = 0; m < (1u << links.size()); ++m) {
    Links subset;
    for (std::size_t i = 0; i < links.size(); ++i) {
      if (m >> i & 1) subset.push_back(links[i]);
    }
    if (subset.size() > best && LinksFeasible(t, subset)) best = subset.size();
  }
  return best;
}

// Is some schedule of `length` entries over the tree's cells feasible? (exhaustive)
bool SomeScheduleOfLength(const CellTree& t, std::size_t length) {
  Schedule s(std::vector<CellId>(length, CellId(0)));
  for (;;) {
    if (IsFeasible(t, s)) return true;
    std::size_t i = 0;
    while (i < length && (++s[i]).value() == t.cell_count()) s[i++] = CellId(0);
    if (i == length) return false;
  }
}

// ------------------------------------------------------------- groups and links

// Paths A B and B A: nodes A1 -> B2, B3 -> A4. Schedule A B A: fetch 0 takes A1, fetch 1
// takes B2 and B3 together (one link), fetch 2 takes A4. 4 nodes - 1 link = 3 fetches.
TEST(LinksTest, GroupsAndLinksOfASchedule) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  ASSERT_EQ(t.node_count(), 4u);
  EXPECT_EQ(ScheduleGroups(t, {A, B, A}), (std::vector<std::int64_t>{-1, 0, 1, 1, 2}));
  EXPECT_EQ(ScheduleGroups(t, {CellId(9), B, A}), (std::vector<std::int64_t>{-1, 2, -1, 1, 2}));
  EXPECT_EQ(LinksOf(t, {A, B, A}), (Links{N(2, 3)}));
  EXPECT_EQ(LinksOf(t, {B, A, B}), (Links{N(1, 4)}));
  EXPECT_EQ(RunSchedule(t, {A, B, A}).useful_fetches, t.node_count() - 1);
  EXPECT_TRUE(LinksFeasible(t, {N(2, 3)}));
  EXPECT_TRUE(LinksFeasible(t, {N(1, 4)}));
  // Both links: A1 -> B2 ~ B3 -> A4 ~ A1 is a cycle; the two links conflict.
  EXPECT_FALSE(LinksFeasible(t, {N(2, 3), N(1, 4)}));
  EXPECT_TRUE(Conflict(t, N(2, 3), N(1, 4)));
  const LinkCandidates cand = CandidateLinks(t);
  EXPECT_EQ(cand.links, (Links{N(1, 4), N(2, 3)}));
  EXPECT_EQ(cand.conflicts, (std::vector<std::pair<std::size_t, std::size_t>>{{0, 1}}));
  EXPECT_EQ(cand.ToString(), "2 candidate links, 1 conflicts");
  EXPECT_EQ(L(4, 1).ToString(), "1-4");
}

// A group of k nodes gives a chain of k - 1 links: ten root children of one cell? Not in
// a trie; instead paths X c for X = 1..5 put five nodes of cell 0 under different parents,
// all processed by the one fetch of cell 0 after cells 1..5: links 6-7, 7-8, 8-9, 9-10.
TEST(LinksTest, GroupOfKNodesGivesKMinusOneLinks) {
  std::vector<Schedule> paths;
  for (std::uint32_t c = 1; c <= 5; ++c) paths.push_back({c, 0});
  const CellTree t = FromPaths(paths);
  const Schedule s{1, 2, 3, 4, 5, 0};
  const Links links = LinksOf(t, s);
  EXPECT_EQ(links.size(), 4u);
  for (const Link& l : links) EXPECT_EQ(t.cell(l.a), CellId(0)) << l;
  EXPECT_EQ(RunSchedule(t, s).useful_fetches, t.node_count() - links.size());
  EXPECT_TRUE(LinksFeasible(t, links));
}

// Path A B A: the link between A1 and its descendant A3 contracts to {A1 A3} -> B2 -> {A1 A3}.
TEST(LinksTest, AncestorLinkIsInfeasibleAndNoCandidate) {
  const CellTree t = FromPaths({{A, B, A}});
  EXPECT_FALSE(LinksFeasible(t, {N(1, 3)}));
  EXPECT_FALSE(ScheduleFromLinks(t, {N(1, 3)}).has_value());
  EXPECT_TRUE(CandidateLinks(t).links.empty());
  const Contraction k = ContractLinks(t, {N(1, 3)});
  EXPECT_EQ(k.classes(), 2u);
  EXPECT_EQ(k.class_of, (std::vector<std::uint32_t>{Contraction::kNoClass, 0, 1, 0}));
  EXPECT_EQ(k.class_cell, (testing::CellList{A, B}));
  EXPECT_EQ(boost::num_edges(k.graph), 2u);
}

TEST(LinksTest, DependencyGraphHasTreeEdgesWithoutTheRoot) {
  const CellTree t = FromPaths({{A, B, C}, {A, C}, {B}});
  const DependencyGraph g = BuildDependencyGraph(t);
  EXPECT_EQ(boost::num_vertices(g), t.node_count());
  EXPECT_EQ(boost::num_edges(g), t.node_count() - 2);  // two root children
  const auto order = TopologicalOrder(g);
  ASSERT_TRUE(order.has_value());
  std::vector<std::size_t> pos(t.size());
  for (std::size_t i = 0; i < order->size(); ++i) pos[NodeOf((*order)[i]).index()] = i;
  for (NodeId n : t.nodes()) {
    if (t.parent(n) != kRootNode) {
      EXPECT_LT(pos[t.parent(n).index()], pos[n.index()]);
    }
  }
}

TEST(LinksTest, EmptyTreeHasNoLinksAndAnEmptySchedule) {
  const CellTree t = FromPaths({});
  EXPECT_TRUE(LinksFeasible(t, {}));
  EXPECT_EQ(ScheduleFromLinks(t, {}), Schedule{});
  EXPECT_TRUE(LinksOf(t, {A}).empty());
  EXPECT_TRUE(CandidateLinks(t).links.empty());
  std::ostringstream dot;
  WriteDot(dot, t);
  EXPECT_NE(dot.str().find("digraph"), std::string::npos);
}

// ------------------------------------------------------------------------- chains

// The chain (docs/design.md §1, the paper's slides). Paths A B, B C, C A give
//   A1 -> B2,  B3 -> C4,  C5 -> A6
// and the links a = {A1, A6}, b = {B2, B3}, c = {C4, C5}. Any two are feasible: with a and b
// the contraction is C5 -> {A1 A6} -> {B2 B3} -> C4, acyclic (schedule C A B C), and the
// same holds for b, c (A B C A) and c, a (B C A B) by symmetry. All three close the chain
// {A} -> {B} (A1 -> B2), {B} -> {C} (B3 -> C4), {C} -> {A} (C5 -> A6): a cycle, so no
// schedule realises all three although no two of them conflict. Hence the bound (3: each
// cell at generation 1) is not reachable: the best is 6 nodes - 2 links = 4 fetches.
TEST(LinksChainTest, PairwiseFeasibleButNotTogether) {
  const CellTree t = FromPaths({{A, B}, {B, C}, {C, A}});
  ASSERT_EQ(t.node_count(), 6u);
  const Link a = L(At(t, {A}), At(t, {C, A})), b = L(At(t, {A, B}), At(t, {B})),
             c = L(At(t, {B, C}), At(t, {C}));
  EXPECT_EQ(a, L(1, 6));
  const Links all{a, b, c};
  for (const Link& x : all) {
    for (const Link& y : all) EXPECT_FALSE(Conflict(t, x, y)) << x << " " << y;
  }
  EXPECT_FALSE(LinksFeasible(t, all));
  EXPECT_FALSE(Realisable(t, all, false));
  EXPECT_EQ(ScheduleFromLinks(t, {a, b}), (Schedule{C, A, B, C}));
  EXPECT_TRUE(CandidateLinks(t).conflicts.empty());
  EXPECT_EQ(LargestFeasibleSubset(t, all), 2u);
  EXPECT_EQ(Bound(t), 3u);
  EXPECT_FALSE(SomeScheduleOfLength(t, 3));
  EXPECT_TRUE(SomeScheduleOfLength(t, 4));
}

// A longer chain A B, B C, C D, D A: the four links are infeasible together, yet every
// three of them are feasible (the chain must be closed to make a cycle).
TEST(LinksChainTest, LongerChainNeedsEveryLink) {
  const CellTree t = FromPaths({{A, B}, {B, C}, {C, D}, {D, A}});
  const Links all{L(At(t, {A}), At(t, {D, A})), L(At(t, {A, B}), At(t, {B})),
                  L(At(t, {B, C}), At(t, {C})), L(At(t, {C, D}), At(t, {D}))};
  EXPECT_FALSE(LinksFeasible(t, all));
  for (std::size_t skip = 0; skip < all.size(); ++skip) {
    Links three = all;
    three.erase(three.begin() + static_cast<std::ptrdiff_t>(skip));
    EXPECT_TRUE(LinksFeasible(t, three)) << "without " << all[skip];
  }
  EXPECT_TRUE(CandidateLinks(t).conflicts.empty());
}

// Several chains. (1) Two disjoint chains, over A B C and D E F: pairwise feasible, and the
// largest feasible subset drops one link per chain (6 - 2). (2) Two chains sharing a link:
// paths A B, B C, C A, B D, D A give A1 -> B2, B3 -> {C4, D5}, C6 -> A7, D8 -> A9 and the
// links {A1 A7}, {A1 A9}, {B2 B3}, {C4 C6}, {D5 D8}. Chain A -> B -> C -> A uses {A1 A7},
// {B2 B3}, {C4 C6}; chain A -> B -> D -> A uses {A1 A9}, {B2 B3}, {D5 D8}. Dropping the
// shared {B2 B3} breaks both, so 4 of 5 are feasible; dropping any other link leaves a chain.
TEST(LinksChainTest, LinksWithNoPairwiseConflictOnSeveralChainsAreInfeasibleTogether) {
  const CellTree two = FromPaths({{A, B}, {B, C}, {C, A}, {D, E}, {E, F}, {F, D}});
  Links disjoint;
  for (CellId x : {A, D}) {
    const CellId y(x.value() + 1), z(x.value() + 2);
    disjoint.push_back(L(At(two, {x}), At(two, {z, x})));
    disjoint.push_back(L(At(two, {x, y}), At(two, {y})));
    disjoint.push_back(L(At(two, {y, z}), At(two, {z})));
  }
  EXPECT_FALSE(LinksFeasible(two, disjoint));
  EXPECT_TRUE(CandidateLinks(two).conflicts.empty());
  EXPECT_EQ(LargestFeasibleSubset(two, disjoint), 4u);

  const CellTree t = FromPaths({{A, B}, {B, C}, {C, A}, {B, D}, {D, A}});
  ASSERT_EQ(t.node_count(), 9u);
  const Link shared = L(At(t, {A, B}), At(t, {B}));
  const Links all{L(At(t, {A}), At(t, {C, A})), L(At(t, {A}), At(t, {D, A})), shared,
                  L(At(t, {B, C}), At(t, {C})), L(At(t, {B, D}), At(t, {D}))};
  for (const Link& x : all) {
    for (const Link& y : all) EXPECT_FALSE(Conflict(t, x, y)) << x << " " << y;
  }
  EXPECT_FALSE(LinksFeasible(t, all));
  EXPECT_FALSE(Realisable(t, all, false));
  for (const Link& drop : all) {
    Links rest;
    std::copy_if(all.begin(), all.end(), std::back_inserter(rest),
                 [&](const Link& l) { return l != drop; });
    EXPECT_EQ(LinksFeasible(t, rest), drop == shared) << "without " << drop;
  }
}

// The greedy rule cannot realise every feasible link set (links.h). Paths A B and C A B D B:
//   A1 -> B2,  C3 -> A4 -> B5 -> D6 -> B7;  links {A1 A4} and {B2 B7}.
// Contraction: C3 -> {A1 A4} -> B5 -> D6 -> {B2 B7}, and {A1 A4} -> {B2 B7}: acyclic. A fetch
// may leave ready nodes behind: C, A (A1 A4), B (B5 only), D, B (B2 B7). Greedily, the A
// fetch that takes A1 and A4 makes B2 and B5 ready at once, so the next B takes both and B2
// comes before B7. ScheduleFromLinks still gives a feasible greedy schedule of 5 fetches.
TEST(LinksTest, GreedyRuleCannotRealiseEveryFeasibleLinkSet) {
  const CellTree t = FromPaths({{A, B}, {C, A, B, D, B}});
  const Links links{N(1, 4), N(2, 7)};
  EXPECT_TRUE(LinksFeasible(t, links));
  EXPECT_TRUE(Realisable(t, links, false));
  EXPECT_FALSE(Realisable(t, links, true));
  const auto s = ScheduleFromLinks(t, links);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(*s, (Schedule{C, A, B, D, B}));
  const ScheduleRun run = RunSchedule(t, *s);
  EXPECT_TRUE(run.feasible);
  EXPECT_EQ(run.useful_fetches, 5u);
}

TEST(LinksTest, CandidateLinksRejectsLargeTrees) {
  Schedule path;
  for (int i = 0; i < 70; ++i) path.push_back(i % 2 == 0 ? A : B);
  const CellTree t = FromPaths({path});
  EXPECT_THROW(CandidateLinks(t), InputError);
  try {
    CandidateLinks(t);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("70 nodes"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(CandidateLinks(FromPaths({Schedule(path.begin(), path.begin() + 64)})));
}

// ---------------------------------------------------------------------------- dot

// Lines of `text` that contain `needle` (std::regex is avoided: GCC 12 warns inside it
// in sanitizer builds).
std::size_t CountLines(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) count += line.find(needle) != line.npos ? 1 : 0;
  return count;
}

// Node lines: "<id>[label=\"cell...".
std::size_t CountNodeLines(const std::string& text) {
  std::istringstream in(text);
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) {
    const std::size_t digits = line.find_first_not_of("0123456789");
    count += digits > 0 && digits != line.npos && line.compare(digits, 12, "[label=\"cell") == 0;
  }
  return count;
}

TEST(LinksDotTest, DotOfTwoCrossedPathsAndALinkIsTheGoldenText) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  std::ostringstream out;
  WriteDot(out, t, {N(2, 3)});
  EXPECT_EQ(out.str(),
            "digraph G {\n"
            "node [style=filled, shape=box];\n"
            "1[label=\"cell0 g1 e1\", fillcolor=\"#8dd3c7\"];\n"
            "2[label=\"cell1 g1 e1\", fillcolor=\"#ffffb3\"];\n"
            "3[label=\"cell1 g1 e1\", fillcolor=\"#ffffb3\"];\n"
            "4[label=\"cell0 g1 e1\", fillcolor=\"#8dd3c7\"];\n"
            "1->2 [style=solid];\n"
            "2->3 [style=dashed, dir=none, constraint=false];\n"
            "3->4 [style=solid];\n"
            "}\n");
}

TEST(LinksDotTest, OneNodeLinePerNodeOneDashedEdgePerLink) {
  std::mt19937 rng(5);
  const CellTree t = RandomTree(rng, 14, 30, 6);  // more cells than palette colours
  const Links links = LinksOf(t, Peel(t).schedule);
  ASSERT_FALSE(links.empty());
  std::ostringstream first, second;
  WriteDot(first, t, links);
  WriteDot(second, t, links);
  const std::string dot = first.str();
  EXPECT_EQ(dot, second.str());
  EXPECT_EQ(CountNodeLines(dot), t.node_count());
  EXPECT_EQ(CountLines(dot, "style=dashed, dir=none, constraint=false"), links.size());
  std::size_t tree_edges = 0;
  for (NodeId n : t.nodes()) tree_edges += t.parent(n) != kRootNode ? 1 : 0;
  EXPECT_EQ(CountLines(dot, "->"), tree_edges + links.size());
  EXPECT_EQ(CountLines(dot, "style=solid"), tree_edges);
  for (NodeId n : t.nodes()) {
    if (t.cell(n) == CellId(12)) {
      EXPECT_NE(dot.find(std::to_string(n.index()) + "[label=\"cell12 g"), std::string::npos);
      EXPECT_NE(dot.find("fillcolor=\"#8dd3c7\"]",
                         dot.find(std::to_string(n.index()) + "[label=\"cell12")),
                std::string::npos);
    }
  }
  if (std::system("command -v dot >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "graphviz `dot` not installed: DOT syntax not checked by dot";
  }
  const std::string path = ::testing::TempDir() + "links_test.dot";
  std::ofstream(path) << dot;
  EXPECT_EQ(std::system(("dot -Tsvg " + path + " -o /dev/null").c_str()), 0);
  std::remove(path.c_str());
}

// --------------------------------------------------------------------- properties

TEST(LinksPropertyTest, PeelLinksAreFeasibleAndCountFetches) {
  ForRandomTrees(3000, 64, [](const CellTree& t, std::mt19937& rng) {
    const Schedule s = Peel(t).schedule;
    const Links links = LinksOf(t, s);
    const ScheduleRun run = RunSchedule(t, s);
    ASSERT_TRUE(run.feasible);
    EXPECT_EQ(run.useful_fetches, t.node_count() - links.size());
    EXPECT_EQ(ContractLinks(t, links).classes(), run.useful_fetches);
    EXPECT_TRUE(LinksFeasible(t, links));
    for (int r = 0; r < 3; ++r) EXPECT_TRUE(LinksFeasible(t, RandomSubset(links, rng, 60)));
    const auto rebuilt = ScheduleFromLinks(t, links);
    ASSERT_TRUE(rebuilt.has_value());
    const ScheduleRun again = RunSchedule(t, *rebuilt);
    EXPECT_TRUE(again.feasible);
    EXPECT_LE(again.useful_fetches, run.useful_fetches);
  });
}

// Any cell sequence, feasible or not: its greedy links are feasible and every group is one
// cell; when it is feasible, fetches = nodes - links.
TEST(LinksPropertyTest, LinksOfRandomSchedulesAreFeasible) {
  ForRandomTrees(3000, 64, [](const CellTree& t, std::mt19937& rng) {
    Schedule s(std::vector<CellId>(rng() % (2 * t.node_count() + 1)));
    for (CellId& c : s) c = CellId(rng() % (t.cell_count() + 1));
    const Links links = LinksOf(t, s);
    const ScheduleRun run = RunSchedule(t, s);
    EXPECT_TRUE(LinksFeasible(t, links));
    EXPECT_EQ(run.useful_fetches, run.processed_nodes - links.size());
    const auto fetch = ScheduleGroups(t, s);
    for (const Link& l : links) {
      EXPECT_EQ(fetch[l.a.index()], fetch[l.b.index()]);
      EXPECT_EQ(t.cell(l.a), s[static_cast<std::size_t>(fetch[l.a.index()])]);
    }
  });
}

// On tiny trees: LinksFeasible agrees exactly with the exhaustive search over schedules
// that may leave ready nodes for later; the greedy search realises a subset of these.
TEST(LinksPropertyTest, FeasibilityMatchesBruteForce) {
  int greedy_gaps = 0, feasible_sets = 0;
  ForRandomTrees(3000, 12, [&](const CellTree& t, std::mt19937& rng) {
    const Links pairs = SameCellPairs(t);
    for (int r = 0; r < 4; ++r) {
      const Links links = RandomSubset(pairs, rng, 10 + 25 * r);
      const bool feasible = LinksFeasible(t, links);
      ASSERT_EQ(feasible, Realisable(t, links, false)) << ::testing::PrintToString(links);
      const bool greedy = Realisable(t, links, true);
      EXPECT_TRUE(!greedy || feasible) << ::testing::PrintToString(links);
      greedy_gaps += feasible && !greedy ? 1 : 0;
      feasible_sets += feasible ? 1 : 0;
      const auto s = ScheduleFromLinks(t, links);
      ASSERT_EQ(s.has_value(), feasible);
      if (!s) continue;
      const ScheduleRun run = RunSchedule(t, *s);
      EXPECT_TRUE(run.feasible);
      EXPECT_LE(run.useful_fetches, ContractLinks(t, links).classes());
    }
  });
  std::printf("%d feasible link sets, %d not realisable under the greedy rule\n", feasible_sets,
              greedy_gaps);
}

// CandidateLinks: exactly the same-cell pairs that are feasible alone, and its fast conflict
// test agrees with Conflict (contraction) on every pair; on tiny trees also with brute force.
TEST(LinksPropertyTest, CandidatesAndConflictsMatchContraction) {
  ForRandomTrees(400, 40, [](const CellTree& t, std::mt19937&) {
    const LinkCandidates cand = CandidateLinks(t);
    Links feasible_pairs;
    for (const Link& l : SameCellPairs(t)) {
      if (LinksFeasible(t, {l})) feasible_pairs.push_back(l);
    }
    ASSERT_EQ(cand.links, feasible_pairs);
    std::vector<std::pair<std::size_t, std::size_t>> expected;
    for (std::size_t i = 0; i < cand.links.size(); ++i) {
      for (std::size_t j = i + 1; j < cand.links.size(); ++j) {
        if (Conflict(t, cand.links[i], cand.links[j])) expected.emplace_back(i, j);
      }
    }
    EXPECT_EQ(cand.conflicts, expected);
  });
  ForRandomTrees(1000, 10, [](const CellTree& t, std::mt19937&) {
    const LinkCandidates cand = CandidateLinks(t);
    std::size_t k = 0;
    for (std::size_t i = 0; i < cand.links.size(); ++i) {
      for (std::size_t j = i + 1; j < cand.links.size(); ++j) {
        const bool conflict = k < cand.conflicts.size() && cand.conflicts[k] == std::pair{i, j};
        k += conflict ? 1 : 0;
        EXPECT_EQ(conflict, !Realisable(t, {cand.links[i], cand.links[j]}, false));
      }
    }
  });
}

}  // namespace
}  // namespace raycell
