#!/usr/bin/env python3
"""Tests tools/check_deps.py: the tree as it is passes, and each planted wrong include in a
small tree of the same layout fails with a line naming it. Run by ctest (check_deps_test).

Usage: tests/tools/check_deps_test.py ROOT
"""
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
CHECK = ROOT / "tools" / "check_deps.py"

# (file planted, the include it holds, whether the order allows it)
CASES = [
    ("analysis/a.cpp", "bounds/lower_bound.h", True),
    ("analysis/a.cpp", "search/optimum.h", True),
    ("scheduling/s.cpp", "search/best_schedule.h", True),
    ("replay/r.cpp", "engine/slot_queue.h", True),
    ("tools/t.cpp", "record/scene.h", True),
    ("tools/t.cpp", "study/study.h", True),
    ("study/s.cpp", "record/recorder.h", True),
    ("study/s.cpp", "runner/driver.h", True),
    ("study/s.h", "analysis/analysis.h", True),
    ("graph/g.h", "search/optimum.h", False),       # the core above the searches
    ("graph/g.cpp", "bounds/scs.h", False),
    ("bounds/b.cpp", "search/late_bound.h", False),  # siblings
    ("search/s.cpp", "bounds/lower_bound.h", False),
    ("search/s.cpp", "analysis/analysis.h", False),  # upward
    ("bounds/b.h", "analysis/analysis.h", False),
    ("scheduling/s.h", "bounds/lower_bound.h", False),  # would link GLPK
    ("scheduling/s.cpp", "analysis/analysis.h", False),
    ("replay/r.cpp", "analysis/analysis.h", False),
    ("replay/r.cpp", "bounds/scs.h", False),
    ("engine/e.h", "graph/cell_tree.h", False),
    ("replay/r.cpp", "record/scene.h", False),
    ("replay/r.cpp", "study/study.h", False),  # the study stands on replay and analysis
    ("runner/r.cpp", "replay/replayer.h", True),
    ("tools/t.cpp", "runner/sweep.h", True),
    ("replay/r.cpp", "runner/driver.h", False),  # the model sees no runner
    ("replay/r.h", "runner/result_table.h", False),
    ("runner/r.cpp", "analysis/analysis.h", False),  # would link GLPK
    ("runner/r.cpp", "study/study.h", False),
    ("tools/bench/b.cpp", "tests/oracle/simulator.h", True),  # a benchmark against the oracle
    ("tools/t.cpp", "tests/oracle/simulator.h", False),
    ("replay/r.cpp", "tests/oracle/simulator.h", False),
    ("tools/bench/b.cpp", "tests/test_util.h", False),
    ("analysis/a.h", "study/report.h", False),
    ("record/r.cpp", "study/accuracy.h", False),
    ("study/s.cpp", "tools/commands.h", False),
    ("traces/x.cpp", "openvdb/openvdb.h", False),
    ("base/x.h", "traces/trace_reader.h", False),
]


def run(root):
    return subprocess.run([sys.executable, str(CHECK), str(root)], capture_output=True,
                          text=True)


def main():
    failures = []
    real = run(ROOT)
    if real.returncode != 0:
        failures.append(f"the tree itself fails:\n{real.stdout}")
    for path, target, allowed in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            f = pathlib.Path(tmp) / path
            f.parent.mkdir(parents=True)
            f.write_text(f'#include "{target}"\n' if "openvdb" not in target else
                         f"#include <{target}>\n")
            r = run(tmp)
            named = f"{path}:1:" in r.stdout
            if allowed and r.returncode != 0:
                failures.append(f"{path} including {target} refused:\n{r.stdout}")
            if not allowed and (r.returncode != 1 or not named):
                failures.append(f"{path} including {target} not refused "
                                f"(exit {r.returncode}):\n{r.stdout}")
    for f in failures:
        print("FAIL:", f)
    print(f"check_deps_test: {len(CASES) + 1 - len(failures)} of {len(CASES) + 1} cases pass")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
