#include "search/beam_search.h"

#include <algorithm>
#include <sstream>

#include "base/check.h"
#include "search/search_util.h"

namespace raycell {

std::string BeamResult::ToString() const {
  std::ostringstream s;
  s << "beam " << width << ": ";
  if (found) {
    s << schedule.size() << " entries";
  } else {
    s << "none below the limit";
  }
  s << ", " << states << " states, " << children << " children";
  return s.str();
}

namespace {

using Index = CellForest::Index;

struct Child {
  std::uint32_t f;      // g + h
  std::uint32_t left;   // unprocessed nodes after the move
  std::uint64_t tie;    // tie-break
  std::uint32_t state;  // parent's rank in its layer
  CellId cell;
  std::uint32_t h;
  bool operator<(const Child& o) const {
    if (f != o.f) return f < o.f;
    if (left != o.left) return left < o.left;
    if (tie != o.tie) return tie < o.tie;
    return state != o.state ? state < o.state : cell < o.cell;  // a total order
  }
};

// One pass over a cell's nodes in a state: how many are ready, and the cell's maxGen term
// before and after processing them (Beam::ScoreMove).
struct MoveScore {
  std::uint32_t ready, old_term, new_term;
};

struct Layer {
  std::vector<Word> bits;  // size() * words
  std::vector<std::uint32_t> h, left;
  // size() * the forest's cells with nodes: each state's MoveScore per cell, in the order of
  // CellForest::cells().
  std::vector<MoveScore> scores;
  std::size_t size() const { return h.size(); }
  void Clear() { bits.clear(), h.clear(), left.clear(), scores.clear(); }
};

class Beam {
 public:
  Beam(const CellForest& f, const BeamOptions& o)
      : f_(f),
        o_(o),
        words_(WordsFor(f.size())),
        slot_(f.cell_count(), 0),
        stamp_(f.cells().size(), 0),
        rg_old_(f.size()),
        rg_new_(f.size()) {
    for (std::size_t k = 0; k < f.cells().size(); ++k)
      slot_[f.cells()[k].value()] = std::uint32_t(k);
  }

  BeamResult Run() {
    BeamResult out;
    if (f_.size() == 0) {
      out.found = true;
      return out;
    }
    cur_.bits.assign(words_, 0);
    cur_.h.push_back(std::uint32_t(f_.bound()));
    cur_.left.push_back(std::uint32_t(f_.size()));
    for (CellId c : f_.cells()) cur_.scores.push_back(ScoreMove(cur_.bits.data(), c));
    out.states = 1;
    for (std::uint32_t g = 0;; ++g) {
      const std::size_t width = Width(out, cur_.h[0]);
      out.width = std::max(out.width, width);
      ScoreChildren(g, out);
      if (children_.empty()) return out;  // every child pruned by `upper`
      SortPrefix(0, 2 * width);
      moves_.emplace_back();
      if (children_[0].h == 0) {  // the complete set: the shortest schedule of the beam
        moves_.back().push_back({children_[0].state, children_[0].cell});
        out.found = true;
        out.schedule = Path();
        return out;
      }
      Select(width, out);
      std::swap(cur_, next_);
    }
  }

 private:
  struct Move {
    std::uint32_t parent;
    CellId cell;
  };

  // The width for the next layer: the requested one, lowered so that the layers still
  // expected (at least h more) fit in what is left of the node-visit budget.
  std::size_t Width(const BeamResult& out, std::uint32_t h) const {
    const std::uint64_t per_state = std::uint64_t(f_.size()) + words_;
    const std::uint64_t left =
        out.node_visits < o_.max_node_visits ? o_.max_node_visits - out.node_visits : 0;
    const std::uint64_t fit = left / (per_state * std::max<std::uint64_t>(h, 1));
    return std::size_t(std::max<std::uint64_t>(1, std::min<std::uint64_t>(o_.width, fit)));
  }

