#include "search/optimum.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <queue>
#include <sstream>
#include <utility>

#include "base/check.h"
#include "graph/peel.h"
#include "graph/schedule.h"

// Why the search is exact.
//
// States and moves. A state is the set of processed nodes; it is downward closed (a node is
// processed only after its parent). A move on cell c processes every node of c whose parent
// is processed. That is exactly how docs/design.md runs a schedule, so the paths from the start
// state are the schedules, entry for entry, once entries that process nothing are dropped
// (dropping them keeps a schedule feasible and makes it shorter). Taking all available nodes
// of c is also never worse than taking some: running any schedule from a superset state S'
// of S keeps, entry by entry, a superset of what the run from S has processed (a node
// processed from S has its parent processed from S, hence from S'), so every schedule that
// finishes from S finishes from S'. Processing more now only enables more later.
//
// Heuristic. The cells are split into groups: pairs {a, b} chosen at the start (below) and
// single cells. h(S) = sum over groups G of h_G(S):
//  - single cell c: the largest remgen of an unprocessed node of c, where remgen(n) is the
//    number of unprocessed nodes of c on the path from the processed part to n, inclusive
//    (the bound of the remaining forest for c). A fetch of c lowers the remgen of a node of
//    c by at most one (the path's nodes of c are processed top-down, at most one per fetch,
//    since two nodes of c on one path cannot both have a processed parent), so at least
//    h_c(S) more fetches of c are needed.
//  - pair {a, b}: the length of the shortest schedule of the projection of the unprocessed
//    forest onto {a, b} (every node of a or b, its parent the nearest ancestor of a or b),
//    computed exactly by this same search, memoised. The fetches of a and b of any schedule
//    that finishes from S, run on the projection, finish it (each node's projected parent is
//    processed no later than its real parent), so they are at least h_G(S).
// Groups are disjoint and every entry fetches one cell, so h is admissible. It is also
// consistent (h(S) <= 1 + h(S') for a move S -> S' on c): only the group of c changes; a
// single cell's term drops by at most one (above); for a pair, prepending c to a shortest
// projected schedule from S' gives a projected schedule from S (the projected move on c
// processes at least the nodes the real move did, and more processed never hurts), so
// h_G(S) <= 1 + h_G(S'). With the optional extra bound (consistent by contract), the maximum
// of consistent heuristics is consistent. With a consistent heuristic A* never reopens a
// closed state and the first goal taken from the open list has the fewest fetches; the
// search reopens states anyway when reached with fewer fetches, so a heuristic that is only
// admissible (a pair value that hit its limit, or a faulty extra bound) costs time, not
// exactness.
//
// Pairs are chosen once: for every pair of cells (when there are at most kMaxPairCells
// cells), the gain h_{a,b} - maxGen(a) - maxGen(b) at the start; pairs with positive gain
// are matched greedily, largest gain first (lowest cells on ties).
//
// Incumbent. A feasible schedule of length P is known. Any state on a schedule of length
// L < P has g + h <= L < P (admissibility), so states with g + h >= P are pruned without
// losing any schedule shorter than P. If the open list runs empty, none exists and P is
// optimal.
//
// Bracket. While the search runs, some state on an optimal path is open with its optimal
// g (the usual A* argument), so the smallest f on the open list is a lower bound on the
// optimum; a search stopped by a limit reports it.
//
// Determinism. Moves are generated in increasing cell order and the open list is ordered by
// (f, larger g first, state creation order or, with a seed, a seeded hash of it): no ties
// depend on addresses. Different seeds may return different shortest schedules.

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
  if (status == kUnknown) s << " in [" << lower << ", " << upper << "]";
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

using Index = CellForest::Index;
using StateId = BitsTable::Id;
constexpr StateId kNoState = BitsTable::kNone;
using Clock = std::chrono::steady_clock;

