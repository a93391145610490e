// What a study writes into its folder, from its StudyResult: report.md (the tables of every
// grid, the several processors table of the finest grid, the run time against error table and
// the depth and subdivision tables), the CSV behind each table (cell_trees_*.csv,
// fetches_*.csv, processors.csv, accuracy/accuracy.csv, depth.csv, subdivisions.csv) and the plots
// drawn from those CSVs by tools/plot_study.py and tools/plot_accuracy.py (python3 with
// matplotlib). The texts are functions of the result alone, so tests can check them without running
// a study.
#pragma once

#include <string>
#include <vector>

#include "study/accuracy.h"
#include "study/study.h"

namespace raycell {

// Per frame: rays, nodes, bound, Peel, optimum, the bracket of the optimum and its gap.
std::string TreesCsv(const GridStudy& g);
// Per frame: the fetches of every studied scheduler, the bound and the bracket.
std::string FetchesCsv(const GridStudy& g);
// One grid's section of report.md: its summary table and the bracket of the optimum.
std::string GridReport(const GridStudy& g);
// processors.csv, one row per GridStudy::processors entry, in its order: scheduler,
// processors, then the total's fetches, time_ps, time_bound_ps, work_ps, stall_ps, idle_ps (as
// docs/schemas.md defines them for a replay) and utilisation (4 decimals, as sweep prints it).
std::string ProcessorsCsv(const GridStudy& g);
// report.md's several processors section of the grid: per processor count each scheduler's
// fetches, time and utilisation, the time bound and the fastest's time over it; empty when
// the grid has no such replays.
std::string ProcessorsReport(const GridStudy& g);
// accuracy.csv, one line per row, as Python's csv.DictWriter writes such rows (CRLF line
// ends, a field quoted when it holds a comma, floats as Python's repr, True/False).
std::string AccuracyCsv(const std::vector<AccuracyRow>& rows);
// The Markdown table of the rows (seconds and ratio to two decimals, error to four, fetch
// change in percent with its sign, "yes" for the default settings).
std::string AccuracyTable(const std::vector<AccuracyRow>& rows);
// report.md's run time against error section: the table, or why it was not measured; empty
// when it was not asked for.
std::string AccuracyReport(const AccuracyStudy& a);
// depth.csv, one row per DepthStudy row, in its order: max_depth, default (1 for record's
// default max depth, else 0), rays, primary_rays, reflection_rays, refraction_rays,
// shadow_rays, nodes (Cell Tree nodes), fetches_maxwork, fetches_celltree, time_maxwork_ps,
// time_celltree_ps (summed over the frames), rmse (image RMSE against max depth 5, as Python's
// repr prints the float).
std::string DepthCsv(const DepthStudy& d);
// report.md's depth section: the table, or why it was not measured; empty when the result has
// neither (a DepthStudy never measured).
std::string DepthReport(const DepthStudy& d);
// subdivisions.csv, one row per SubdivisionStudy row, in its order: spec, scheduler, cells,
// footprint_min, footprint_median, footprint_max, fetches, cache_bytes, board_bytes,
// stall_ps, time_ps (totals over the frames).
std::string SubdivisionsCsv(const SubdivisionStudy& d);
// report.md's subdivision section: the table (changes against the first SPEC under the same
// scheduler), or why it was not measured; empty when neither.
std::string SubdivisionsReport(const SubdivisionStudy& d);
// report.md.
std::string StudyReport(const StudyResult& r);
// Runs the plot script `name` (tools/plot_*.py, found beside the running binary or in its
// ../share/raycell) with python3 and `args`. InputError naming the command if it fails (no
// matplotlib).
void RunPlotScript(const std::string& name, const std::vector<std::string>& args);

// Draws DIR/accuracy.png from DIR/accuracy.csv. InputError if it cannot (no matplotlib).
void PlotAccuracy(const std::string& dir);
// Writes report.md, the CSVs and the plots into the study's folder; returns report.md's path.
// InputError if the plots cannot be drawn.
std::string WriteStudyReport(const StudyResult& r);
// The "On the suite" section: the suite's headlines read from options.suite, or how to get
// them.
std::string SuiteHeadlinesReport(const StudyResult& r);

}  // namespace raycell
