// Parts of a sharded `raycell analyze` and their merge (docs/design.md §6 "Sharded
// analysis"). A part is what `raycell analyze TRACE --frames A..B --part FILE` writes: one line
// naming the analysis (the trace by content, the options that change the output, the frames
// A..B), then exactly the bytes the same command prints on stdout. `raycell analyze merge`
// joins parts into the bytes of one unsharded run.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "traces/trace_reader.h"

namespace raycell {

// What a part's first line says.
struct AnalyzePartInfo {
  std::string format;            // table, json or csv
  std::string options;           // the options that change the output, canonical ("--bracket ...")
  int first = 0, last = 0;       // the frame numbers asked for, inclusive
  std::uint64_t trace_hash = 0;  // TraceFingerprint of the trace
  std::string trace;             // its path, as given (for messages only)
};

// A hash of what an analysis reads from the trace: the cell grid and every frame's number,
// totals and checksum of its rays (from the index; no frame is decoded). Two traces with the
// same rays, e.g. a one-shot recording and the concatenation of its frame ranges, have the
// same fingerprint, whatever their paths.
std::uint64_t TraceFingerprint(const TraceReader& reader);

// "# raycell analyze part schema=... frames=A..B ...\n"
std::string AnalyzePartLine(const AnalyzePartInfo& info);

// Reads the parts, checks that they come from one trace (by fingerprint), one format and the
// same options, that their frame ranges neither overlap nor leave a gap, and that every row
// lies in its part's range; then writes, through OUT.tmp, the output of one run over the
// union of the ranges (the header once, the rows in frame order). InputError otherwise, and
// nothing written.
void MergeAnalyzeParts(const std::vector<std::string>& parts, const std::string& out);

}  // namespace raycell