// The largest remgen of an unprocessed node of c (0 if none); see "Heuristic".
std::uint32_t MaxRemgen(const CellForest& f, const Word* bits, CellId c,
                        std::vector<std::uint32_t>& remgen) {
  std::uint32_t best = 0;
  for (Index n : f.nodes_of(c)) {
    if (TestBit(bits, n)) continue;
    const Index a = f.same_cell_above(n);
    remgen[n] = (a != CellForest::kNone && !TestBit(bits, a)) ? remgen[a] + 1 : 1;
    best = std::max(best, remgen[n]);
  }
  return best;
}

// The projection of a forest onto two cells, and the memoised length of the shortest
// schedule of its unprocessed part.
class PairProjection {
 public:
  static constexpr std::uint64_t kMaxStates = 200'000;  // per memo miss

  PairProjection(const CellForest& f, CellId a, CellId b) {
    std::merge(f.nodes_of(a).begin(), f.nodes_of(a).end(), f.nodes_of(b).begin(),
               f.nodes_of(b).end(), std::back_inserter(nodes_));
    std::vector<Index> parent(nodes_.size());
    std::vector<CellId> cells(nodes_.size());
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      cells[i] = f.cell(nodes_[i]);
      Index p = f.parent(nodes_[i]);
      while (p != CellForest::kNone && f.cell(p) != a && f.cell(p) != b) p = f.parent(p);
      parent[i] = p == CellForest::kNone ? CellForest::kNone : Local(p);
    }
    forest_ = CellForest::FromArrays(parent, cells);
    words_ = WordsFor(nodes_.size());
    memo_ = BitsTable(words_);
    scratch_.resize(words_);
  }

  // h_G of the state `bits` of the full forest. `exact` is cleared when a memo miss hit its
  // limit (the value is then only a lower bound).
  std::uint32_t Value(const Word* bits, bool& exact) {
    std::fill(scratch_.begin(), scratch_.end(), 0);
    std::vector<Index> left;
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      if (TestBit(bits, nodes_[i])) {
        SetBit(scratch_, i);
      } else {
        left.push_back(Index(i));
      }
    }
    if (left.empty()) return 0;
    const std::uint64_t hash = HashBits(scratch_.data(), words_);
    const StateId s = memo_.Find(scratch_.data(), hash);
    if (s != kNoState) return value_[s];
    ShorterOptions o;
    o.limits.max_states = kMaxStates;
    o.limits.max_seconds = std::numeric_limits<double>::infinity();
    const ShorterResult r = FindShorter(CellForest::Sub(forest_, left), o);
    expanded_ += r.expanded;
    if (r.status != ShorterResult::kFound) exact = false;
    const auto v = std::uint32_t(r.status == ShorterResult::kFound ? r.schedule.size() : r.lower);
    memo_.Add(scratch_.data(), hash);
    value_.push_back(v);
    return v;
  }

  std::size_t bytes() const { return memo_.bytes() + value_.size() * 4; }
  std::uint64_t expanded() const { return expanded_; }

 private:
  Index Local(Index n) const {
    return Index(std::lower_bound(nodes_.begin(), nodes_.end(), n) - nodes_.begin());
  }

  std::vector<Index> nodes_;  // forest nodes of a and b, increasing
  CellForest forest_;         // their projection
  std::size_t words_ = 0;
  BitsTable memo_{1};
  std::vector<std::uint32_t> value_;
  std::vector<Word> scratch_;
  std::uint64_t expanded_ = 0;
};

// h = sum over groups; see "Heuristic".
class Heuristic {
 public:
  static constexpr std::size_t kMaxPairCells = 64;

  Heuristic(const CellForest& f, bool pairs) : f_(f), group_of_(f.cell_count(), kSingle) {
    remgen_.resize(f.size());
    if (pairs && f.cells().size() <= kMaxPairCells) ChoosePairs();
  }

  std::uint32_t Start(const Word* bits) {
    std::uint32_t h = 0;
    for (CellId c : f_.cells()) {
      if (group_of_[c.value()] == kSingle) h += MaxRemgen(f_, bits, c, remgen_);
    }
    for (PairProjection& p : pairs_) h += p.Value(bits, exact_);
    return h;
  }

