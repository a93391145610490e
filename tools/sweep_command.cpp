// raycell sweep: one replay per combination of varied configuration keys, one CSV row each
// (runner/sweep.h), and `raycell sweep merge` to join the files of sharded runs.
#include <algorithm>
#include <iostream>
#include <memory>

#include "base/check.h"
#include "base/parallel.h"
#include "base/progress.h"
#include "replay/config.h"
#include "runner/sweep.h"
#include "tools/commands.h"
#include "tools/frames.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct SweepArgs {
  std::string trace, config, frames, shard, out, cells;
  std::vector<std::string> varies;
  unsigned jobs = HardwareThreads();
  bool quiet = false;
  std::string merge_out;
  std::vector<std::string> merge_shards;
};

SweepSpec MakeSpec(const SweepArgs& a) {
  SweepSpec spec;
  spec.trace = a.trace;
  spec.cells = a.cells;
  spec.config = a.config;
  spec.base = a.config.empty() ? DefaultConfig() : LoadConfig(a.config);
  for (const std::string& v : a.varies) spec.varies.push_back(Vary::Parse(v));
  spec.frames = a.frames;
  if (!a.shard.empty()) spec.shard = Shard::Parse(a.shard);
  ValidateVaries(spec.base, spec.varies);  // before the trace is even opened
  return spec;
}

void Run(const SweepArgs& a) {
  if (a.trace.empty()) throw InputError("give a TRACE file to sweep");
  if (a.out.empty()) throw InputError("give --out FILE.csv");
  if (a.jobs < 1) throw InputError("--jobs must be at least 1");
  SweepSpec spec = MakeSpec(a);
  const TraceReader reader = TraceReader::Open(a.trace, a.cells);
  if (!reader.warning().empty()) std::cerr << "raycell: warning: " << reader.warning() << "\n";
  spec.frame_indices = SelectFrameRange(reader, a.frames);
  Progress progress(!a.quiet);
  SweepOptions options;
  options.jobs = a.jobs;
  options.progress = [&](double f) { progress.Update(f, "sweeping"); };
  const SweepOutcome outcome = RunSweep(reader, spec, a.out, options);
  progress.Done();
  if (!a.quiet && outcome.resumed > 0) {
    std::cerr << "raycell: resumed " << outcome.resumed << " rows from " << a.out
              << ".partial, ran " << outcome.ran << "\n";
  }
  if (!a.quiet && outcome.frames_resumed > 0) {
    std::cerr << "raycell: resumed " << outcome.frames_resumed << " frames of totals from " << a.out
              << ".checkpoint\n";
  }
}

