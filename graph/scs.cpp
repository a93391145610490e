#include "graph/scs.h"

#include <algorithm>
#include <limits>
#include <queue>
#include <sstream>
#include <utility>

#include "base/check.h"

// Why the answers are proofs.
//
// States and moves. A state is a position vector p: string i has its first p_i symbols
// matched. A move appends symbol a to the supersequence built so far and advances every
// string whose next symbol is a. Advancing every such string (rather than some) is never
// worse: from a state that is ahead in every string, every continuation that completes the
// other state completes this one too. So the shortest common supersequence is the fewest
// moves from the start (all 0) to the end (all at their lengths).
//
// Forced moves. When some symbol a is wanted next by every string that still holds an a (all
// others hold none), some shortest completion starts with a: take any completion T = u a v,
// u free of a; then a u v completes too (a string starting with a matches the first a, and the
// rest of it matched inside v before; a string without a matched inside u v already) and has
// the same length and the same number of copies of every symbol. So from such a state only
// the move on a (the smallest such symbol) is generated. By induction on the remaining
// optimal length, every state still has a shortest completion in this reduced graph, and the
// same holds for completions within per-symbol budgets (same copies of every symbol).
//
// Heuristics (each a lower bound on the moves still needed, and consistent: one move lowers
// it by at most one).
//  - hl: the longest remaining suffix. Each move advances a string by at most one.
//  - hc: the sum over symbols a of the most copies of a that one remaining suffix holds. A
//    move on a advances each string by at most one a and changes no other symbol's term;
//    moves on different symbols are different moves.
//  - hp: for a few fixed pairs of strings, the SCS of their two remaining suffixes (a table
//    computed by the textbook dynamic program). A common supersequence of all remaining
//    suffixes is one of the two; a move lowers a pair's SCS by at most one (otherwise the
//    move followed by a completion of the pair would beat the pair's SCS).
// h = max(hl, hc, hp), a maximum of consistent heuristics, is consistent, and h = 0 at the
// end. So A* never reopens a closed state, takes the end first at its optimal g, and, when
// stopped early, the smallest f = g + h on the open list is a lower bound: some state of a
// shortest path is on the open list with g at its optimum, so its f is at most the optimum.
//
// Incumbent. A greedy supersequence of length U is known; only states with f < U are stored.
// A shortest path with length < U has f < U all along, so it is never cut; if the open list
// runs empty, nothing shorter than U exists and U is the SCS. The bound reported after a
// stop is min(smallest open f, U).
//
// The budget search is a depth-first search over (p, copies used so far) with the forced
// moves above, cut when some symbol needs more copies than its budget leaves (hc per symbol)
// or the remaining budget in total is below hl or hp; a state is remembered only once its
// whole subtree failed, so meeting it again (same p and same copies used) fails as well.
//
// Determinism: symbols are renumbered in increasing cell order, moves are tried in a fixed
// order and the open list is ordered by (f, larger g first, creation order).

