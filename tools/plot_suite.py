#!/usr/bin/python3
"""suite.png of a `raycell suite` folder, from its suite.csv: per scene, each scheduler's change
in fetches and in time after frame 0 against Max Work on the board of several processors, the
online schedulers' fetches over the oracle's at one processor, and, where the scenes were
regrouped, each subdivision's change in cache bytes against the uniform grid. Exits non-zero
(and the suite fails) if anything cannot be drawn.

Usage: plot_suite.py SUITE_DIR PROCESSORS
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    folder, processors = sys.argv[1], sys.argv[2]
    with open(f"{folder}/suite.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])

    def value(scene, kind, name, sched, procs, field):
        for r in rows:
            if (r["scene"], r["kind"], r["name"], r["scheduler"], r["processors"]) == (
                    scene, kind, name, sched, procs):
                return float(r[field])
        return math.nan

    def bars(ax, series, title, ylabel, base_line):
        width = 0.8 / max(1, len(series))
        for i, (label, values) in enumerate(series):
            ax.bar([x + i * width for x in range(len(scenes))], values, width, label=label)
        ax.axhline(base_line, color="black", linewidth=0.8)
        ax.set_xticks([x + (len(series) - 1) * width / 2 for x in range(len(scenes))])
        ax.set_xticklabels(scenes, rotation=45, ha="right", fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.legend(fontsize=6, ncol=3)
        ax.grid(alpha=0.3, axis="y")

    many = [n for n in dict.fromkeys(r["name"] for r in rows
                                     if r["kind"] == "scheduler" and r["processors"] == processors)
            if n != "maxwork"]
    one = [n for n in dict.fromkeys(r["name"] for r in rows
                                    if r["kind"] == "scheduler" and r["processors"] == "1")
           if n not in ("best",)]
    specs = list(dict.fromkeys(r["name"] for r in rows if r["kind"] == "cells"))
    cell_scheds = list(dict.fromkeys(r["scheduler"] for r in rows if r["kind"] == "cells"))
    panels = 3 + (1 if specs else 0)
    fig, axes = plt.subplots(panels, 1, figsize=(10, 3.2 * panels))

    def change(s, name, field):
        base = value(s, "scheduler", "maxwork", "maxwork", processors, field)
        v = value(s, "scheduler", name, name, processors, field)
        return 100 * (v / base - 1) if base > 0 else math.nan

    bars(axes[0], [(n, [change(s, n, "fetches") for s in scenes]) for n in many],
         f"{processors} processors: fetches against Max Work", "change (%)", 0)
    bars(axes[1], [(n, [change(s, n, "time_after_first_ps") for s in scenes]) for n in many],
         f"{processors} processors: time after frame 0 against Max Work", "change (%)", 0)

    def over_best(s, name):
        best = value(s, "scheduler", "best", "best", "1", "fetches")
        return value(s, "scheduler", name, name, "1", "fetches") / best if best > 0 else math.nan

    bars(axes[2], [(n, [over_best(s, n) for s in scenes]) for n in one],
         "1 processor: fetches over the oracle's (best)", "ratio", 1)
    if specs:
        sched = cell_scheds[-1]
        base_spec = specs[0]

        def cells_change(s, spec):
            base = value(s, "cells", base_spec, sched, "1", "cache_bytes")
            v = value(s, "cells", spec, sched, "1", "cache_bytes")
            return 100 * (v / base - 1) if base > 0 else math.nan

        bars(axes[3], [(spec, [cells_change(s, spec) for s in scenes]) for spec in specs[1:]],
             f"subdivisions under {sched}: cache bytes against {base_spec}", "change (%)", 0)
    fig.tight_layout()
    fig.savefig(f"{folder}/suite.png", dpi=90)


if __name__ == "__main__":
    main()
