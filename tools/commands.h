// The raycell subcommands. Each Add* registers its options on the app; the command runs from
// the callback and reports bad input as InputError.
#pragma once

#include <CLI/CLI.hpp>

namespace raycell {

void AddRecordCommand(CLI::App& app);
void AddTraceCommand(CLI::App& app);
void AddAnalyzeCommand(CLI::App& app);
void AddReplayCommand(CLI::App& app);
void AddStudyCommand(CLI::App& app);
void AddSuiteCommand(CLI::App& app);
void AddSweepCommand(CLI::App& app);

// The help of `--cells SPEC` for the commands that read a regroupable capture regrouped
// (analyze, replay, sweep; `trace regroup --help` explains each SPEC).
inline constexpr const char* kCellsSpecHelp =
    "a regroupable capture (`record --regroupable`) regrouped into this subdivision: NXxNYxNZ, "
    "grid:NXxNYxNZ, grid:N:crossings, kd:N:footprint, kd:N:work, kd:N:sqrt, kd:budget:BYTES, "
    "octree:BYTES, dynamic:N[:sqrt], auto:N (see `raycell trace regroup --help`); default: its own "
    "grid";

}  // namespace raycell
