#include "graph/optimum.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <queue>
#include <sstream>

#include "base/check.h"
#include "graph/peel.h"
#include "graph/schedule.h"

// Why the search is exact.
//
// States and moves. A state is the set of processed nodes; it always contains the root and
// is downward closed (a node is processed only after its parent). A move on cell c processes
// every node of c whose parent is processed. That is exactly how DESIGN.md runs a schedule,
// so the paths from the start state are the schedules, entry for entry, once entries that
// process nothing are dropped (dropping them keeps a schedule feasible and makes it shorter).
// Taking all available nodes of c is also never worse than taking some: running any schedule
// from a superset state S' of S keeps, entry by entry, a superset of what the run from S has
// processed (a node processed from S has its parent processed from S, hence from S'), so
// every schedule that finishes from S finishes from S'. Processing more now only enables more
// later.
//
// Heuristic. remgen(n), for an unprocessed node n, is the number of unprocessed nodes of
// cell(n) on the path from the processed part to n, inclusive; h(S) = sum over cells c of
// the largest remgen of a node of c (the bound of the remaining forest; h = 0 exactly at the
// goal). Admissible: one fetch of c lowers remgen of a node of c by at most one (the path's
// nodes of c are processed top-down, at most one per fetch, since two nodes of c on one path
// cannot both have a processed parent), so a node with remgen g needs g more fetches of c;
// and fetches of different cells are different entries.
// Consistent (h(S) <= 1 + h(S') for a move S -> S' on c): the move processes only nodes of
// c, so remgen of every node of another cell is unchanged (it counts only nodes of its own
// cell), and remgen of a node of c drops by one if the first node of c on its remaining path
// was processed, else stays. So the term of c drops by at most one and the others stay.
// With unit move costs, A* with a consistent heuristic never reopens a closed state and the
// first goal taken from the open list has the fewest fetches.
//
// Incumbent. Peel's schedule is feasible, of length P. Any state on a schedule of length
// L < P has g + h <= L < P (admissibility), so states with g + h >= P are pruned without
// losing any schedule shorter than P. If the open list runs empty, none exists and P is
// optimal.
//
// Determinism. Moves are generated in increasing cell order and the open list is ordered by
// (f, larger g first, state creation order): no ties depend on addresses or hashing.

