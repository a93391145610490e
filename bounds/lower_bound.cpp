#include "bounds/lower_bound.h"

#include <glpk.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "base/check.h"
#include "base/parse.h"
#include "bounds/projection.h"
#include "bounds/scs.h"

// Why every number this file reports is at most the optimum.
//
// Let T be an optimal (shortest feasible) schedule and x_c the number of entries of T that
// are cell c. T is a common supersequence of all root-to-leaf paths (docs/design.md §1), so:
//  (1) x_c >= maxGen(c): a node of generation g has g nodes of cell c on its path, each needing
//      its own entry of c (maxGen).
//  (2) for any set S of cells, T restricted to S (the entries of cells of S, in order) is a
//      common supersequence of the paths projected onto S, so sum_{c in S} x_c >= SCS(S) >= the
//      proven lower bound of bounds/scs.h (its own proof is in bounds/string_dag.h and what builds
//      on it).
//  (3) for any S and any vector u over S such that the projections onto S have no common
//      supersequence with at most u_c copies of each c in S (FitsBudget says kNotRealisable,
//      a proof by exhaustive search), T restricted to S cannot have x_c <= u_c for every c:
//      it would be such a supersequence. So some c in S has x_c >= u_c + 1 (a cut). A c with
//      u_c >= MostUseful(c) is dropped from the disjunction: a supersequence with more copies
//      of c keeps one with at most MostUseful(c) after dropping the copies no path uses, so
//      more copies of c are no way out. Raising u (lifting) is checked by the same search at
//      each step, and an unknown answer stops it. Unions of groups (UnionCuts) are sets S
//      like any other.
// So the count vector of T satisfies every constraint of the program below, and the program's
// minimum of sum x_c is at most |T|. When a group holds every cell with nodes, its projection
// is the tree's paths themselves: its exact SCS is the optimum (result.optimal). The matching stage
// is a special case: pairs with no cell in common are disjoint groups, and their SCS bounds add
// (different cells are different entries), plus maxGen for the cells outside the pairs.
//
// The program is solved by GLPK's branch and bound. Its data are small integers and x is
// integral, so the objective is integral: a branch-and-bound bound b proves >= ceil(b - 1e-6).
// When the node limit stops the search, the reported value is the smallest bound of an open
// node (or the incumbent if smaller), a lower bound on the program's minimum.

namespace raycell {

std::string LowerBoundResult::ToString() const {
  std::ostringstream s;
  s << "lower bound " << value << " (maxGen " << max_gen << "; " << method << "; " << groups.size()
    << " groups, " << cuts << " cuts, " << states << " states";
  if (limits_reached) s << "; limits reached";
  s << ")";
  return s.str();
}

namespace {

// ------------------------------------------------------------------ the count program

// min sum x_c over the cells with maxGen > 0, x_c integer >= maxGen(c), with rows
// sum_{c in S} x_c >= b (AddAtLeast) and cuts "some c in S has x_c >= v_c" (AddCut), the
// latter through binaries z_{c,v} with x_c >= maxGen(c) + (v - maxGen(c)) z_{c,v}: z_{c,v} = 1
// forces x_c >= v, and the cut row sum z >= 1 forces one of them.
//
// GLPK keeps an environment per thread (its memory pool), which lives until glp_free_env on
// that thread: the last program of a thread frees it, so that threads that end (the study's,
// a sweep's) leave nothing behind (LeakSanitizer found it). A program is created per call
// of LowerBound, so the environment's set-up is a negligible part of the call.
thread_local int live_programs = 0;

class CountProgram {
 public:
  explicit CountProgram(const std::vector<std::uint32_t>& max_gen)
      : max_gen_(max_gen), column_(max_gen.size(), 0) {
    ++live_programs;
    glp_ = glp_create_prob();
    glp_set_obj_dir(glp_, GLP_MIN);
    for (std::size_t c = 0; c < max_gen.size(); ++c) {
      if (max_gen[c] == 0) continue;
      const int j = glp_add_cols(glp_, 1);
      column_[c] = j;
      glp_set_col_kind(glp_, j, GLP_IV);
      glp_set_col_bnds(glp_, j, GLP_LO, max_gen[c], 0);
      glp_set_obj_coef(glp_, j, 1);
    }
  }
  ~CountProgram() {
    glp_delete_prob(glp_);
    if (--live_programs == 0) glp_free_env();
  }
  CountProgram(const CountProgram&) = delete;
  CountProgram& operator=(const CountProgram&) = delete;

  void AddAtLeast(const std::vector<CellId>& cells, std::uint32_t rhs) {
    std::vector<int> ind{0};
    std::vector<double> val{0};
    for (CellId c : cells) ind.push_back(column_[c.value()]), val.push_back(1);
    AddRow(ind, val, rhs);
  }

