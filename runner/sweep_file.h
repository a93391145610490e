// The sweep file's format, shared by the sweep (runner/sweep.cpp: writing, resuming,
// checkpoints) and the merge of its shards (runner/sweep_merge.cpp): the comment line's parts,
// rows read back as totals and written again. Internal to runner/; runner/sweep.h describes
// the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/replayer.h"

namespace raycell::sweep_file {

inline constexpr char kCommentStart[] = "# raycell sweep ";
inline constexpr char kFramesPart[] = " frames=";
inline constexpr char kCombinationsPart[] = " combinations=";
inline constexpr char kShardPart[] = " shard=";
inline constexpr char kCheckpointStart[] = "# raycell sweep checkpoint ";
// The totals' columns at the end of every row (runner/result_table.h, kSweepColumns).
inline constexpr std::size_t kResultColumns = 13;

// Whole decimal number, or false.
bool ParseSize(const std::string& s, std::size_t* out);
// The hash of the configuration: its TOML without the comment lines (docs/schemas.md).
std::string ConfigHash(const ReplayConfig& config);
// The lines of `text` (which ends with '\n' or is empty), without their '\n'.
std::vector<std::string> Lines(const std::string& text);
// The combination index a row starts with, or SIZE_MAX.
std::size_t RowIndex(const std::string& row);
// "PATH: line N" of data row `row` (after the comment line and the header).
std::string RowContext(const std::string& path, std::size_t row);

// A row splits into its head (index and values, as written) and the totals it prints. The
// totals' columns hold no comma or quote, so they are the last kResultColumns fields.
struct ParsedRow {
  std::size_t index = SIZE_MAX;
  std::string head;     // "index,values..." as written
  ReplayResult totals;  // the counted columns; utilisation as printed (not used to add)
};
// InputError naming `where` when `row` is not a sweep row.
ParsedRow ParseRow(const std::string& row, const std::string& where);
// Sets the utilisation of totals read back from rows. The processors are not in the row,
// but every frame's idle time is (processors x time - work - stall), so they are
// (work + stall + idle) / time.
void FinishReadTotals(ReplayResult* t, const std::string& where);
// The row of `head` with `totals`, without its '\n': the bytes SweepRow writes for the same
// totals.
std::string RowWithTotals(const std::string& head, const ReplayResult& totals);

}  // namespace raycell::sweep_file
