#!/usr/bin/env python3
"""Checks a `raycell replay --timeline` file against the Chrome trace-event format as the
viewers read it, without a viewer (neither Perfetto's trace processor nor chrome://tracing
runs here):

  python3 tools/bench/check_timeline.py timeline.json

- JSON object format: a `traceEvents` array of objects, `otherData` an object;
- every event has `ph`, `pid`, `name`; `ts` (a number >= 0) on every event but metadata;
- `X`: `tid` and `dur` >= 0; `C`: `args` an object of numbers (the series);
  `i`: scope `s` one of g, p, t; `M`: one of the metadata names the viewers know, with args;
- slices on a thread nest properly once read as Perfetto reads them (llround(us * 1000)
  nanoseconds for ts and dur separately): no slice ends inside the next one on its track.
  (Ours never nest: each track's slices are disjoint, so this is "no overlap".)

Prints a summary; exits 1 with the first problems found.
"""
import json
import sys
from collections import defaultdict

PHASES = {"X", "C", "i", "M"}  # the phases raycell writes
METADATA = {"process_name", "thread_name", "thread_sort_index", "process_sort_index"}


def ns(us):
    # Perfetto's CoerceToTs for a double: std::llround(value * 1000.0).
    v = us * 1000.0
    return int(v + 0.5) if v >= 0 else -int(-v + 0.5)


def main(path):
    with open(path, "rb") as f:
        doc = json.load(f)
    problems = []

    def bad(msg):
        if len(problems) < 20:
            problems.append(msg)

    if not isinstance(doc, dict) or not isinstance(doc.get("traceEvents"), list):
        print("not the JSON object format: no traceEvents array")
        return 1
    if not isinstance(doc.get("otherData", {}), dict):
        bad("otherData is not an object")
    counts = defaultdict(int)
    tracks = defaultdict(list)
    for k, e in enumerate(doc["traceEvents"]):
        if not isinstance(e, dict):
            bad(f"event {k} is not an object")
            continue
        ph = e.get("ph")
        counts[ph] += 1
        if ph not in PHASES:
            bad(f"event {k}: unexpected ph {ph!r}")
        if not isinstance(e.get("pid"), int) or not isinstance(e.get("name"), str):
            bad(f"event {k}: pid or name missing")
        if ph != "M" and not (isinstance(e.get("ts"), (int, float)) and e["ts"] >= 0):
            bad(f"event {k}: ts missing or negative")
        if ph == "X":
            if not isinstance(e.get("tid"), int):
                bad(f"event {k}: X without tid")
            if not (isinstance(e.get("dur"), (int, float)) and e["dur"] >= 0):
                bad(f"event {k}: X without a dur >= 0")
            else:
                tracks[(e["pid"], e.get("tid"))].append((ns(e["ts"]), ns(e["dur"]), k))
        elif ph == "C":
            args = e.get("args")
            if not isinstance(args, dict) or not args or not all(
                    isinstance(v, (int, float)) for v in args.values()):
                bad(f"event {k}: counter args are not numbers")
        elif ph == "i":
            if e.get("s", "t") not in ("g", "p", "t"):
                bad(f"event {k}: instant scope {e.get('s')!r}")
        elif ph == "M":
            if e.get("name") not in METADATA or not isinstance(e.get("args"), dict):
                bad(f"event {k}: metadata {e.get('name')!r}")
    slices = 0
    for track, xs in tracks.items():
        xs.sort(key=lambda x: (x[0], x[1]))
        slices += len(xs)
        end = 0
        for ts, dur, k in xs:
            if ts < end:
                bad(f"event {k}: starts at {ts} ns inside the slice before on track {track}, "
                    f"which ends at {end} ns")
            end = max(end, ts + dur)
    print(f"{path}: {len(doc['traceEvents'])} events "
          f"({', '.join(f'{counts[p]} {p}' for p in sorted(counts, key=str))}), "
          f"{slices} slices on {len(tracks)} tracks; schema "
          f"{doc.get('otherData', {}).get('schema')}")
    for p in problems:
        print("problem:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))
