#include "scheduling/plan_cache.h"

#include "base/hash.h"
#include "graph/peel.h"

namespace raycell {

std::uint64_t TreeKey(const CellTree& tree) { return tree.ContentKey(); }

std::uint64_t BoardKey(const std::vector<CellId>& board_cell_of) {
  Hash64 h;
  h.Add(board_cell_of.size());
  for (CellId c : board_cell_of) h.Add(c.value());
  return h.Finish();
}

std::uint64_t PlanKey(std::uint64_t kind, std::initializer_list<std::uint64_t> parts) {
  Hash64 h;
  h.Add(kind);
  h.Add(parts.size());
  for (std::uint64_t p : parts) h.Add(p);
  return h.Finish();
}

std::shared_ptr<const std::vector<CellId>> SharedPeel(PlanCache* cache, const CellTree& tree) {
  return Shared<std::vector<CellId>>(cache, PlanKey(kPeelPlan, {TreeKey(tree)}),
                                     [&] { return Peel(tree).schedule; });
}

std::shared_ptr<const CellTree> SharedUnion(PlanCache* cache, const CellTree& before,
                                            const CellTree& previous) {
  return Shared<CellTree>(cache, PlanKey(kUnionTree, {TreeKey(before), TreeKey(previous)}), [&] {
    return UnionShape({&before, &previous});
  });
}

}  // namespace raycell