namespace raycell {

std::string ScsResult::ToString() const {
  std::ostringstream s;
  if (exact) {
    s << "exact " << lower_bound;
  } else {
    s << "in [" << lower_bound << ", " << upper_bound << "]";
  }
  s << " (" << states << " states)";
  return s.str();
}

const char* ToString(Realisability r) {
  switch (r) {
    case Realisability::kRealisable:
      return "realisable";
    case Realisability::kNotRealisable:
      return "not realisable";
    case Realisability::kUnknown:
      return "unknown";
  }
  return "?";
}

namespace {

using Word = std::uint64_t;
using Symbol = std::uint16_t;
using StateId = std::uint32_t;
constexpr StateId kNoState = std::numeric_limits<StateId>::max();
constexpr Symbol kNoSymbol = std::numeric_limits<Symbol>::max();

std::uint64_t Mix(std::uint64_t x) {  // splitmix64's finalizer
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t HashWords(const Word* w, std::size_t n) {
  std::uint64_t h = n;
  for (std::size_t i = 0; i < n; ++i) h = Mix(h ^ w[i]);
  return h;
}

std::uint32_t BitWidth(std::uint32_t v) {
  std::uint32_t b = 1;
  while ((v >> b) != 0) ++b;
  return b;
}

// Packs small unsigned values, `bits` each, into words.
struct Packing {
  std::uint32_t bits = 1;
  std::size_t count = 0;
  std::size_t words() const { return (count * bits + 63) / 64; }
  std::uint32_t Get(const Word* w, std::size_t i) const {
    const std::size_t bit = i * bits, word = bit / 64, shift = bit % 64;
    Word v = w[word] >> shift;
    if (shift + bits > 64) v |= w[word + 1] << (64 - shift);
    return static_cast<std::uint32_t>(v & ((Word{1} << bits) - 1));
  }
  void Set(Word* w, std::size_t i, std::uint32_t value) const {
    const std::size_t bit = i * bits, word = bit / 64, shift = bit % 64;
    const Word mask = (Word{1} << bits) - 1;
    w[word] = (w[word] & ~(mask << shift)) | (Word{value} << shift);
    if (shift + bits > 64) {
      const std::size_t high = 64 - shift;
      w[word + 1] = (w[word + 1] & ~(mask >> high)) | (Word{value} >> high);
    }
  }
};

// The strings with dense symbols and the tables the heuristics read.
class Problem {
 public:
  explicit Problem(const std::vector<CellString>& input) {
    const std::vector<CellString> strings = RemoveDominated(input);
    for (const CellString& s : strings) symbols_.insert(symbols_.end(), s.begin(), s.end());
    std::sort(symbols_.begin(), symbols_.end());
    symbols_.erase(std::unique(symbols_.begin(), symbols_.end()), symbols_.end());
    RAYCELL_CHECK_LT(symbols_.size(), std::size_t{kNoSymbol});
    k_ = static_cast<std::uint32_t>(symbols_.size());
    std::uint32_t longest = 0;
    for (const CellString& s : strings) {
      std::vector<Symbol> d;
      for (CellId c : s) d.push_back(Dense(c));
      longest = std::max(longest, static_cast<std::uint32_t>(d.size()));
      str_.push_back(std::move(d));
    }
    packing_.bits = BitWidth(longest);
    packing_.count = str_.size();
    BuildCounts();
    ChoosePairs();
  }

  std::size_t strings() const { return str_.size(); }
  std::uint32_t symbols() const { return k_; }
  CellId cell(Symbol a) const { return symbols_[a]; }
  Symbol Dense(CellId c) const {
    const auto it = std::lower_bound(symbols_.begin(), symbols_.end(), c);
    return it != symbols_.end() && *it == c ? static_cast<Symbol>(it - symbols_.begin())
                                            : kNoSymbol;
  }
  const Packing& packing() const { return packing_; }
  std::uint32_t length(std::size_t i) const { return static_cast<std::uint32_t>(str_[i].size()); }
  Symbol next(std::size_t i, std::uint32_t p) const {
    return p < str_[i].size() ? str_[i][p] : kNoSymbol;
  }
  // Copies of symbol a in string i from position p on.
  std::uint32_t count(std::size_t i, std::uint32_t p, Symbol a) const {
    return counts_[offset_[i] + p * k_ + a];
  }

  struct Eval {
    std::uint32_t h = 0;        // max(hl, hc, hp)
    Symbol forced = kNoSymbol;  // the smallest symbol every string needing it wants next
    bool done = false;          // every string fully matched
  };
  // `need` (k entries) receives the most copies of each symbol a remaining suffix holds.
  Eval Evaluate(const std::vector<std::uint32_t>& p, std::vector<std::uint32_t>& need,
                std::vector<bool>& blocked) const {
    Eval e;
    need.assign(k_, 0);
    blocked.assign(k_, false);
    std::uint32_t hl = 0;
    for (std::size_t i = 0; i < str_.size(); ++i) {
      const std::uint32_t rem = length(i) - p[i];
      if (rem == 0) continue;
      hl = std::max(hl, rem);
      const std::uint16_t* c = &counts_[offset_[i] + p[i] * k_];
      const Symbol nx = str_[i][p[i]];
      for (Symbol a = 0; a < k_; ++a) {
        if (c[a] == 0) continue;
        need[a] = std::max<std::uint32_t>(need[a], c[a]);
        if (a != nx) blocked[a] = true;
      }
    }
    std::uint32_t hc = 0;
    for (Symbol a = 0; a < k_; ++a) {
      hc += need[a];
      if (e.forced == kNoSymbol && need[a] > 0 && !blocked[a]) e.forced = a;
    }
    e.done = hl == 0;
    e.h = std::max({hl, hc, PairBound(p)});
    return e;
  }

  std::uint32_t PairBound(const std::vector<std::uint32_t>& p) const {
    std::uint32_t h = 0;
    for (const Pair& q : pairs_) {
      h = std::max<std::uint32_t>(h, q.table[p[q.i] * (length(q.j) + 1) + p[q.j]]);
    }
    return h;
  }

 private:
  struct Pair {
    std::size_t i, j;
    std::vector<std::uint16_t> table;  // SCS of the suffixes from (x, y) at x*(len j+1)+y
  };

  void BuildCounts() {
    for (std::size_t i = 0; i < str_.size(); ++i) {
      offset_.push_back(counts_.size());
      const std::size_t len = str_[i].size();
      counts_.resize(counts_.size() + (len + 1) * k_, 0);
      std::uint16_t* base = &counts_[offset_[i]];
      for (std::size_t p = len; p-- > 0;) {
        std::copy(base + (p + 1) * k_, base + (p + 2) * k_, base + p * k_);
        ++base[p * k_ + str_[i][p]];
      }
    }
  }

  Pair PairTable(std::size_t i, std::size_t j) const {
    Pair q{i, j, {}};
    const std::size_t li = str_[i].size(), lj = str_[j].size(), w = lj + 1;
    q.table.resize((li + 1) * w);
    for (std::size_t x = li + 1; x-- > 0;) {
      for (std::size_t y = lj + 1; y-- > 0;) {
        std::uint16_t v;
        if (x == li) {
          v = static_cast<std::uint16_t>(lj - y);
        } else if (y == lj) {
          v = static_cast<std::uint16_t>(li - x);
        } else if (str_[i][x] == str_[j][y]) {
          v = 1 + q.table[(x + 1) * w + y + 1];
        } else {
          v = 1 + std::min(q.table[(x + 1) * w + y], q.table[x * w + y + 1]);
        }
        q.table[x * w + y] = v;
      }
    }
    return q;
  }

  // The pairs with the largest SCS at the start among the pairs of the longest strings
  // (ties: smaller indices), at most kPairs of them.
  void ChoosePairs() {
    constexpr std::size_t kCandidates = 48, kPairs = 24;
    const std::size_t n = std::min(str_.size(), kCandidates);  // str_ is longest first
    std::vector<std::pair<std::uint32_t, std::pair<std::size_t, std::size_t>>> scored;
    std::vector<Pair> all;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        Pair q = PairTable(i, j);
        const std::uint32_t start = q.table[0];
        if (start > std::max(length(i), length(j))) {
          scored.push_back({start, {i, j}});
        }
      }
    }
    std::stable_sort(scored.begin(), scored.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    if (scored.size() > kPairs) scored.resize(kPairs);
    for (const auto& s : scored) pairs_.push_back(PairTable(s.second.first, s.second.second));
  }

  std::vector<CellId> symbols_;
  std::uint32_t k_ = 0;
  std::vector<std::vector<Symbol>> str_;
  std::vector<std::size_t> offset_;
  std::vector<std::uint16_t> counts_;
  std::vector<Pair> pairs_;
  Packing packing_;
};

// Position vectors stored once each, in creation order, with a hash table over them.
class StateStore {
 public:
  explicit StateStore(std::size_t words) : words_(std::max<std::size_t>(words, 1)) {}

