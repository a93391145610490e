#!/usr/bin/python3
"""Plots of a `raycell study` folder: fetches per frame per scheduler, the bracket of each
frame's optimum, and Cell Tree size per frame, one PNG each per cell grid; with --processors,
processors.png: time and fetches against the processor count (processors.csv); with --depth,
depth.png: rays, Cell Tree nodes, fetches, simulated time and image RMSE against the maximum
depth (depth.csv); with --subdivisions, subdivisions.png: bytes into the cache and fetch
stall per subdivision and scheduler (subdivisions.csv). Reads the CSVs the study wrote;
exits non-zero (and the study fails) if anything cannot be drawn.

Usage: plot_study.py STUDY_DIR [--processors] [--depth] [--subdivisions] CELLS [CELLS ...]
       e.g. plot_study.py study --processors --depth 2x2x2 3x3x3
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save_fetches_plot(fig, ax, title, path):
    """Axes in fetches per frame, the legend below them (it would hide the curves)."""
    ax.set_xlabel("frame")
    ax.set_ylabel("cell fetches (one-cell cache)")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_fetches(folder, cells):
    rows = read(f"{folder}/fetches_{cells}.csv")
    frames = [int(r["frame"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 5))
    for key, label, style in [("maxwork", "Max Work", "o-"), ("celltree", "Cell Tree", "s-"),
                              ("celltree-best", "Cell Tree, best of frame i", "D-"),
                              ("celltree-union", "Cell Tree, best of frames i-1, i", "v-"),
                              ("celltree-adaptive", "Cell Tree, adaptive", "P-"),
                              ("peel", "Peel oracle", "^:"), ("best", "best oracle", "x:"),
                              ("bound", "maxGen bound", "k--")]:
        if key in rows[0]:  # (a study folder written before the scheduler existed lacks it)
            ax.plot(frames, [int(r[key]) for r in rows], style, label=label, markersize=4)
    save_fetches_plot(fig, ax, f"Fetches per frame, {cells} cells", f"{folder}/fetches_{cells}.png")


def plot_bracket(folder, cells):
    trees = read(f"{folder}/cell_trees_{cells}.csv")
    fetches = read(f"{folder}/fetches_{cells}.csv")
    frames = [int(r["frame"]) for r in trees]
    fig, ax = plt.subplots(figsize=(7, 5))
    lower = [int(r["lower_bound"]) for r in trees]
    best = [int(r["best_length"]) for r in trees]
    ax.fill_between(frames, lower, best, color="tab:green", alpha=0.2, label="the optimum lies here")
    for values, label, style in [
            ([int(r["bound"]) for r in trees], "maxGen bound", "k--"),
            (lower, "best lower bound", "g^-"),
            (best, "best schedule found", "gv-"),
            ([int(r["peel_length"]) for r in trees], "Peel", "r.-"),
            ([int(r["maxwork"]) for r in fetches], "Max Work (fetches)", "o:"),
            ([int(r["celltree"]) for r in fetches], "Cell Tree (fetches)", "s:"),
            ([int(r["celltree-best"]) for r in fetches], "Cell Tree, best of frame i", "D:"),
            ([int(r["celltree-union"]) for r in fetches], "Cell Tree, best of frames i-1, i", "x:")]:
        ax.plot(frames, values, style, label=label, markersize=4)
    save_fetches_plot(fig, ax, f"Bracket of the optimum per frame, {cells} cells",
                      f"{folder}/bracket_{cells}.png")


def plot_trees(folder, cells):
    rows = read(f"{folder}/cell_trees_{cells}.csv")
    frames = [int(r["frame"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(frames, [int(r["rays"]) for r in rows], "o-", label="rays", markersize=4)
    ax.plot(frames, [int(r["nodes"]) for r in rows], "s-", label="Cell Tree nodes", markersize=4)
    ax.set_yscale("log")
    ax.set_xlabel("frame")
    ax.set_ylabel("count")
    ax.set_title(f"Cell Tree size per frame, {cells} cells")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(f"{folder}/cell_trees_{cells}.png", dpi=100)
    plt.close(fig)


# The schedulers of processors.csv, as the report names them, and their line styles.
PROCESSORS_SCHEDULERS = [("maxwork", "Max Work", "o-"), ("celltree", "Cell Tree", "s-"),
                         ("balanced", "balanced", "D-")]


def plot_processors(folder):
    """Two panels against the processor count (log2 axis): each scheduler's time with the time
    bound dashed, and each scheduler's fetches."""
    rows = read(f"{folder}/processors.csv")
    fig, (time_ax, fetch_ax) = plt.subplots(1, 2, figsize=(11, 4.5))
    bound = {}
    for key, label, style in PROCESSORS_SCHEDULERS:
        mine = [r for r in rows if r["scheduler"] == key]
        counts = [int(r["processors"]) for r in mine]
        time_ax.plot(counts, [int(r["time_ps"]) / 1e9 for r in mine], style, label=label,
                     markersize=4)
        fetch_ax.plot(counts, [int(r["fetches"]) for r in mine], style, label=label, markersize=4)
        for r in mine:  # where the schedulers' bounds differ, the least is below every time
            p = int(r["processors"])
            bound[p] = min(bound.get(p, float("inf")), int(r["time_bound_ps"]) / 1e9)
    counts = sorted(bound)
    time_ax.plot(counts, [bound[p] for p in counts], "k--", label="time bound (any scheduler)")
    for ax, ylabel, title in [(time_ax, "simulated time (ms), all frames", "Time"),
                              (fetch_ax, "cell fetches into the caches", "Fetches")]:
        ax.set_xscale("log", base=2)
        ax.set_xticks(counts)
        ax.set_xticklabels([str(p) for p in counts])
        ax.set_xlabel("block processors")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title} against processors")
        ax.grid(alpha=0.3, which="both")
        ax.set_ylim(bottom=0)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(f"{folder}/processors.png", dpi=100)
    plt.close(fig)