  // h of `after`, a move on c from `before` whose h is h.
  std::uint32_t Child(std::uint32_t h, const Word* before, const Word* after, CellId c) {
    if (group_of_[c.value()] == kSingle) {
      return h - MaxRemgen(f_, before, c, remgen_) + MaxRemgen(f_, after, c, remgen_);
    }
    PairProjection& p = pairs_[group_of_[c.value()]];
    return h - p.Value(before, exact_) + p.Value(after, exact_);
  }

  std::size_t bytes() const {
    std::size_t b = 0;
    for (const PairProjection& p : pairs_) b += p.bytes();
    return b;
  }
  std::size_t pairs() const { return pairs_.size(); }

 private:
  static constexpr std::uint32_t kSingle = std::numeric_limits<std::uint32_t>::max();

  void ChoosePairs() {
    struct Candidate {
      std::int64_t gain;
      CellId a, b;
    };
    std::vector<Candidate> candidates;
    const std::vector<Word> none(WordsFor(f_.size()), 0);
    const auto& max_gen = f_.max_generations();
    const std::vector<CellId>& cells = f_.cells();
    std::vector<PairProjection> all;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      for (std::size_t j = i + 1; j < cells.size(); ++j) {
        PairProjection p(f_, cells[i], cells[j]);
        bool exact = true;
        const std::int64_t gain = std::int64_t(p.Value(none.data(), exact)) -
                                  max_gen[cells[i].value()] - max_gen[cells[j].value()];
        if (exact && gain > 0) candidates.push_back({gain, cells[i], cells[j]});
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& x, const Candidate& y) { return x.gain > y.gain; });
    for (const Candidate& c : candidates) {
      if (group_of_[c.a.value()] != kSingle || group_of_[c.b.value()] != kSingle) continue;
      group_of_[c.a.value()] = group_of_[c.b.value()] = std::uint32_t(pairs_.size());
      pairs_.emplace_back(f_, c.a, c.b);
    }
  }

  const CellForest& f_;
  std::vector<std::uint32_t> group_of_;  // per cell: kSingle or an index into pairs_
  std::vector<PairProjection> pairs_;
  std::vector<std::uint32_t> remgen_;  // scratch, per node
  bool exact_ = true;
};

struct OpenEntry {
  std::uint32_t f, g;
  std::uint64_t tie;  // the state's id, or a seeded hash of it
  StateId state;
  // std::priority_queue pops the largest: the smallest f, then the largest g, then the
  // smallest tie (the oldest state without a seed).
  bool operator<(const OpenEntry& o) const {
    if (f != o.f) return f > o.f;
    if (g != o.g) return g < o.g;
    return tie > o.tie;
  }
};

class Search {
 public:
  Search(const CellForest& f, const ShorterOptions& o)
      : f_(f),
        o_(o),
        start_(Clock::now()),
        words_(WordsFor(f.size())),
        store_(words_),
        heuristic_(f, o.pair_heuristic),
        cur_(words_),
        next_(words_) {}

  ShorterResult Run() {
    ShorterResult out;
    const std::uint32_t own = heuristic_.Start(cur_.data());
    const std::uint32_t h = o_.extra_bound ? std::max(own, o_.extra_bound(f_, cur_.data())) : own;
    if (o_.upper != 0 && h >= o_.upper) {
      out.status = ShorterResult::kNone;
      out.lower = o_.upper;
      return out;
    }
    Offer(cur_.data(), own, h, kNoState, kNoCell);
    StateId goal = kNoState;
    while (!open_.empty()) {
      const OpenEntry e = open_.top();
      if (closed_[e.state] || e.g != g_[e.state]) {  // stale entry
        open_.pop();
        continue;
      }
      if (own_[e.state] == 0) {
        goal = e.state;
        break;
      }
      out.stopped = LimitReached(out.expanded);
      if (!out.stopped.empty()) break;
      open_.pop();
      closed_[e.state] = true;
      ++out.expanded;
      Expand(e.state);
    }
    out.bytes = peak_bytes_;
    out.work = work_;
    if (goal != kNoState) {
      out.status = ShorterResult::kFound;
      out.schedule = PathTo(goal);
      out.lower = out.schedule.size();
    } else if (out.stopped.empty()) {
      out.status = ShorterResult::kNone;
      out.lower = o_.upper;
    } else {
      out.status = ShorterResult::kStopped;
      out.lower = open_.top().f;  // the smallest f: see "Bracket"
    }
    return out;
  }