  std::size_t size() const { return hash_.size(); }
  std::size_t words() const { return words_; }
  const Word* bits(StateId s) const { return &bits_[std::size_t{s} * words_]; }
  StateId Find(const Word* w, std::uint64_t hash) const {
    if (table_.empty()) return kNoState;
    for (std::size_t i = hash & (table_.size() - 1);; i = (i + 1) & (table_.size() - 1)) {
      const StateId s = table_[i];
      if (s == kNoState) return kNoState;
      if (hash_[s] == hash && std::equal(w, w + words_, bits(s))) return s;
    }
  }
  StateId Add(const Word* w, std::uint64_t hash) {
    RAYCELL_CHECK_LT(size(), std::size_t{kNoState});
    const auto s = static_cast<StateId>(size());
    bits_.insert(bits_.end(), w, w + words_);
    hash_.push_back(hash);
    if (2 * size() > table_.size()) Rehash(std::max<std::size_t>(1024, 2 * table_.size()));
    Place(s);
    return s;
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
  std::vector<StateId> table_;
};

void Unpack(const Packing& pk, const Word* w, std::vector<std::uint32_t>& p) {
  p.resize(pk.count);
  for (std::size_t i = 0; i < pk.count; ++i) p[i] = pk.Get(w, i);
}
void Pack(const Packing& pk, const std::vector<std::uint32_t>& p, std::vector<Word>& w) {
  w.assign(std::max<std::size_t>(pk.words(), 1), 0);
  for (std::size_t i = 0; i < pk.count; ++i) pk.Set(w.data(), i, p[i]);
}

// Advances every string whose next symbol is a.
void Advance(const Problem& in, const std::vector<std::uint32_t>& p, Symbol a,
             std::vector<std::uint32_t>& q) {
  q = p;
  for (std::size_t i = 0; i < in.strings(); ++i) {
    if (in.next(i, p[i]) == a) ++q[i];
  }
}

// The symbols some string wants next, in increasing order.
std::vector<Symbol> NextSymbols(const Problem& in, const std::vector<std::uint32_t>& p) {
  std::vector<bool> wanted(in.symbols(), false);
  for (std::size_t i = 0; i < in.strings(); ++i) {
    const Symbol a = in.next(i, p[i]);
    if (a != kNoSymbol) wanted[a] = true;
  }
  std::vector<Symbol> out;
  for (Symbol a = 0; a < in.symbols(); ++a) {
    if (wanted[a]) out.push_back(a);
  }
  return out;
}

// Weighted majority merge: the forced symbol if any, else the symbol whose advanced strings
// have the most remaining symbols in total (smallest symbol on ties).
CellString Greedy(const Problem& in) {
  std::vector<std::uint32_t> p(in.strings(), 0), q, need;
  std::vector<bool> blocked;
  CellString out;
  for (;;) {
    const Problem::Eval e = in.Evaluate(p, need, blocked);
    if (e.done) return out;
    Symbol best = e.forced;
    if (best == kNoSymbol) {
      std::vector<std::uint64_t> weight(in.symbols(), 0);
      for (std::size_t i = 0; i < in.strings(); ++i) {
        const Symbol a = in.next(i, p[i]);
        if (a != kNoSymbol) weight[a] += in.length(i) - p[i];
      }
      best = static_cast<Symbol>(std::max_element(weight.begin(), weight.end()) - weight.begin());
    }
    out.push_back(in.cell(best));
    Advance(in, p, best, q);
    p.swap(q);
  }
}

struct OpenEntry {
  std::uint32_t f, g;
  StateId state;
  // std::priority_queue pops the largest: smallest f, then largest g, then oldest state.
  bool operator<(const OpenEntry& o) const {
    if (f != o.f) return f > o.f;
    if (g != o.g) return g < o.g;
    return state > o.state;
  }
};

class AStar {
 public:
  AStar(const Problem& in, const ScsLimits& limits) : in_(in), limits_(limits) {}

