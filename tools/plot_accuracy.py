#!/usr/bin/python3
"""The plot of a study's run time against error: DIR/accuracy.png from DIR/accuracy.csv (as
`raycell study` writes them into STUDY/accuracy/), one panel per kind of error: the renderer's
image RMSE against its finest step, the image RMSE of the max depth rows against the deepest,
and the replay's error in simulated time, each against the run time as a ratio to the most
accurate setting. Exits non-zero (and the study fails) if it cannot be drawn.

Usage: plot_accuracy.py DIR     e.g. plot_accuracy.py study/accuracy
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    folder = sys.argv[1]
    rows = read(os.path.join(folder, "accuracy.csv"))
    deepest = max((int(r["value"]) for r in rows if r["knob"] == "max depth"), default=5)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4))
    for ax, part, ylabel in ((axes[0], "renderer", "image RMSE against step 0.25"),
                             (axes[1], "max depth", f"image RMSE against max depth {deepest}"),
                             (axes[2], "replay", "relative error in simulated time")):
        for knob in sorted({r["knob"] for r in rows if r["knob"].startswith(part)}):
            pts = [(float(r["time_ratio"]), float(r["error"]), r["value"]) for r in rows
                   if r["knob"] == knob]
            # In the order of the setting: a depth's time is noisy, its error is not.
            pts.sort(key=(lambda p: int(p[2])) if part == "max depth" else (lambda p: p[0]))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-",
                    label=knob[len(part) + 1:] or knob)
            for p in pts:
                ax.annotate(p[2], (p[0], p[1]), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_xlabel("run time, ratio to the most accurate setting")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{part.capitalize()}: run time against error")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "accuracy.png"), dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