  // Some cell c of `terms` has x_c >= v (terms: (c, v) with v > maxGen(c)).
  void AddCut(const std::vector<std::pair<CellId, std::uint32_t>>& terms) {
    std::vector<int> ind{0};
    std::vector<double> val{0};
    for (const auto& [c, v] : terms) ind.push_back(Indicator(c, v)), val.push_back(1);
    AddRow(ind, val, 1);
  }

  struct Solution {
    std::uint64_t bound = 0;       // proven lower bound on the program's minimum
    bool optimal = false;          // bound is the minimum and x attains it
    std::vector<std::uint32_t> x;  // per cell (0 for cells without nodes); empty if none
  };

  // Branch and bound within max_nodes nodes and max_work / rows nodes.
  Solution Solve(std::uint64_t max_nodes, std::uint64_t max_work) {
    Solution s;
    const std::uint64_t rows = static_cast<std::uint64_t>(std::max(1, glp_get_num_rows(glp_)));
    max_nodes = std::min(max_nodes, std::max<std::uint64_t>(1, max_work / rows));
    const int term = glp_term_out(GLP_OFF);
    glp_smcp smcp;
    glp_init_smcp(&smcp);
    smcp.msg_lev = GLP_MSG_OFF;
    const int lp = glp_simplex(glp_, &smcp);
    RAYCELL_CHECK(lp == 0 && glp_get_status(glp_) == GLP_OPT);
    NodeLimit limit{max_nodes, false, 0};
    glp_iocp iocp;
    glp_init_iocp(&iocp);
    iocp.msg_lev = GLP_MSG_OFF;
    iocp.cb_func = &NodeLimit::Callback;
    iocp.cb_info = &limit;
    const int rc = glp_intopt(glp_, &iocp);
    glp_term_out(term);
    const int status = glp_mip_status(glp_);
    const bool has_x = status == GLP_OPT || status == GLP_FEAS;
    if (has_x) {
      s.x.assign(max_gen_.size(), 0);
      for (std::size_t c = 0; c < max_gen_.size(); ++c) {
        if (column_[c] != 0) s.x[c] = Round(glp_mip_col_val(glp_, column_[c]));
      }
    }
    if (rc == 0 && status == GLP_OPT) {
      s.optimal = true;
      s.bound = Round(glp_mip_obj_val(glp_));
    } else {
      RAYCELL_CHECK(limit.stopped);
      double b = limit.bound;
      if (has_x) b = std::min(b, glp_mip_obj_val(glp_));
      s.bound = static_cast<std::uint64_t>(std::ceil(b - 1e-6));
    }
    return s;
  }

 private:
  struct NodeLimit {
    std::uint64_t max_nodes;
    bool stopped;
    double bound;
    static void Callback(glp_tree* tree, void* info) {
      auto* self = static_cast<NodeLimit*>(info);
      if (glp_ios_reason(tree) != GLP_ISELECT) return;
      int active = 0, current = 0, total = 0;
      glp_ios_tree_size(tree, &active, &current, &total);
      if (static_cast<std::uint64_t>(total) <= self->max_nodes) return;
      const int best = glp_ios_best_node(tree);
      self->bound = best != 0 ? glp_ios_node_bound(tree, best) : 0;
      self->stopped = true;
      glp_ios_terminate(tree);
    }
  };

  static std::uint32_t Round(double v) { return static_cast<std::uint32_t>(std::llround(v)); }

  void AddRow(const std::vector<int>& ind, const std::vector<double>& val, double rhs) {
    const int i = glp_add_rows(glp_, 1);
    glp_set_mat_row(glp_, i, static_cast<int>(ind.size()) - 1, ind.data(), val.data());
    glp_set_row_bnds(glp_, i, GLP_LO, rhs, 0);
  }

  int Indicator(CellId c, std::uint32_t v) {
    RAYCELL_CHECK(column_[c.value()] != 0);
    RAYCELL_CHECK_LT(max_gen_[c.value()], v);
    const std::uint64_t key = (std::uint64_t{c.value()} << 32) | v;
    auto it = indicator_.find(key);
    if (it != indicator_.end()) return it->second;
    const int z = glp_add_cols(glp_, 1);
    glp_set_col_kind(glp_, z, GLP_BV);
    glp_set_obj_coef(glp_, z, 0);
    // x_c - (v - maxGen) z >= maxGen.
    const int ind[] = {0, column_[c.value()], z};
    const double val[] = {0, 1, -double(v - max_gen_[c.value()])};
    const int i = glp_add_rows(glp_, 1);
    glp_set_mat_row(glp_, i, 2, ind, val);
    glp_set_row_bnds(glp_, i, GLP_LO, max_gen_[c.value()], 0);
    indicator_.emplace(key, z);
    return z;
  }

