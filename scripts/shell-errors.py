#!/usr/bin/env python3
"""Per-point error over a room's floor, walls and ceiling, from `radlab run` result directories.

Issue 45's targets are stricter on floors and walls (3% mean, 10% max) than on the rest of a scene. A room's shell
is taken as the evaluation points lying on the bounding box of all of a run's evaluation points (within 1e-3 of
its diagonal): the room's six sides, whatever stands in it. The error per point is the run's own `rel_error`
column (the reports' max error: |B - R| / max(|R|, 2% of the scene's mean R) in the worst channel). Prints a
markdown table of mean / max error over the shell (and the number of shell points) per scene and method, for
every finished or killed run.

    python3 scripts/shell-errors.py results/defaults-suite [more result directories ...]
"""
import csv
import glob
import json
import os
import sys


def shell_errors(points_csv):
    rows = list(csv.DictReader(open(points_csv)))
    pos = [[float(x[c]) for c in "xyz"] for x in rows]
    lo = [min(p[i] for p in pos) for i in range(3)]
    hi = [max(p[i] for p in pos) for i in range(3)]
    tol = 1e-3 * sum((hi[i] - lo[i]) ** 2 for i in range(3)) ** 0.5
    return [
        float(x["rel_error"])
        for p, x in zip(pos, rows)
        if any(abs(p[i] - lo[i]) < tol or abs(p[i] - hi[i]) < tol for i in range(3))
    ]


def main(dirs):
    cells = {}
    for d in dirs:
        for path in sorted(glob.glob(os.path.join(d, "runs", "*.json"))):
            if path.endswith((".job.json", ".partial.json")):
                continue
            run = json.load(open(path))
            points = path[: -len(".json")] + ".points.csv"
            if not os.path.exists(points) or run["outcome"] == "error":
                continue
            errors = shell_errors(points)
            if errors:
                cells[(run["scene"], run["label"] or run["method"])] = errors
    scenes = list(dict.fromkeys(s for s, _ in cells))
    methods = list(dict.fromkeys(m for _, m in cells))
    print("| method | " + " | ".join(scenes) + " |")
    print("|---|" + "---|" * len(scenes))
    for m in methods:
        row = []
        for s in scenes:
            e = cells.get((s, m))
            row.append("" if e is None else f"{100 * sum(e) / len(e):.1f}% / {100 * max(e):.0f}% ({len(e)})")
        print(f"| {m} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["results/defaults-suite"])
