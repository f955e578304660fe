#!/usr/bin/env python3
"""Prints the README's quickstart table from results/headline/quickstart/runs.csv (time = set-up + steps + one
answering pass at the evaluation points; rays = steps' + answering's), so the table is regenerated, not
transcribed."""
import csv
import sys

path = sys.argv[1] if len(sys.argv) > 1 else "results/headline/quickstart/runs.csv"
print("| method | setting | elements | rays | time | relative L1 | max (floored) | memory held |")
print("|---|---|---|---|---|---|---|---|")
for r in csv.DictReader(open(path)):
    sweep = r["sweep"]
    if sweep.startswith("element_size="):
        setting = f"element {float(sweep.split('=')[1]):g} mm"
    elif sweep.startswith("epsilon="):
        setting = f"ε = {float(sweep.split('=')[1]):g}"
    elif r["method"] == "pathtrace":
        setting = "paths doubling per step"
    else:
        setting = sweep or "defaults"
    rays = (int(r["rays"]) + int(r["answer_rays"] or 0)) / 1e6
    time = float(r["setup_s"] or 0) + float(r["wall_s"]) + float(r["answer_s"] or 0)
    print(
        f"| {r['label']} | {setting} | {int(r['elements']):,} | {rays:.2f} M | {time:.2f} s | "
        f"{100 * float(r['l1']):.1f}% | {100 * float(r['max']):.0f}% | {int(r['bytes']) / 2**20:.2f} MiB |"
    )
