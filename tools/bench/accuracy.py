#!/usr/bin/python3
"""Run time against error for the knobs that trade one for the other (issue 5).

Renderer step size, early-termination cutoff and the marcher's precision: capture time (as a ratio to the most
accurate setting measured in the same run) against the image RMSE to a reference rendered
with a four times finer step than the default, and against the change in Cell Tree
scheduling's fetch count. Replay granularity: replay time against the error in fetches and
simulated time. Prints a Markdown table and writes accuracy.csv and accuracy.png.

Usage: tools/bench/accuracy.py [--scene builtin|FILE.vdb] [--res 128x128] [--frames 4]
                               [--out bench-out/accuracy]
"""
import argparse
import csv
import os
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RAYCELL = os.environ.get("RAYCELL", os.path.join(ROOT, "build", "tools", "raycell"))


def run(args):
    t0 = time.perf_counter()
    subprocess.run([RAYCELL] + args, check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return time.perf_counter() - t0


def record(opts, name, extra):
    out = os.path.join(opts.out, name)
    os.makedirs(out, exist_ok=True)
    args = ["record", "--scene", opts.scene, "--res", opts.res, "--orbit",
            f"{opts.frames}:20", "--cells", "3x3x3", "--out", os.path.join(out, "c.rct"),
            "--images", out, "--quiet"] + extra
    return run(args), out


def images(folder, frames):
    return [mpimg.imread(os.path.join(folder, f"frame_{i:04d}.png"))[..., :3].astype(float)
            for i in range(frames)]


def rmse(a, b):
    return float(np.sqrt(np.mean([np.mean((x - y) ** 2) for x, y in zip(a, b)])))


def replay(trace, granularity="ray", sample=1):
    t0 = time.perf_counter()
    p = subprocess.run([RAYCELL, "replay", trace, "--granularity", granularity, "--format",
                        "csv", "--quiet", "--sample", str(sample)], check=True,
                       stdout=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - t0
    total = [r for r in csv.DictReader(p.stdout.splitlines()) if r["frame"] == "total"][0]
    return seconds, int(total["fetches"]), int(total["time_ps"])


def renderer_rows(opts):
    ref_time, ref_dir = record(opts, "reference", ["--step", "0.25", "--shadow-step", "0.75"])
    ref_img = images(ref_dir, opts.frames)
    _, ref_fetches, _ = replay(os.path.join(ref_dir, "c.rct"))
    rows = []
    knobs = [("step", s, ["--step", str(s), "--shadow-step", str(3 * s)]) for s in (0.5, 1, 2, 4)]
    knobs += [("cutoff", c, ["--cutoff", str(c)]) for c in (0.001, 0.02, 0.05)]
    knobs += [("precision", "single", ["--precision", "single"])]  # step 1, as the default
    for knob, value, extra in knobs:
        seconds, folder = record(opts, f"{knob}-{value}", extra)
        _, fetches, _ = replay(os.path.join(folder, "c.rct"))
        rows.append({"knob": f"renderer {knob}", "value": value, "seconds": seconds,
                     "time_ratio": seconds / ref_time,
                     "error": rmse(images(folder, opts.frames), ref_img),
                     "error_kind": "image RMSE vs step 0.25",
                     "fetch_change": (fetches - ref_fetches) / ref_fetches,
                     "default": (knob == "step" and value == 1)})
    rows.insert(0, {"knob": "renderer step", "value": 0.25, "seconds": ref_time,
                    "time_ratio": 1.0, "error": 0.0, "error_kind": "reference",
                    "fetch_change": 0.0, "default": False})
    return rows, os.path.join(opts.out, "step-1", "c.rct")


def granularity_rows(trace):
    ray = replay(trace, "ray")
    node = replay(trace, "node")
    return [{"knob": "replay granularity", "value": g, "seconds": r[0], "time_ratio": r[0] / ray[0],
             "error": abs(r[2] - ray[2]) / ray[2], "error_kind": "simulated time, relative",
             "fetch_change": (r[1] - ray[1]) / ray[1], "default": g == "node"}
            for g, r in (("ray", ray), ("node", node))]


def sampling_rows(trace):
    full = replay(trace, "ray")  # sampling saves time where segments are replayed one by one
    rows = []
    for k in (1, 2, 4, 8, 16):
        r = replay(trace, "ray", k)
        rows.append({"knob": "replay sampling 1 in k (per ray)", "value": k, "seconds": r[0],
                     "time_ratio": r[0] / full[0], "error": abs(r[2] - full[2]) / full[2],
                     "error_kind": "simulated time, relative",
                     "fetch_change": (r[1] - full[1]) / full[1], "default": k == 1})
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--scene", default="builtin")
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench-out", "accuracy"))
    opts = ap.parse_args()
    os.makedirs(opts.out, exist_ok=True)
    rows, default_trace = renderer_rows(opts)
    rows += granularity_rows(default_trace)
    rows += sampling_rows(default_trace)
    keys = ["knob", "value", "seconds", "time_ratio", "error", "error_kind", "fetch_change",
            "default"]
    with open(os.path.join(opts.out, "accuracy.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    print("| knob | value | time (ratio to most accurate) | error | fetch change | default |")
    print("|---|---:|---:|---:|---:|---|")
    for r in rows:
        print(f"| {r['knob']} | {r['value']} | {r['seconds']:.2f} s ({r['time_ratio']:.2f}) | "
              f"{r['error']:.4f} ({r['error_kind']}) | {100 * r['fetch_change']:+.1f}% | "
              f"{'yes' if r['default'] else ''} |")
    # One panel per kind of error: the renderer's image RMSE, the replay's simulated time.
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, part, ylabel in ((axes[0], "renderer", "image RMSE against step 0.25"),
                             (axes[1], "replay", "relative error in simulated time")):
        for knob in sorted({r["knob"] for r in rows if r["knob"].startswith(part)}):
            pts = sorted((r["time_ratio"], r["error"], str(r["value"])) for r in rows
                         if r["knob"] == knob)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=knob[len(part) + 1:])
            for p in pts:
                ax.annotate(p[2], (p[0], p[1]), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_xlabel("run time, ratio to the most accurate setting")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{part.capitalize()}: run time against error")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(opts.out, "accuracy.png"), dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