  ScsResult Run() {
    ScsResult r;
    r.supersequence = Greedy(in_);
    r.upper_bound = static_cast<std::uint32_t>(r.supersequence.size());
    StateStore store(in_.packing().words());
    std::vector<std::uint32_t> p(in_.strings(), 0), q;
    std::vector<Word> w;
    const Problem::Eval start = in_.Evaluate(p, need_, blocked_);
    r.lower_bound = std::min(start.h, r.upper_bound);
    if (r.lower_bound == r.upper_bound) return Exact(r, r.upper_bound);
    Pack(in_.packing(), p, w);
    Add(store, w, 0, kNoState, kNoSymbol);
    open_.push({start.h, 0, 0});
    while (!open_.empty()) {
      const OpenEntry top = open_.top();
      if (top.g > g_[top.state]) {  // a stale entry: the state was reached cheaper since
        open_.pop();
        continue;
      }
      open_.pop();
      Unpack(in_.packing(), store.bits(top.state), p);
      const Problem::Eval e = in_.Evaluate(p, need_, blocked_);
      if (e.done) {
        r.supersequence = Path(top.state);
        return Exact(r, top.g);
      }
      if (store.size() >= limits_.max_states) {
        // `top` had the smallest f on the open list.
        r.lower_bound = std::min(top.f, r.upper_bound);
        return r;
      }
      ++r.states;
      const std::vector<Symbol> moves =
          e.forced != kNoSymbol ? std::vector<Symbol>{e.forced} : NextSymbols(in_, p);
      for (Symbol a : moves) {
        Advance(in_, p, a, q);
        const std::uint32_t g = top.g + 1;
        Pack(in_.packing(), q, w);
        const std::uint64_t hash = HashWords(w.data(), store.words());
        StateId s = store.Find(w.data(), hash);
        if (s != kNoState && g_[s] <= g) continue;
        const std::uint32_t h = s != kNoState ? h_[s] : in_.Evaluate(q, need_, blocked_).h;
        if (g + h >= r.upper_bound) continue;
        if (s == kNoState) {
          s = Add(store, w, h, top.state, a);
        } else {
          parent_[s] = top.state, move_[s] = a;
        }
        g_[s] = g;
        open_.push({g + h, g, s});
      }
    }
    // Nothing shorter than the greedy supersequence exists.
    return Exact(r, r.upper_bound);
  }