 private:
  std::size_t Bytes() const {
    return store_.bytes() + g_.size() * (3 * 4 + sizeof(CellId) + 1) +
           open_.size() * sizeof(OpenEntry) + heuristic_.bytes();
  }

  std::string LimitReached(std::uint64_t expanded) {
    std::ostringstream s;
    const std::size_t bytes = Bytes();
    peak_bytes_ = std::max(peak_bytes_, bytes);
    if (expanded >= o_.limits.max_states) {
      s << "state limit reached (max_states = " << o_.limits.max_states << ")";
    } else if (bytes > o_.limits.max_bytes) {
      s << "memory limit reached (max_bytes = " << o_.limits.max_bytes << ")";
    } else if (expanded % 256 == 0 && std::chrono::duration<double>(Clock::now() - start_).count() >
                                          o_.limits.max_seconds) {
      s << "time limit reached (max_seconds = " << o_.limits.max_seconds << ")";
    }
    return s.str();
  }

  // Creates each successor of `s`: one per cell with an available node.
  void Expand(StateId s) {
    std::copy(store_.bits(s), store_.bits(s) + words_, cur_.begin());
    const std::uint32_t g = g_[s] + 1, own = own_[s];
    work_ += f_.size();
    for (CellId c : f_.cells()) {
      ready_.clear();
      for (Index n : f_.nodes_of(c)) {
        const Index p = f_.parent(n);
        if (!TestBit(cur_.data(), n) && (p == CellForest::kNone || TestBit(cur_.data(), p))) {
          ready_.push_back(n);
        }
      }
      if (ready_.empty()) continue;
      next_ = cur_;
      for (Index n : ready_) SetBit(next_, n);
      work_ += 2 * (words_ + f_.nodes_of(c).size());
      const std::uint32_t next_own = heuristic_.Child(own, cur_.data(), next_.data(), c);
      const std::uint32_t h =
          o_.extra_bound ? std::max(next_own, o_.extra_bound(f_, next_.data())) : next_own;
      if (o_.upper == 0 || g + h < o_.upper) Offer(next_.data(), next_own, g + h, s, c);
    }
  }

  // Stores the state (or finds it) and queues it if reached with fewer fetches than before.
  void Offer(const Word* bits, std::uint32_t own, std::uint32_t f, StateId parent, CellId move) {
    const std::uint32_t g = parent == kNoState ? 0 : g_[parent] + 1;
    const std::uint64_t hash = HashBits(bits, words_);
    StateId s = store_.Find(bits, hash);
    if (s == kNoState) {
      s = store_.Add(bits, hash);
      g_.push_back(g), own_.push_back(own), parent_.push_back(parent), move_.push_back(move);
      closed_.push_back(false);
    } else if (g_[s] <= g) {
      return;  // with a consistent heuristic a closed state already has its fewest fetches
    } else {
      g_[s] = g, parent_[s] = parent, move_[s] = move, closed_[s] = false;  // reopened
    }
    open_.push({f, g, o_.seed == 0 ? s : MixBits(o_.seed ^ s), s});
  }

  std::vector<CellId> PathTo(StateId s) const {
    std::vector<CellId> path;
    for (; parent_[s] != kNoState; s = parent_[s]) path.push_back(move_[s]);
    std::reverse(path.begin(), path.end());
    return path;
  }