constexpr char kFooter[] =
    "Every combination of the --vary values is one replay of the selected frames and one CSV\n"
    "row. Combinations are numbered from 0, row-major over the --vary options in the order\n"
    "given (the last one varies fastest); every combination is checked against the\n"
    "configuration before any replay runs.\n\n"
    "Each frame is decoded once for up to 4096 combinations (a block): the frames are the\n"
    "outer loop, every combination of the block is replayed on a frame (on --jobs threads)\n"
    "before the next frame is decoded, and combinations that can only differ in what no\n"
    "result depends on (the seed of a scheduler that is not random, the granularity auto\n"
    "resolves to, ...) are replayed once.\n\n"
    "The file starts with a comment line naming the sweep (trace, config and its hash, varies,\n"
    "frames, combination count, shard), then the header\n"
    "  index,<varied keys>,fetches,bound,time_ps,time_bound_ps,work_ps,stall_ps,idle_ps,\n"
    "  utilisation,peak_queued_rays,peak_queued_bytes,rays,segments,samples\n"
    "with totals over the frames (bound empty where it does not hold; time_bound_ps a lower\n"
    "bound on time_ps under any scheduler). Rows come in index order and the file is\n"
    "byte-identical whatever --jobs is.\n\n"
    "Interrupting: rows are appended to OUT.partial as their block completes, in order;\n"
    "inside a block, the totals so far are saved to OUT.checkpoint after a frame (at most once\n"
    "a second). OUT.partial becomes OUT when all are done. After Ctrl-C (or a crash) rerun the\n"
    "same command: it keeps the rows in OUT.partial, resumes the block from OUT.checkpoint and\n"
    "runs the rest, and writes the same bytes as an uninterrupted run. A .partial or\n"
    ".checkpoint of a different sweep is an error, never reused; delete them to start again.\n\n"
    "Sharding: --shard I/N (0-based, 0 <= I < N) runs the combinations with index % N == I;\n"
    "--frames A..B runs a range of frames, and runs over disjoint ranges are frame shards of\n"
    "one sweep. `raycell sweep merge OUT SHARD...` checks that the files are shards of one\n"
    "sweep covering every combination, and every frame of one range A..B, exactly once, and\n"
    "writes the file an unsharded run writes, byte for byte: rows of one combination over\n"
    "different frames add up (sums; peaks as maxima; utilisation from the summed times),\n"
    "and the comment then says frames=\"A..B\", as a run with --frames A..B does.\n\n"
    "Examples:\n"
    "  raycell sweep capture.rct --vary scheduler=maxwork,celltree,peel \\\n"
    "      --vary processors.count=1,2 --jobs 2 --out sweep.csv\n"
    "  raycell sweep capture.rct --config gicube.toml \\\n"
    "      --vary \"level.cache.capacity=1 cell,2 cells,64MiB\" --out cache.csv\n"
    "  raycell sweep capture.rct --vary scheduler=maxwork,peel --shard 0/2 --out s0.csv\n"
    "  raycell sweep capture.rct --vary scheduler=maxwork,peel --shard 1/2 --out s1.csv\n"
    "  raycell sweep merge sweep.csv s0.csv s1.csv\n"
    "  raycell sweep capture.rct --vary scheduler=maxwork,peel --frames 0..14 --out f0.csv\n"
    "  raycell sweep capture.rct --vary scheduler=maxwork,peel --frames 15..29 --out f1.csv\n"
    "  raycell sweep merge frames.csv f0.csv f1.csv";

void AddMerge(CLI::App* cmd, const std::shared_ptr<SweepArgs>& args) {
  CLI::App* merge = cmd->add_subcommand(
      "merge",
      "Join the files of `raycell sweep --shard I/N` and `--frames A..B` runs into the "
      "unsharded file.");
  merge->add_option("OUT", args->merge_out, "merged CSV file to write")->required();
  merge->add_option("SHARDS", args->merge_shards, "the shard files, each shard once")->required();
  merge->callback([args] { MergeSweepShards(args->merge_out, args->merge_shards); });
}

}  // namespace

void AddSweepCommand(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "Replay a trace once per combination of varied configuration keys, into a CSV.");
  cmd->footer(kFooter);
  cmd->require_subcommand(0, 1);
  cmd->add_option("TRACE", args->trace, "trace file written by `raycell record`");
  cmd->add_option("--cells", args->cells, kCellsSpecHelp);
  cmd->add_option("--config", args->config, "TOML configuration (default: the GI-Cube defaults)");
  cmd->add_option("--vary", args->varies,
                  "KEY=V1,V2,... a configuration key and its values (repeatable), e.g. "
                  "processors.count=1,2,4; keys as `raycell replay --set` takes them");
  cmd->add_option("--frames", args->frames, "frame numbers A..B (default: all)");
  cmd->add_option("--jobs", args->jobs, "worker threads (default: the hardware threads)");
  cmd->add_option("--shard", args->shard, "I/N: run only combinations with index % N == I");
  cmd->add_option("--out", args->out,
                  "CSV file to write (OUT.partial and OUT.checkpoint while running)");
  cmd->add_flag("--quiet", args->quiet, "no progress bar or resume message");
  AddMerge(cmd, args);
  cmd->callback([cmd, args] {
    if (cmd->got_subcommand("merge")) return;
    Run(*args);
  });
}

}  // namespace raycell