 private:
  StateId Add(StateStore& store, const std::vector<Word>& w, std::uint32_t h, StateId parent,
              Symbol move) {
    const StateId s = store.Add(w.data(), HashWords(w.data(), store.words()));
    g_.push_back(0), h_.push_back(h), parent_.push_back(parent), move_.push_back(move);
    return s;
  }
  CellString Path(StateId s) const {
    CellString out;
    for (; parent_[s] != kNoState; s = parent_[s]) out.push_back(in_.cell(move_[s]));
    std::reverse(out.begin(), out.end());
    return out;
  }
  static ScsResult Exact(ScsResult r, std::uint32_t length) {
    r.exact = true;
    r.lower_bound = r.upper_bound = length;
    return r;
  }

  const Problem& in_;
  ScsLimits limits_;
  std::priority_queue<OpenEntry> open_;
  std::vector<std::uint32_t> g_, h_;
  std::vector<StateId> parent_;
  std::vector<Symbol> move_;
  std::vector<std::uint32_t> need_;
  std::vector<bool> blocked_;
};

// Depth-first search for a common supersequence within per-symbol budgets.
class BudgetSearch {
 public:
  BudgetSearch(const Problem& in, std::vector<std::uint32_t> budget, const ScsLimits& limits)
      : in_(in), budget_(std::move(budget)), limits_(limits) {
    std::uint32_t most = 0;
    for (std::uint32_t b : budget_) most = std::max(most, b);
    used_packing_.bits = BitWidth(most);
    used_packing_.count = in_.symbols();
    pos_words_ = in_.packing().words();
    failed_ = StateStore(pos_words_ + used_packing_.words());
  }

  BudgetResult Run() {
    BudgetResult r;
    std::vector<std::uint32_t> p(in_.strings(), 0), used(in_.symbols(), 0);
    std::uint64_t left = 0;
    for (std::uint32_t b : budget_) left += b;
    const Outcome o = Search(p, used, left);
    r.states = states_;
    if (o == kFound) {
      r.answer = Realisability::kRealisable;
      for (Symbol a : path_) r.witness.push_back(in_.cell(a));
    } else {
      r.answer = o == kFail ? Realisability::kNotRealisable : Realisability::kUnknown;
    }
    return r;
  }

 private:
  enum Outcome { kFound, kFail, kStopped };