  glp_prob* glp_ = nullptr;
  std::vector<std::uint32_t> max_gen_;
  std::vector<int> column_;  // GLPK column of x_c, 0 for cells without nodes
  std::map<std::uint64_t, int> indicator_;
};

// The most total gain of pairs with no cell in common: a maximum-weight matching, solved as
// a 0/1 program (one binary per pair, each cell in at most one chosen pair). GLPK is not
// needed for a matching in principle (Edmonds), but the program is tiny and exact.
std::uint64_t MatchingGain(
    const std::vector<std::pair<std::pair<CellId, CellId>, std::uint32_t>>& pairs,
    std::uint64_t max_nodes) {
  if (pairs.empty()) return 0;
  glp_prob* p = glp_create_prob();
  glp_set_obj_dir(p, GLP_MAX);
  std::map<CellId, int> row;
  for (const auto& e : pairs) {
    for (CellId c : {e.first.first, e.first.second}) {
      if (row.count(c)) continue;
      row[c] = glp_add_rows(p, 1);
      glp_set_row_bnds(p, row[c], GLP_UP, 0, 1);
    }
  }
  for (const auto& e : pairs) {
    const int j = glp_add_cols(p, 1);
    glp_set_col_kind(p, j, GLP_BV);
    glp_set_obj_coef(p, j, e.second);
    const int ind[] = {0, row[e.first.first], row[e.first.second]};
    const double val[] = {0, 1, 1};
    glp_set_mat_col(p, j, 2, ind, val);
  }
  const int term = glp_term_out(GLP_OFF);
  glp_smcp smcp;
  glp_init_smcp(&smcp);
  smcp.msg_lev = GLP_MSG_OFF;
  glp_simplex(p, &smcp);
  glp_iocp iocp;
  glp_init_iocp(&iocp);
  iocp.msg_lev = GLP_MSG_OFF;
  (void)max_nodes;
  const int rc = glp_intopt(p, &iocp);
  glp_term_out(term);
  std::uint64_t gain = 0;
  // Any chosen set of disjoint pairs is a valid packing, so even a non-optimal answer is a
  // valid bound: sum the weights of the chosen pairs, checking they are disjoint.
  if (rc == 0 && (glp_mip_status(p) == GLP_OPT || glp_mip_status(p) == GLP_FEAS)) {
    std::map<CellId, int> used;
    for (std::size_t e = 0; e < pairs.size(); ++e) {
      if (glp_mip_col_val(p, static_cast<int>(e) + 1) < 0.5) continue;
      RAYCELL_CHECK(++used[pairs[e].first.first] == 1 && ++used[pairs[e].first.second] == 1);
      gain += pairs[e].second;
    }
  }
  glp_delete_prob(p);
  return gain;
}

// ------------------------------------------------------------------ groups

struct Group {
  GroupBound bound;
  std::unique_ptr<ScsSolver> solver;
  bool union_of_tight = false;  // made by UnionCuts (no SCS computed)
  // Count vectors (over bound.cells) known to be realisable (a witness's copies) or not.
  std::vector<std::vector<std::uint32_t>> realisable, not_realisable;
};

class Bounder {
 public:
  Bounder(const CellTree& tree, const LowerBoundOptions& options)
      : tree_(tree), options_(options), max_gen_(MaxGenerations(tree)), projector_(tree) {
    const std::uint64_t cells = std::uint64_t{options.grid[0]} * options.grid[1] * options.grid[2];
    if (cells != 0 && cells < tree.cell_count()) {
      std::ostringstream s;
      s << "lower bound option grid " << options.grid[0] << "x" << options.grid[1] << "x"
        << options.grid[2] << " has " << cells << " cells, but the tree has cells up to "
        << tree.cell_count() - 1;
      throw InputError(s.str());
    }
    paths_ = TreePaths(tree);
  }

  LowerBoundResult Run() {
    start_ = std::chrono::steady_clock::now();
    r_.max_gen = std::accumulate(max_gen_.begin(), max_gen_.end(), std::uint64_t{0});
    r_.value = r_.max_gen;
    r_.method = "maxgen";
    Stage("maxgen", r_.max_gen);
    CountProgram program(max_gen_);
    std::vector<std::string> parts;
    if (options_.pairs) {
      AddPairs(program);
      std::uint64_t gain = MatchingGain(pair_gains_, options_.max_ip_nodes);
      Stage("pairs matching", r_.max_gen + gain);
    }
    if (options_.triples && options_.pairs) AddTriples(program);
    if (options_.pairs) parts.push_back("pairs");
    if (options_.triples && options_.pairs) parts.push_back("triples");
    if (!parts.empty()) Solve(program, "ip(" + Join(parts, ",") + ")");
    if (options_.blocks) {
      AddBlocks(program);
      parts.push_back("blocks");
      Solve(program, "ip(" + Join(parts, ",") + ")");
    }
    if (options_.cuts && !parts.empty()) {
      if (Complete()) {
        Stage("ip(" + Join(parts, ",") + ")+cuts", r_.value);  // nothing left to gain
      } else {
        CutLoop(program, "ip(" + Join(parts, ",") + ")+cuts");
      }
    }
    r_.optimal = Complete() && r_.value == complete_value_;
    for (const Group& g : groups_) {
      if (g.bound.scs_lower > g.bound.max_gen_sum) r_.groups.push_back(g.bound);
    }
    return r_;
  }

