#!/usr/bin/python3
"""Plots of a `raycell study` folder: fetches per frame per scheduler and Cell Tree size per
frame, one PNG each per cell grid. Reads the CSVs the study wrote; exits non-zero (and the
study fails) if anything cannot be drawn.

Usage: plot_study.py STUDY_DIR CELLS [CELLS ...]     e.g. plot_study.py study 2x2x2 3x3x3
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def plot_fetches(folder, cells):
    rows = read(f"{folder}/fetches_{cells}.csv")
    frames = [int(r["frame"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, label, style in [("maxwork", "Max Work", "o-"), ("celltree", "Cell Tree", "s-"),
                              ("peel", "Peel oracle", "^-"), ("bound", "maxGen bound", "k--")]:
        ax.plot(frames, [int(r[key]) for r in rows], style, label=label, markersize=4)
    ax.set_xlabel("frame")
    ax.set_ylabel("cell fetches (one-cell cache)")
    ax.set_title(f"Fetches per frame, {cells} cells")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(f"{folder}/fetches_{cells}.png", dpi=100)
    plt.close(fig)


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


def main():
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    folder = sys.argv[1]
    for cells in sys.argv[2:]:
        plot_fetches(folder, cells)
        plot_trees(folder, cells)
    return 0


if __name__ == "__main__":
    sys.exit(main())
