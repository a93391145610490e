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
void AddSweepCommand(CLI::App& app);

}  // namespace raycell