def plot_depth(folder):
    """Four panels against the maximum depth: rays (all, and spawned) and Cell Tree nodes on a
    log axis; each scheduler's fetches; each scheduler's simulated time; the image RMSE against
    the deepest setting. Record's default depth is marked on each."""
    rows = read(f"{folder}/depth.csv")
    depths = [int(r["max_depth"]) for r in rows]
    default = [int(r["max_depth"]) for r in rows if r["default"] == "1"]
    fig, axes = plt.subplots(1, 4, figsize=(16, 4))
    size_ax, fetch_ax, time_ax, error_ax = axes
    size_ax.plot(depths, [int(r["rays"]) for r in rows], "o-", label="rays", markersize=4)
    size_ax.plot(depths, [int(r["rays"]) - int(r["primary_rays"]) for r in rows], "^-",
                 label="spawned rays", markersize=4)
    size_ax.plot(depths, [int(r["nodes"]) for r in rows], "s-", label="Cell Tree nodes",
                 markersize=4)
    size_ax.set_yscale("log")
    for key, label, style in PROCESSORS_SCHEDULERS[:2]:
        fetch_ax.plot(depths, [int(r[f"fetches_{key}"]) for r in rows], style, label=label,
                      markersize=4)
        time_ax.plot(depths, [int(r[f"time_{key}_ps"]) / 1e9 for r in rows], style, label=label,
                     markersize=4)
    error_ax.plot(depths, [float(r["rmse"]) for r in rows], "o-", color="tab:red",
                  label=f"against max depth {depths[-1]}", markersize=4)
    for ax, ylabel, title in [(size_ax, "count, all frames", "Rays and Cell Tree nodes"),
                              (fetch_ax, "cell fetches (one-cell cache)", "Fetches"),
                              (time_ax, "simulated time (ms), all frames", "Time"),
                              (error_ax, "image RMSE", "Image error")]:
        for d in default:
            ax.axvline(d, color="grey", linestyle=":", label="record's default")
        ax.set_xticks(depths)
        ax.set_xlabel("max depth (reflection, refraction)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title} against max depth")
        ax.grid(alpha=0.3, which="both")
        if ax is not size_ax:
            ax.set_ylim(bottom=0)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(f"{folder}/depth.png", dpi=100)
    plt.close(fig)


def plot_subdivisions(folder):
    """Two panels per SPEC, bars per scheduler: bytes into the cache (board->cache link) and
    fetch stall, each against the first SPEC's (the uniform grid)."""
    rows = read(f"{folder}/subdivisions.csv")
    specs = list(dict.fromkeys(r["spec"] for r in rows))
    schedulers = list(dict.fromkeys(r["scheduler"] for r in rows))
    fig, (bytes_ax, stall_ax) = plt.subplots(1, 2, figsize=(12, 4.5))
    width = 0.8 / len(schedulers)
    for i, sched in enumerate(schedulers):
        by_spec = {r["spec"]: r for r in rows if r["scheduler"] == sched}
        xs = [k + (i - (len(schedulers) - 1) / 2) * width for k in range(len(specs))]
        bytes_ax.bar(xs, [int(by_spec[s]["cache_bytes"]) / 1e6 for s in specs], width,
                     label=sched)
        stall_ax.bar(xs, [int(by_spec[s]["stall_ps"]) / 1e9 for s in specs], width, label=sched)
    for ax, ylabel, title in [(bytes_ax, "MB into the cache, all frames", "Bytes moved"),
                              (stall_ax, "fetch stall (ms), all frames", "Stall")]:
        ax.set_xticks(range(len(specs)))
        ax.set_xticklabels(specs, rotation=25, ha="right", fontsize=8)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title} per subdivision")
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(f"{folder}/subdivisions.png", dpi=100)
    plt.close(fig)


def main():
    args = sys.argv[1:]
    processors = "--processors" in args
    depth = "--depth" in args
    subdivisions = "--subdivisions" in args
    args = [a for a in args if a not in ("--processors", "--depth", "--subdivisions")]
    if len(args) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    folder = args[0]
    for cells in args[1:]:
        plot_fetches(folder, cells)
        plot_bracket(folder, cells)
        plot_trees(folder, cells)
    if processors:
        plot_processors(folder)
    if depth:
        plot_depth(folder)
    if subdivisions:
        plot_subdivisions(folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