  // Every child of every state of the current layer, with its score. The states' MoveScores
  // were computed when they were kept (Select); node_visits still counts a pass over every
  // node per state, the cost of scoring them all afresh, so that the work limit gives the
  // same widths, and so the same schedules, as when they were.
  void ScoreChildren(std::uint32_t g, BeamResult& out) {
    children_.clear();
    const std::size_t cells = f_.cells().size();
    for (std::uint32_t s = 0; s < cur_.size(); ++s) {
      const MoveScore* scores = &cur_.scores[s * cells];
      for (std::size_t k = 0; k < cells; ++k) {
        const CellId c = f_.cells()[k];
        const auto [ready, old_term, new_term] = scores[k];
        if (ready == 0) continue;
        ++out.children;
        const std::uint32_t h = cur_.h[s] - old_term + new_term;
        if (o_.upper != 0 && g + 1 + h >= o_.upper) continue;
        const std::uint64_t tie =
            o_.seed == 0
                ? std::uint64_t(s) * f_.cell_count() + c.value()
                : MixBits(o_.seed ^ MixBits(std::uint64_t(s) * f_.cell_count() + c.value()));
        children_.push_back({g + 1 + h, cur_.left[s] - ready, tie, s, c, h});
      }
      out.node_visits += f_.size();
    }
  }

  // One pass over the nodes of c (ancestors first): how many are ready, and c's maxGen term
  // before and after processing them. rg: remaining generation, 0 for processed nodes.
  MoveScore ScoreMove(const Word* bits, CellId c) {
    MoveScore m{0, 0, 0};
    for (Index n : f_.nodes_of(c)) {
      if (TestBit(bits, n)) {
        rg_old_[n] = rg_new_[n] = 0;
        continue;
      }
      const Index a = f_.same_cell_above(n), p = f_.parent(n);
      const std::uint32_t ro = (a != CellForest::kNone && rg_old_[a]) ? rg_old_[a] + 1 : 1;
      rg_old_[n] = ro;
      m.old_term = std::max(m.old_term, ro);
      if (p == CellForest::kNone || TestBit(bits, p)) {
        rg_new_[n] = 0;
        ++m.ready;
        continue;
      }
      const std::uint32_t rn = (a != CellForest::kNone && rg_new_[a]) ? rg_new_[a] + 1 : 1;
      rg_new_[n] = rn;
      m.new_term = std::max(m.new_term, rn);
    }
    return m;
  }

  // The next layer: the best children, duplicates merged, at most `width`.
  // Sorts children_[from..] so that its first `count` are the smallest, in order (the
  // order is total, so this is a prefix of the fully sorted list).
  void SortPrefix(std::size_t from, std::size_t count) {
    const auto begin = children_.begin() + from;
    if (children_.size() - from > count) {
      std::nth_element(begin, begin + count, children_.end());
      std::sort(begin, begin + count);
    } else {
      std::sort(begin, children_.end());
    }
  }

  void Select(std::size_t width, BeamResult& out) {
    next_.Clear();
    const std::size_t most = std::min(width, children_.size());
    table_.assign(std::size_t(1) << CeilLog2(2 * most + 2), kEmpty);
    hashes_.clear();
    std::vector<Word> bits(words_);
    std::size_t sorted = std::min(children_.size(), 2 * width);
    for (std::size_t k = 0; k < children_.size() && next_.size() < width; ++k) {
      if (k == sorted) {  // duplicates used up the sorted part: sort the next 2 * width
        SortPrefix(k, 2 * width);
        sorted = std::min(children_.size(), k + 2 * width);
      }
      const Child& ch = children_[k];
      const Word* from = &cur_.bits[std::size_t(ch.state) * words_];
      std::copy(from, from + words_, bits.begin());
      processed_.clear();
      for (Index n : f_.nodes_of(ch.cell)) {
        const Index p = f_.parent(n);
        if (!TestBit(from, n) && (p == CellForest::kNone || TestBit(from, p))) {
          SetBit(bits, n);
          processed_.push_back(n);
        }
      }
      out.node_visits += words_ + f_.nodes_of(ch.cell).size();
      const std::uint64_t hash = HashBits(bits.data(), words_);
      if (!Insert(bits.data(), hash)) continue;
      next_.bits.insert(next_.bits.end(), bits.begin(), bits.end());
      next_.h.push_back(ch.h);
      next_.left.push_back(ch.left);
      AddScores(ch, bits.data());
      moves_.back().push_back({ch.state, ch.cell});
      ++out.states;
    }
  }

