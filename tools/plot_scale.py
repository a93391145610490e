#!/usr/bin/python3
"""scale.png of a `raycell study` folder, from its scale.csv: each command's wall time and peak
memory against the visits of the capture (the visits series) and against its cells (the cells
series), on log-log axes. Exits non-zero (and the study fails) if anything cannot be drawn.

Usage: plot_scale.py STUDY_DIR
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    folder = sys.argv[1]
    with open(f"{folder}/scale.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    commands = []
    for r in rows:
        if r["command"] not in commands:
            commands.append(r["command"])
    fig, axes = plt.subplots(2, 2, figsize=(10, 8))
    panels = [("visits", "visits", "seconds", "wall time, s"),
              ("visits", "visits", "peak_mb", "peak memory, MB"),
              ("cells", "cell_count", "seconds", "wall time, s"),
              ("cells", "cell_count", "peak_mb", "peak memory, MB")]
    for ax, (series, x_field, y_field, ylabel) in zip(axes.flat, panels):
        for command in commands:
            points = sorted((float(r[x_field]), float(r[y_field])) for r in rows
                            if r["command"] == command and r["series"] in (series, "both"))
            ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=command)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("visits in the capture" if series == "visits" else "cells")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", linewidth=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Scale: record, analyze, replay (Max Work, 1 processor)")
    fig.tight_layout()
    fig.savefig(f"{folder}/scale.png", dpi=100)


if __name__ == "__main__":
    main()