 private:
  // Whether some group holds every cell with nodes and its SCS is exact: its projection is the
  // tree's paths themselves, so that SCS is the optimum (and no bound can exceed it).
  bool Complete() {
    std::size_t active = 0;
    for (std::uint32_t m : max_gen_) active += m > 0;
    for (const Group& g : groups_) {
      if (g.bound.exact && g.bound.cells.size() == active && active > 0) {
        complete_value_ = g.bound.scs_lower;
        return true;
      }
    }
    return active == 0;
  }

  void Stage(const std::string& name, std::uint64_t value) {
    if (value > r_.value) {
      r_.value = value;
      r_.method = name;
    }
    LowerBoundStage st;
    st.name = name;
    st.value = r_.value;
    st.states = r_.states;
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    r_.stages.push_back(st);
  }

  std::uint64_t StatesLeft() const {
    return r_.states >= options_.max_total_states ? 0 : options_.max_total_states - r_.states;
  }
  ScsLimits Limits() const {
    ScsLimits l;
    l.max_states = std::min(options_.max_group_states, StatesLeft());
    return l;
  }

  // The paths' projection onto `cells` (increasing): ProjectPaths(tree_, cells), at the cost
  // of those cells' nodes (TreeProjector).
  std::vector<CellString> Project(const std::vector<CellId>& cells) const {
    return projector_.Project(cells);
  }

  // Computes the SCS bound of `cells` (once per set); returns its index in groups_, or -1
  // when the set was already computed.
  int Compute(std::vector<CellId> cells) {
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    if (!seen_.insert(cells).second) return -1;
    Group g;
    g.bound.cells = cells;
    for (CellId c : cells) g.bound.max_gen_sum += max_gen_[c.value()];
    ScsLimits limits = Limits();
    if (options_.merged_parts && cells.size() >= options_.large_group_cells) {
      limits.max_states = std::min(limits.max_states, options_.max_large_group_states);
    }
    if (limits.max_states == 0) {
      // No states left: no search, and no projection either (at hundreds of cells, projecting
      // and removing dominated strings for each of thousands of groups after the budget ran
      // out cost most of the time). Such a group has no gain and no solver: the cuts skip it.
      r_.limits_reached = true;
      g.bound.scs_lower = g.bound.max_gen_sum;  // (1) summed over the group
    } else {
      g.solver = std::make_unique<ScsSolver>(Project(cells), options_.merged_parts);
      g.bound.strings = static_cast<std::uint32_t>(g.solver->strings());
      const ScsResult s = g.solver->Shortest(limits);
      g.bound.scs_lower = std::max(s.lower_bound, g.bound.max_gen_sum);
      g.bound.exact = s.exact;
      g.bound.states = std::max<std::uint64_t>(s.states, 1);
      r_.states += g.bound.states;
      if (!s.exact) r_.limits_reached = true;
    }
    groups_.push_back(std::move(g));
    return static_cast<int>(groups_.size()) - 1;
  }

  void AddIfGain(CountProgram& program, int g) {
    if (g < 0) return;
    const GroupBound& b = groups_[g].bound;
    if (b.scs_lower > b.max_gen_sum) program.AddAtLeast(b.cells, b.scs_lower);
  }