  Outcome Search(const std::vector<std::uint32_t>& p, std::vector<std::uint32_t>& used,
                 std::uint64_t left) {
    std::vector<std::uint32_t> need;
    std::vector<bool> blocked;
    const Problem::Eval e = in_.Evaluate(p, need, blocked);
    if (e.done) return kFound;
    if (e.h > left) return kFail;
    for (Symbol a = 0; a < in_.symbols(); ++a) {
      if (need[a] + used[a] > budget_[a]) return kFail;
    }
    std::vector<Word> key = Key(p, used);
    const std::uint64_t hash = HashWords(key.data(), key.size());
    if (failed_.Find(key.data(), hash) != kNoState) return kFail;
    if (++states_ > limits_.max_states) return kStopped;
    std::vector<Symbol> moves;
    if (e.forced != kNoSymbol) {
      moves.push_back(e.forced);
    } else {
      moves = NextSymbols(in_, p);
      // Most strings advanced first; then smaller symbol.
      std::vector<std::uint32_t> advanced(in_.symbols(), 0);
      for (std::size_t i = 0; i < in_.strings(); ++i) {
        const Symbol a = in_.next(i, p[i]);
        if (a != kNoSymbol) ++advanced[a];
      }
      std::stable_sort(moves.begin(), moves.end(),
                       [&](Symbol a, Symbol b) { return advanced[a] > advanced[b]; });
    }
    std::vector<std::uint32_t> q;
    for (Symbol a : moves) {
      if (used[a] >= budget_[a]) continue;
      Advance(in_, p, a, q);
      ++used[a];
      path_.push_back(a);
      const Outcome o = Search(q, used, left - 1);
      if (o != kFail) return o;
      path_.pop_back();
      --used[a];
    }
    failed_.Add(key.data(), hash);
    return kFail;
  }

  std::vector<Word> Key(const std::vector<std::uint32_t>& p,
                        const std::vector<std::uint32_t>& used) const {
    std::vector<Word> key(failed_.words(), 0);
    for (std::size_t i = 0; i < p.size(); ++i) in_.packing().Set(key.data(), i, p[i]);
    for (std::size_t a = 0; a < used.size(); ++a) {
      used_packing_.Set(key.data() + pos_words_, a, used[a]);
    }
    return key;
  }

  const Problem& in_;
  std::vector<std::uint32_t> budget_;  // per dense symbol
  ScsLimits limits_;
  Packing used_packing_;
  std::size_t pos_words_ = 0;
  StateStore failed_{1};
  std::uint64_t states_ = 0;
  std::vector<Symbol> path_;
};

}  // namespace

class ScsSolver::Instance {
 public:
  explicit Instance(const std::vector<CellString>& strings) : problem(strings) {
    for (Symbol a = 0; a < problem.symbols(); ++a) cells.push_back(problem.cell(a));
  }
  Problem problem;
  std::vector<CellId> cells;
};

ScsSolver::ScsSolver(const std::vector<CellString>& strings)
    : in_(std::make_unique<const Instance>(strings)) {}
ScsSolver::~ScsSolver() = default;
ScsSolver::ScsSolver(ScsSolver&&) noexcept = default;
ScsSolver& ScsSolver::operator=(ScsSolver&&) noexcept = default;

std::size_t ScsSolver::strings() const { return in_->problem.strings(); }
const std::vector<CellId>& ScsSolver::symbols() const { return in_->cells; }

std::uint32_t ScsSolver::MostUseful(CellId cell) const {
  const Problem& p = in_->problem;
  const Symbol a = p.Dense(cell);
  std::uint32_t n = 0;
  if (a == kNoSymbol) return 0;
  for (std::size_t i = 0; i < p.strings(); ++i) n += p.count(i, 0, a);
  return n;
}

ScsResult ScsSolver::Shortest(const ScsLimits& limits) const {
  if (in_->problem.strings() == 0) {
    ScsResult r;
    r.exact = true;
    return r;
  }
  return AStar(in_->problem, limits).Run();
}

BudgetResult ScsSolver::FitsBudget(const std::vector<std::uint32_t>& budget,
                                   const ScsLimits& limits) const {
  const Problem& p = in_->problem;
  std::vector<std::uint32_t> dense(p.symbols());
  for (Symbol a = 0; a < p.symbols(); ++a) {
    RAYCELL_CHECK_LT(std::size_t{p.cell(a)}, budget.size());
    dense[a] = budget[p.cell(a)];
  }
  return BudgetSearch(p, std::move(dense), limits).Run();
}

ScsResult ShortestCommonSupersequence(const std::vector<CellString>& strings,
                                      const ScsLimits& limits) {
  return ScsSolver(strings).Shortest(limits);
}

}  // namespace raycell