  const CellForest& f_;
  const ShorterOptions o_;
  const Clock::time_point start_;
  const std::size_t words_;
  BitsTable store_;
  std::vector<std::uint32_t> g_, own_;
  std::vector<StateId> parent_;
  std::vector<CellId> move_;
  std::vector<bool> closed_;
  std::priority_queue<OpenEntry> open_;
  Heuristic heuristic_;
  std::vector<Word> cur_, next_;  // scratch bitsets
  std::vector<Index> ready_;      // scratch
  std::size_t peak_bytes_ = 0;
  std::uint64_t work_ = 0;
};

std::string Sizes(const CellTree& tree, const char* what, std::size_t incumbent) {
  return "bound " + std::to_string(Bound(tree)) + ", " + what + " " + std::to_string(incumbent);
}

}  // namespace

ShorterResult FindShorter(const CellForest& forest, const ShorterOptions& options) {
  ShorterResult out = Search(forest, options).Run();
  if (out.status == ShorterResult::kFound) {
    RAYCELL_CHECK(IsFeasible(forest, out.schedule));
    RAYCELL_CHECK(options.upper == 0 || out.schedule.size() < options.upper);
  }
  return out;
}

OptimumResult ExactOptimum(const CellTree& tree, const OptimumLimits& limits) {
  OptimumOptions options;
  options.limits = limits;
  return ExactOptimum(tree, options);
}

OptimumResult ExactOptimum(const CellTree& tree, const OptimumOptions& options) {
  const auto start = Clock::now();
  OptimumResult out;
  if (tree.node_count() > options.limits.max_nodes) {
    out.status = OptimumResult::kTooLarge;
    out.reason = "tree has " + std::to_string(tree.node_count()) +
                 " nodes, more than max_nodes = " + std::to_string(options.limits.max_nodes);
    return out;
  }
  const bool peel = options.incumbent.empty();
  const std::vector<CellId> incumbent = peel ? Peel(tree).schedule : options.incumbent;
  RAYCELL_CHECK(IsFeasible(tree, incumbent));
  const char* what = peel ? "Peel" : "incumbent";
  const std::string whose = peel ? "Peel's" : "the incumbent's";
  const std::uint64_t bound = Bound(tree);
  // A lower bound above a feasible schedule's length is a bug of whoever computed it.
  RAYCELL_CHECK_LE(options.lower_bound, incumbent.size());
  out.lower = std::max(bound, options.lower_bound);
  out.upper = incumbent.size();
  if (incumbent.size() <= out.lower) {
    out.status = OptimumResult::kOptimal;
    out.schedule = incumbent;
    out.reason = (peel ? "Peel's length equals the " : "the incumbent's length equals the ") +
                 std::string(incumbent.size() == bound ? "bound " : "lower bound ") +
                 std::to_string(incumbent.size());
  } else {
    ShorterOptions o;
    o.upper = incumbent.size();
    o.limits = options.limits;
    o.pair_heuristic = options.pair_heuristic;
    o.extra_bound = options.extra_bound;
    const ShorterResult r = FindShorter(CellForest::FromTree(tree), o);
    out.states_expanded = r.expanded;
    const std::string sizes = Sizes(tree, what, incumbent.size());
    if (r.status == ShorterResult::kStopped) {
      out.status = OptimumResult::kUnknown;
      out.lower = std::max(out.lower, r.lower);
      out.reason = r.stopped + "; " + sizes;
    } else {
      out.status = OptimumResult::kOptimal;
      out.schedule = r.status == ShorterResult::kFound ? r.schedule : incumbent;
      out.reason =
          (r.status == ShorterResult::kFound ? "shorter than " : "no schedule is shorter than ") +
          whose + "; " + sizes;
    }
  }
  if (out.status == OptimumResult::kOptimal) {
    out.length = out.lower = out.upper = out.schedule.size();
    RAYCELL_CHECK(IsFeasible(tree, out.schedule));
  }
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

}  // namespace raycell