  // Pairs of cells that share a path, where the paths conflict most first. A pair (a, b) can
  // gain over maxGen(a) + maxGen(b) only when some path has an a before a b and some path a b
  // before an a: otherwise every path's projection is a^i b^j (or b^j a^i, the same order for
  // every path) with i <= maxGen(a), j <= maxGen(b), all of them subsequences of
  // a^maxGen(a) b^maxGen(b), and the SCS is the maxGen sum. Those pairs are skipped without a
  // search (no row is lost: their row would be implied by (1)). The others are searched in the
  // order of their conflicts, the fewer of the paths with a before b and with b before a, most
  // first (then by cell numbers), so that on a frame of hundreds of cells, where
  // max_total_states runs out before every pair is searched, the states go where the paths
  // cross.
  void AddPairs(CountProgram& program) {
    // Keyed by a * cells + b (a < b); visited in that order below, the cell order of the
    // pairs.
    std::unordered_map<std::uint64_t, Orders> by_key;
    std::vector<std::uint32_t> at(tree_.cell_count(), kAbsent);
    std::vector<Span> spans;
    for (const CellString& p : paths_) PathOrders(p, at, spans, by_key);
    std::vector<std::pair<std::uint64_t, Orders>> sorted(by_key.begin(), by_key.end());
    std::sort(sorted.begin(), sorted.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    const std::uint64_t cells = tree_.cell_count();
    std::vector<std::pair<std::uint32_t, std::pair<CellId, CellId>>> conflicting;
    for (const auto& [key, o] : sorted) {
      const std::pair<CellId, CellId> pair{CellId(static_cast<std::uint32_t>(key / cells)),
                                           CellId(static_cast<std::uint32_t>(key % cells))};
      together_.emplace_hint(together_.end(), pair, o.both);
      if (o.ab > 0 && o.ba > 0) conflicting.push_back({std::min(o.ab, o.ba), pair});
    }
    std::stable_sort(conflicting.begin(), conflicting.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    r_.pairs_sharing = sorted.size();
    r_.pairs_conflicting = conflicting.size();
    for (const auto& [weight, pair] : conflicting) {
      const int g = Compute({pair.first, pair.second});
      if (g < 0) continue;
      const GroupBound& b = groups_[g].bound;
      pair_gain_[pair] = b.scs_lower - b.max_gen_sum;
      if (b.scs_lower > b.max_gen_sum) pair_gains_.push_back({pair, b.scs_lower - b.max_gen_sum});
      AddIfGain(program, g);
    }
    std::sort(pair_gains_.begin(), pair_gains_.end());  // the matching's input in cell order
  }

  static constexpr std::uint32_t kAbsent = ~std::uint32_t{0};
  struct Span {
    CellId cell;
    std::uint32_t first = 0, last = 0;  // first and last position on the path
  };
  struct Orders {
    std::uint32_t both = 0;        // paths through a and b
    std::uint32_t ab = 0, ba = 0;  // of them, with some a before some b; some b before some a
  };

  // Adds one path's orders: for each pair of distinct cells on it, whether some a comes
  // before some b (ab) and some b before some a (ba), each counted once per path. `at` (all
  // kAbsent between calls) and `spans` are scratch.
  void PathOrders(const CellString& p, std::vector<std::uint32_t>& at, std::vector<Span>& spans,
                  std::unordered_map<std::uint64_t, Orders>& orders) const {
    spans.clear();
    for (std::uint32_t i = 0; i < p.size(); ++i) {
      std::uint32_t& k = at[p[i].value()];
      if (k == kAbsent) {
        k = static_cast<std::uint32_t>(spans.size());
        spans.push_back({p[i], i, i});
      } else {
        spans[k].last = i;
      }
    }
    for (const Span& s : spans) at[s.cell.value()] = kAbsent;
    std::sort(spans.begin(), spans.end(),
              [](const Span& x, const Span& y) { return x.cell < y.cell; });
    const std::uint64_t cells = tree_.cell_count();
    for (std::size_t i = 0; i < spans.size(); ++i) {
      const Span& a = spans[i];
      for (std::size_t j = i + 1; j < spans.size(); ++j) {
        const Span& b = spans[j];
        Orders& o = orders[std::uint64_t{a.cell.value()} * cells + b.cell.value()];
        ++o.both;
        if (a.first < b.last) ++o.ab;  // the first a before the last b
        if (b.first < a.last) ++o.ba;
      }
    }
  }

  std::uint32_t PairGain(CellId a, CellId b) const {
    const auto it = pair_gain_.find({std::min(a, b), std::max(a, b)});
    return it == pair_gain_.end() ? 0 : it->second;
  }

  // Triples whose three pairs share paths, the largest total pair gain first.
  void AddTriples(CountProgram& program) {
    std::vector<std::vector<CellId>> partners(tree_.cell_count());
    for (const auto& e : together_) {
      partners[e.first.first.value()].push_back(e.first.second);
    }
    std::vector<std::pair<std::uint32_t, std::array<CellId, 3>>> candidates;
    for (CellId a : CellRange(tree_.cell_count())) {
      for (std::size_t i = 0; i < partners[a.value()].size(); ++i) {
        const CellId b = partners[a.value()][i];
        for (std::size_t j = i + 1; j < partners[a.value()].size(); ++j) {
          const CellId c = partners[a.value()][j];
          if (!together_.count({b, c})) continue;
          const std::uint32_t score = PairGain(a, b) + PairGain(a, c) + PairGain(b, c);
          if (score > 0) candidates.push_back({score, {a, b, c}});
        }
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    if (candidates.size() > options_.max_triples) candidates.resize(options_.max_triples);
    for (const auto& t : candidates) {
      AddIfGain(program, Compute({t.second[0], t.second[1], t.second[2]}));
    }
  }

  void AddBlocks(CountProgram& program) {
    std::vector<std::vector<CellId>> blocks =
        options_.grid[0] != 0 ? GridBlocks() : ClusterBlocks();
    std::size_t most = options_.max_blocks;
    if (blocks.size() > options_.max_blocks && options_.grid[0] != 0 &&
        !Covers(blocks, options_.max_blocks)) {
      // More boxes than the budget, and the first max_blocks leave cells with nodes outside
      // every box (hundreds of cells: they all sit in one slab of the grid). The 2x2x2 boxes
      // that tile the grid (a board-level split, disjoint, so their bounds add in the
      // program) come first instead, all of them: a budget per cell; then the other boxes,
      // smallest first, up to max_blocks in all. (At 27 cells the first boxes cover every
      // cell, and the order stays.)
      std::vector<std::vector<CellId>> tiles = GridTiles(2);
      r_.tiles = tiles.size();
      most = std::max(options_.max_blocks, tiles.size());
      for (auto& b : blocks) {
        if (tiles.size() >= most) break;
        if (std::find(tiles.begin(), tiles.end(), b) == tiles.end()) tiles.push_back(std::move(b));
      }
      blocks = std::move(tiles);
    }
    if (blocks.size() > most) blocks.resize(most);
    // With few cells, all of them together (the tree's own SCS) comes last.
    std::vector<CellId> all;
    for (CellId c : CellRange(max_gen_.size())) {
      if (max_gen_[c.value()] > 0) all.push_back(c);
    }
    if (!all.empty() && all.size() <= options_.max_block_cells) blocks.push_back(all);
    for (const auto& b : blocks) AddIfGain(program, Compute(b));
  }

  // Boxes of neighbouring cells of the grid, smallest volume first: every shape with sides at
  // most 3 and volume 4..18, at every position; only cells with nodes are kept, and boxes
  // with fewer than 3 such cells skipped.
  std::vector<std::vector<CellId>> GridBlocks() const {
    const auto& n = options_.grid;
    std::vector<std::array<std::uint32_t, 3>> shapes;
    for (std::uint32_t dz = 1; dz <= std::min(3u, n[2]); ++dz) {
      for (std::uint32_t dy = 1; dy <= std::min(3u, n[1]); ++dy) {
        for (std::uint32_t dx = 1; dx <= std::min(3u, n[0]); ++dx) {
          const std::uint32_t v = dx * dy * dz;
          if (v >= 4 && v <= options_.max_block_cells) shapes.push_back({dx, dy, dz});
        }
      }
    }
    std::stable_sort(shapes.begin(), shapes.end(), [](const auto& a, const auto& b) {
      return a[0] * a[1] * a[2] < b[0] * b[1] * b[2];
    });
    std::vector<std::vector<CellId>> out;
    for (const auto& s : shapes) {
      for (std::uint32_t z = 0; z + s[2] <= n[2]; ++z) {
        for (std::uint32_t y = 0; y + s[1] <= n[1]; ++y) {
          for (std::uint32_t x = 0; x + s[0] <= n[0]; ++x) {
            std::vector<CellId> b;
            for (std::uint32_t k = z; k < z + s[2]; ++k) {
              for (std::uint32_t j = y; j < y + s[1]; ++j) {
                for (std::uint32_t i = x; i < x + s[0]; ++i) {
                  const CellId c(i + n[0] * (j + n[1] * k));
                  if (c.value() < max_gen_.size() && max_gen_[c.value()] > 0) b.push_back(c);
                }
              }
            }
            if (b.size() >= 3) out.push_back(b);
          }
        }
      }
    }
    return out;
  }

  // Whether the first `count` blocks hold every cell with nodes.
  bool Covers(const std::vector<std::vector<CellId>>& blocks, std::size_t count) const {
    std::vector<bool> in(max_gen_.size(), false);
    for (std::size_t i = 0; i < std::min(count, blocks.size()); ++i) {
      for (CellId c : blocks[i]) in[c.value()] = true;
    }
    for (std::size_t c = 0; c < max_gen_.size(); ++c) {
      if (max_gen_[c] > 0 && !in[c]) return false;
    }
    return true;
  }

  // The boxes of side `side` (smaller at the grid's far edges) that tile the grid, in cell
  // order of their corners; only cells with nodes are kept, and boxes with fewer than 2 such
  // cells skipped (a single cell's bound is maxGen).
  std::vector<std::vector<CellId>> GridTiles(std::uint32_t side) const {
    const auto& n = options_.grid;
    std::vector<std::vector<CellId>> out;
    for (std::uint32_t z = 0; z < n[2]; z += side) {
      for (std::uint32_t y = 0; y < n[1]; y += side) {
        for (std::uint32_t x = 0; x < n[0]; x += side) {
          std::vector<CellId> b;
          for (std::uint32_t k = z; k < std::min(n[2], z + side); ++k) {
            for (std::uint32_t j = y; j < std::min(n[1], y + side); ++j) {
              for (std::uint32_t i = x; i < std::min(n[0], x + side); ++i) {
                const CellId c(i + n[0] * (j + n[1] * k));
                if (c.value() < max_gen_.size() && max_gen_[c.value()] > 0) b.push_back(c);
              }
            }
          }
          if (b.size() >= 2) out.push_back(b);
        }
      }
    }
    return out;
  }

  // Without a grid: from every cell with nodes, grow a set by the cell sharing the most paths
  // with the set so far (smallest id on ties), keeping the sets of 4, 6 and 8 cells.
  std::vector<std::vector<CellId>> ClusterBlocks() const {
    std::vector<std::vector<CellId>> out;
    std::vector<std::map<CellId, std::uint32_t>> near(tree_.cell_count());
    for (const auto& [pair, count] : together_) {
      near[pair.first.value()][pair.second] = count;
      near[pair.second.value()][pair.first] = count;
    }
    for (CellId seed : CellRange(tree_.cell_count())) {
      if (max_gen_[seed.value()] == 0) continue;
      std::vector<CellId> set{seed};
      std::map<CellId, std::uint64_t> score;
      for (;;) {
        for (const auto& [c, n] : near[set.back().value()]) score[c] += n;
        for (CellId c : set) score.erase(c);
        if (score.empty()) break;
        auto best = score.begin();
        for (auto it = score.begin(); it != score.end(); ++it) {
          if (it->second > best->second) best = it;
        }
        set.push_back(best->first);
        if (set.size() == 4 || set.size() == 6 || set.size() == 8) out.push_back(set);
        if (set.size() == 8) break;
      }
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const auto& a, const auto& b) { return a.size() < b.size(); });
    return out;
  }

  void Solve(CountProgram& program, const std::string& name) {
    const CountProgram::Solution s = program.Solve(options_.max_ip_nodes, options_.max_ip_work);
    if (!s.optimal) r_.limits_reached = true;
    Stage(name, s.bound);
  }

  // Solve, find groups whose projection the solution's counts cannot realise, cut, repeat.
  // Groups are checked smallest first; a round ends after kCutsPerRound cuts.
  void CutLoop(CountProgram& program, const std::string& name) {
    constexpr std::size_t kCutsPerRound = 20;
    std::uint64_t best = 0;
    for (std::uint32_t round = 0; round < options_.max_cut_rounds; ++round) {
      const CountProgram::Solution s = program.Solve(options_.max_ip_nodes, options_.max_ip_work);
      if (!s.optimal) r_.limits_reached = true;
      best = std::max(best, s.bound);
      if (!s.optimal || s.x.empty()) break;
      std::size_t added = 0;
      for (std::size_t gi = 0; gi < groups_.size() && added < kCutsPerRound && StatesLeft() > 0;
           ++gi) {
        Group& g = groups_[gi];
        // Every x >= maxGen fits a group without gain; a group whose SCS search hit its limit
        // is left out (its budget searches would mostly hit the limit too).
        if (!g.union_of_tight && (g.bound.scs_lower <= g.bound.max_gen_sum || !g.bound.exact)) {
          continue;
        }
        if (g.bound.cells.size() > options_.max_cut_group_cells) continue;
        std::vector<std::uint32_t> u;
        for (CellId c : g.bound.cells) u.push_back(s.x[c.value()]);
        if (Fits(g, u) != Realisability::kNotRealisable) continue;
        program.AddCut(Lift(g, u));
        ++r_.cuts;
        ++added;
      }
      if (added == 0) added = UnionCuts(program, s.x);
      if (added == 0) break;
    }
    if (StatesLeft() == 0) r_.limits_reached = true;
    Stage(name, best);
  }

  // When no group cuts x: unions of two intersecting groups that x meets with equality (their
  // row is tight), not yet known, of at most max_cut_group_cells cells, are checked too; those
  // that x cannot realise are cut and join the groups checked in later rounds.
  std::size_t UnionCuts(CountProgram& program, const std::vector<std::uint32_t>& x) {
    constexpr std::size_t kMostUnions = 300;
    std::vector<std::size_t> tight;
    for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
      const GroupBound& b = groups_[gi].bound;
      std::uint64_t sum = 0;
      for (CellId c : b.cells) sum += x[c.value()];
      if (b.scs_lower > b.max_gen_sum && sum == b.scs_lower) tight.push_back(gi);
    }
    std::size_t added = 0, tried = 0;
    for (std::size_t i = 0; i < tight.size() && tried < kMostUnions; ++i) {
      for (std::size_t j = i + 1; j < tight.size() && tried < kMostUnions; ++j) {
        if (StatesLeft() == 0) return added;
        const std::vector<CellId>& a = groups_[tight[i]].bound.cells;
        const std::vector<CellId>& b = groups_[tight[j]].bound.cells;
        std::vector<CellId> both, either;
        std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(both));
        std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(either));
        if (both.empty() || either.size() > options_.max_cut_group_cells) continue;
        if (!seen_.insert(either).second) continue;
        ++tried;
        Group g;
        g.bound.cells = either;
        for (CellId c : either) g.bound.max_gen_sum += max_gen_[c.value()];
        g.bound.scs_lower = g.bound.max_gen_sum;  // (1); no SCS search for these
        g.solver = std::make_unique<ScsSolver>(Project(either), options_.merged_parts);
        g.bound.strings = static_cast<std::uint32_t>(g.solver->strings());
        g.union_of_tight = true;
        std::vector<std::uint32_t> u;
        for (CellId c : either) u.push_back(x[c.value()]);
        const bool cut = Fits(g, u) == Realisability::kNotRealisable;
        if (cut) {
          program.AddCut(Lift(g, u));
          ++r_.cuts;
          ++added;
        }
        groups_.push_back(std::move(g));
      }
    }
    return added;
  }