namespace raycell {

const char* ToString(OptimumResult::Status status) {
  switch (status) {
    case OptimumResult::kOptimal:
      return "optimal";
    case OptimumResult::kUnknown:
      return "unknown";
    case OptimumResult::kTooLarge:
      return "too large";
  }
  return "?";
}

std::string OptimumResult::ToString() const {
  std::ostringstream s;
  s << raycell::ToString(status);
  if (status == kOptimal) s << " " << length;
  s << " (";
  if (status == kOptimal) {
    s << "schedule";
    for (CellId c : schedule) s << " " << c;
    s << "; ";
  }
  s << states_expanded << " states, " << seconds << " s): " << reason;
  return s.str();
}

namespace {

using Word = std::uint64_t;
using StateId = std::uint32_t;
constexpr StateId kNoState = std::numeric_limits<StateId>::max();

bool Test(const Word* bits, NodeId n) { return (bits[n / 64] >> (n % 64)) & 1; }
void Set(Word* bits, NodeId n) { bits[n / 64] |= Word{1} << (n % 64); }

std::uint64_t Mix(std::uint64_t x) {  // splitmix64's finalizer
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t Hash(const Word* bits, std::size_t words) {
  std::uint64_t h = words;
  for (std::size_t i = 0; i < words; ++i) h = Mix(h ^ bits[i]);
  return h;
}

// What the search needs of the tree, in flat arrays.
struct TreeIndex {
  std::vector<CellId> cell;
  std::vector<NodeId> parent;
  // The nearest proper ancestor with the same cell, or kNoNode.
  std::vector<NodeId> same_cell_above;
  std::vector<std::vector<NodeId>> cell_nodes;  // increasing ids, so ancestors come first

  static TreeIndex Create(const CellTree& tree) {
    TreeIndex t;
    t.cell.resize(tree.size(), kNoCell);
    t.parent.resize(tree.size(), kNoNode);
    t.same_cell_above.resize(tree.size(), kNoNode);
    t.cell_nodes.resize(tree.cell_count());
    for (NodeId n = 1; n < tree.size(); ++n) {
      t.cell[n] = tree.cell(n);
      t.parent[n] = tree.parent(n);
      t.same_cell_above[n] = SameCellAbove(tree, n);
      t.cell_nodes[t.cell[n]].push_back(n);
    }
    return t;
  }

  static NodeId SameCellAbove(const CellTree& tree, NodeId n) {
    NodeId a = tree.parent(n);
    while (a != kRootNode && tree.cell(a) != tree.cell(n)) a = tree.parent(a);
    return a == kRootNode ? kNoNode : a;
  }
};

// Every state created, in creation order, with a hash table over their bitsets.
class StateStore {
 public:
  explicit StateStore(std::size_t words) : words_(words), table_(1024, kNoState) {}

  std::size_t size() const { return g_.size(); }
  const Word* bits(StateId s) const { return &bits_[s * words_]; }
  std::uint32_t g(StateId s) const { return g_[s]; }
  std::uint32_t h(StateId s) const { return h_[s]; }
  bool closed(StateId s) const { return closed_[s]; }
  void Close(StateId s) { closed_[s] = true; }
  // Moves from the start state to `s`, in order.
  std::vector<CellId> PathTo(StateId s) const {
    std::vector<CellId> path;
    for (; parent_[s] != kNoState; s = parent_[s]) path.push_back(move_[s]);
    std::reverse(path.begin(), path.end());
    return path;
  }
  // The state with these bits, if stored, else kNoState.
  StateId Find(const Word* bits, std::uint64_t hash) const {
    for (std::size_t i = hash & (table_.size() - 1);; i = (i + 1) & (table_.size() - 1)) {
      const StateId s = table_[i];
      if (s == kNoState) return kNoState;
      if (hash_[s] == hash && std::equal(bits, bits + words_, this->bits(s))) return s;
    }
  }
  StateId Add(const Word* bits, std::uint64_t hash, std::uint32_t h) {
    const auto s = static_cast<StateId>(size());
    RAYCELL_CHECK_LT(size(), std::size_t{kNoState});
    bits_.insert(bits_.end(), bits, bits + words_);
    hash_.push_back(hash);
    g_.push_back(0), h_.push_back(h), parent_.push_back(kNoState), move_.push_back(kNoCell);
    closed_.push_back(false);
    if (2 * size() > table_.size()) Rehash(2 * table_.size());
    Place(s);
    return s;
  }
  void Reach(StateId s, std::uint32_t g, StateId parent, CellId move) {
    g_[s] = g, parent_[s] = parent, move_[s] = move;
  }
  std::size_t bytes() const {
    return size() * (words_ * sizeof(Word) + sizeof(std::uint64_t) + 4 * 4) +
           table_.size() * sizeof(StateId);
  }

 private:
  void Place(StateId s) {
    std::size_t i = hash_[s] & (table_.size() - 1);
    while (table_[i] != kNoState) i = (i + 1) & (table_.size() - 1);
    table_[i] = s;
  }
  void Rehash(std::size_t slots) {
    table_.assign(slots, kNoState);
    for (StateId s = 0; s < size(); ++s) Place(s);
  }

  std::size_t words_;
  std::vector<Word> bits_;
  std::vector<std::uint64_t> hash_;
  std::vector<std::uint32_t> g_, h_;
  std::vector<StateId> parent_;
  std::vector<CellId> move_;
  std::vector<bool> closed_;
  std::vector<StateId> table_;  // open addressing, power-of-two size, at most half full
};

struct OpenEntry {
  std::uint32_t f, g;
  StateId state;
  // std::priority_queue pops the largest: the smallest f, then the largest g, then the
  // oldest state.
  bool operator<(const OpenEntry& o) const {
    if (f != o.f) return f > o.f;
    if (g != o.g) return g < o.g;
    return state > o.state;
  }
};

struct SearchOutcome {
  StateId goal = kNoState;  // a goal state with fewest fetches, if one below the incumbent
  std::string stopped;      // the limit that stopped the search, if one did
  std::uint64_t expanded = 0;
};

class Search {
 public:
  using Clock = std::chrono::steady_clock;

  Search(const CellTree& tree, const OptimumLimits& limits, std::uint64_t incumbent,
         Clock::time_point start)
      : t_(TreeIndex::Create(tree)),
        limits_(limits),
        incumbent_(incumbent),
        start_(start),
        words_((tree.size() + 63) / 64),
        store_(words_),
        cur_(words_),
        next_(words_),
        remgen_(tree.size(), 0),
        available_(tree.cell_count()) {}

  SearchOutcome Run() {
    Set(cur_.data(), kRootNode);
    Offer(cur_.data(), StartHeuristic(), 0, kNoState, kNoCell);
    SearchOutcome out;
    while (!open_.empty() && out.stopped.empty()) {
      const OpenEntry e = open_.top();
      open_.pop();
      if (store_.closed(e.state) || e.g != store_.g(e.state)) continue;  // stale entry
      if (store_.h(e.state) == 0) {
        out.goal = e.state;
        break;
      }
      out.stopped = LimitReached(out.expanded);
      if (!out.stopped.empty()) break;
      store_.Close(e.state);
      ++out.expanded;
      Expand(e.state);
    }
    return out;
  }

  std::vector<CellId> PathTo(StateId s) const { return store_.PathTo(s); }

 private:
  std::string LimitReached(std::uint64_t expanded) const {
    std::ostringstream s;
    if (expanded >= limits_.max_states) {
      s << "state limit reached (max_states = " << limits_.max_states << ")";
    } else if (store_.bytes() + open_.size() * sizeof(OpenEntry) > limits_.max_bytes) {
      s << "memory limit reached (max_bytes = " << limits_.max_bytes << ")";
    } else if (expanded % 256 == 0 && Seconds() > limits_.max_seconds) {
      s << "time limit reached (max_seconds = " << limits_.max_seconds << ")";
    }
    return s.str();
  }

  double Seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  // Creates each successor of `s`: one per cell with an available node.
  void Expand(StateId s) {
    std::copy(store_.bits(s), store_.bits(s) + words_, cur_.begin());
    const std::uint32_t g = store_.g(s) + 1, h = store_.h(s);
    for (auto& nodes : available_) nodes.clear();
    for (NodeId n = 1; n < t_.cell.size(); ++n) {
      if (!Test(cur_.data(), n) && Test(cur_.data(), t_.parent[n])) {
        available_[t_.cell[n]].push_back(n);
      }
    }
    for (CellId c = 0; c < available_.size(); ++c) {
      if (available_[c].empty()) continue;
      next_ = cur_;
      for (NodeId n : available_[c]) Set(next_.data(), n);
      const std::uint32_t next_h = h - MaxRemgen(cur_.data(), c) + MaxRemgen(next_.data(), c);
      if (g + next_h < incumbent_) Offer(next_.data(), next_h, g, s, c);
    }
  }

  // Stores the state (or finds it) and queues it if reached with fewer fetches than before.
  void Offer(const Word* bits, std::uint32_t h, std::uint32_t g, StateId parent, CellId move) {
    const std::uint64_t hash = Hash(bits, words_);
    StateId s = store_.Find(bits, hash);
    if (s == kNoState) {
      s = store_.Add(bits, hash, h);
    } else if (store_.closed(s) || store_.g(s) <= g) {
      return;  // consistency: a closed state already has its fewest fetches
    }
    store_.Reach(s, g, parent, move);
    open_.push({g + h, g, s});
  }

  // The largest remgen of an unprocessed node of c (0 if none).
  std::uint32_t MaxRemgen(const Word* bits, CellId c) {
    std::uint32_t best = 0;
    for (NodeId n : t_.cell_nodes[c]) {
      if (Test(bits, n)) continue;
      const NodeId a = t_.same_cell_above[n];
      remgen_[n] = (a != kNoNode && !Test(bits, a)) ? remgen_[a] + 1 : 1;
      best = std::max(best, remgen_[n]);
    }
    return best;
  }

  std::uint32_t StartHeuristic() {
    std::uint32_t h = 0;
    for (CellId c = 0; c < t_.cell_nodes.size(); ++c) h += MaxRemgen(cur_.data(), c);
    return h;
  }

  const TreeIndex t_;
  const OptimumLimits limits_;
  const std::uint64_t incumbent_;
  const Clock::time_point start_;
  const std::size_t words_;
  StateStore store_;
  std::priority_queue<OpenEntry> open_;
  std::vector<Word> cur_, next_;                // scratch bitsets
  std::vector<std::uint32_t> remgen_;           // scratch, per node
  std::vector<std::vector<NodeId>> available_;  // scratch, per cell
};

std::string TooLarge(const CellTree& tree, const OptimumLimits& limits) {
  return "tree has " + std::to_string(tree.node_count()) +
         " nodes, more than max_nodes = " + std::to_string(limits.max_nodes);
}

// Fills the answer of a search that ran to its end.
void Conclude(const CellTree& tree, const Search& search, const SearchOutcome& outcome,
              const PeelResult& peel, OptimumResult& out) {
  const std::string sizes =
      "bound " + std::to_string(Bound(tree)) + ", Peel " + std::to_string(peel.schedule.size());
  if (!outcome.stopped.empty()) {
    out.status = OptimumResult::kUnknown;
    out.reason = outcome.stopped + "; " + sizes;
    return;
  }
  out.status = OptimumResult::kOptimal;
  if (outcome.goal == kNoState) {
    out.schedule = peel.schedule;
    out.reason = "no schedule is shorter than Peel's; " + sizes;
  } else {
    out.schedule = search.PathTo(outcome.goal);
    out.reason = "shorter than Peel's; " + sizes;
  }
  out.length = out.schedule.size();
  RAYCELL_CHECK(IsFeasible(tree, out.schedule));
}

}  // namespace

OptimumResult ExactOptimum(const CellTree& tree, const OptimumLimits& limits) {
  const auto start = Search::Clock::now();
  OptimumResult out;
  if (tree.node_count() > limits.max_nodes) {
    out.status = OptimumResult::kTooLarge;
    out.reason = TooLarge(tree, limits);
    return out;
  }
  const PeelResult peel = Peel(tree);
  if (peel.schedule.size() == Bound(tree)) {
    out.status = OptimumResult::kOptimal;
    out.schedule = peel.schedule;
    out.length = out.schedule.size();
    out.reason = "Peel's length equals the bound " + std::to_string(out.length);
  } else {
    Search search(tree, limits, peel.schedule.size(), start);
    const SearchOutcome outcome = search.Run();
    out.states_expanded = outcome.expanded;
    Conclude(tree, search, outcome, peel, out);
  }
  out.seconds = std::chrono::duration<double>(Search::Clock::now() - start).count();
  return out;
}

}  // namespace raycell