  // The MoveScores of the state just kept in next_ (bits, reached by `ch`, which processed
  // processed_): its parent's, but for the cells a move there changes: ch.cell (its nodes
  // were processed) and the cells of their children (now ready). A move on any other cell
  // reads the same bits of its nodes and their parents as in the parent state.
  void AddScores(const Child& ch, const Word* bits) {
    const std::size_t cells = f_.cells().size();
    const MoveScore* parent = &cur_.scores[ch.state * cells];
    next_.scores.insert(next_.scores.end(), parent, parent + cells);
    MoveScore* scores = &next_.scores[next_.scores.size() - cells];
    ++epoch_;
    const auto rescore = [&](CellId c) {
      const std::uint32_t k = slot_[c.value()];
      if (stamp_[k] == epoch_) return;
      stamp_[k] = epoch_;
      scores[k] = ScoreMove(bits, c);
    };
    rescore(ch.cell);
    for (Index n : processed_) {
      for (const Index* m = f_.child_begin(n); m != f_.child_end(n); ++m) rescore(f_.cell(*m));
    }
  }

  // Adds the state about to be appended to next_ to the table; false if already there.
  bool Insert(const Word* bits, std::uint64_t hash) {
    const std::size_t mask = table_.size() - 1;
    for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
      const std::uint32_t s = table_[i];
      if (s == kEmpty) {
        table_[i] = std::uint32_t(next_.size());
        hashes_.push_back(hash);
        return true;
      }
      if (hashes_[s] == hash &&
          std::equal(bits, bits + words_, &next_.bits[std::size_t(s) * words_])) {
        return false;
      }
    }
  }

  std::vector<CellId> Path() const {
    std::vector<CellId> path;
    std::uint32_t s = 0;
    for (std::size_t layer = moves_.size(); layer-- > 0;) {
      const Move& m = moves_[layer][s];
      path.push_back(m.cell);
      s = m.parent;
    }
    std::reverse(path.begin(), path.end());
    return path;
  }

  static constexpr std::uint32_t kEmpty = 0xffffffffu;

  const CellForest& f_;
  const BeamOptions o_;
  const std::size_t words_;
  Layer cur_, next_;
  std::vector<Child> children_;
  std::vector<std::vector<Move>> moves_;  // per layer, per state kept: how it was reached
  std::vector<std::uint32_t> table_;      // open addressing over next_'s states
  std::vector<std::uint64_t> hashes_;
  std::vector<std::uint32_t> slot_;  // per cell id: its index in f_.cells()
  // AddScores' cells already scored for the current state (stamp_[k] == epoch_).
  std::vector<std::uint64_t> stamp_;
  std::uint64_t epoch_ = 0;
  std::vector<Index> processed_;                // nodes the kept move processed
  std::vector<std::uint32_t> rg_old_, rg_new_;  // scratch, per node
};

}  // namespace

BeamResult BeamSearch(const CellForest& forest, const BeamOptions& options) {
  RAYCELL_CHECK(options.width > 0);
  BeamResult out = Beam(forest, options).Run();
  if (out.found) RAYCELL_CHECK(IsFeasible(forest, out.schedule));
  return out;
}

BeamResult BeamSearch(const CellTree& tree, const BeamOptions& options) {
  return BeamSearch(CellForest::FromTree(tree), options);
}

}  // namespace raycell