  static bool AllLessEqual(const std::vector<std::uint32_t>& a,
                           const std::vector<std::uint32_t>& b) {
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i] > b[i]) return false;
    }
    return true;
  }

  // Whether the group's projection has a common supersequence within the counts u (one per
  // cell of the group). Realisability only grows with the counts, so an answer found before
  // for counts below (realisable) or above (not realisable) answers again without a search.
  Realisability Fits(Group& g, const std::vector<std::uint32_t>& u) {
    for (const auto& r : g.realisable) {
      if (AllLessEqual(r, u)) return Realisability::kRealisable;
    }
    for (const auto& n : g.not_realisable) {
      if (AllLessEqual(u, n)) return Realisability::kNotRealisable;
    }
    std::vector<std::uint32_t> budget(tree_.cell_count(), 0);
    for (std::size_t i = 0; i < u.size(); ++i) budget[g.bound.cells[i].value()] = u[i];
    ScsLimits limits = Limits();
    limits.max_states = std::min(limits.max_states, options_.max_cut_states);
    if (limits.max_states == 0) return Realisability::kUnknown;
    const BudgetResult b = g.solver->FitsBudget(budget, limits);
    r_.states += std::max<std::uint64_t>(b.states, 1);
    if (b.answer == Realisability::kRealisable) {
      std::vector<std::uint32_t> used(u.size(), 0);  // the witness's copies: all it needs
      for (CellId c : b.witness) {
        const auto at = std::lower_bound(g.bound.cells.begin(), g.bound.cells.end(), c);
        ++used[at - g.bound.cells.begin()];
      }
      g.realisable.push_back(used);
    } else if (b.answer == Realisability::kNotRealisable) {
      g.not_realisable.push_back(u);
    }
    return b.answer;
  }

  // u is not realisable for g. Raise each coordinate in turn, one at a time, while it stays
  // not realisable (realisability only grows with the counts, so the result is a maximal such
  // vector along that order); the cut (3): some cell of g has x_c >= u_c + 1. An unknown
  // answer counts as realisable (the coordinate is not raised), which only weakens the cut.
  std::vector<std::pair<CellId, std::uint32_t>> Lift(Group& g, std::vector<std::uint32_t> u) {
    for (std::size_t i = 0; i < u.size() && u.size() <= options_.max_lift_cells; ++i) {
      const std::uint32_t most = g.solver->MostUseful(g.bound.cells[i]);
      while (u[i] < most) {
        ++u[i];
        if (Fits(g, u) != Realisability::kNotRealisable) {
          --u[i];
          break;
        }
      }
    }
    std::vector<std::pair<CellId, std::uint32_t>> cut;
    for (std::size_t i = 0; i < u.size(); ++i) {
      // u_c >= MostUseful: more copies of c never help, so x_c >= u_c + 1 is no way out and
      // the term is left out of the disjunction.
      if (u[i] < g.solver->MostUseful(g.bound.cells[i]))
        cut.push_back({g.bound.cells[i], u[i] + 1});
    }
    RAYCELL_CHECK(!cut.empty());
    return cut;
  }

  const CellTree& tree_;
  const LowerBoundOptions& options_;
  std::vector<std::uint32_t> max_gen_;
  std::vector<CellString> paths_;
  TreeProjector projector_;
  std::map<std::pair<CellId, CellId>, std::uint32_t> together_, pair_gain_;
  std::vector<std::pair<std::pair<CellId, CellId>, std::uint32_t>> pair_gains_;
  std::vector<Group> groups_;
  std::set<std::vector<CellId>> seen_;
  LowerBoundResult r_;
  std::uint64_t complete_value_ = 0;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

LowerBoundResult LowerBound(const CellTree& tree, const LowerBoundOptions& options) {
  return Bounder(tree, options).Run();
}

}  // namespace raycell
