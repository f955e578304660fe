#!/usr/bin/env python3
"""Radiosity at radlab's evaluation points from Radiance (written by `radlab export --to radiance`).

Runs `oconv scene.rad` and `rtrace -I` (irradiance H at each point, lifted along its normal by the `lift`
column, facing the normal; pure Monte Carlo ambient sampling, -aa 0) REPEATS times per point with
uncorrelated sampling (-u+), and writes radiance.csv with x,y,z,r,g,b,se_r,se_g,se_b: B = E + rho H and its
standard error over the repeats. `radlab compare` reads it.

With --aa > 0 Radiance's irradiance cache answers instead (Ward, Rubinstein & Clear 1988: ambient accuracy
-aa, super-samples -as, one evaluation per point, so no standard error columns), in --processes rtrace
processes (-n), for timing the cache against radlab's `irradiance-cache` at the same points.

Usage: python3 radiance-points.py [--repeats 16] [--ab 16] [--ad 128] [--lw 1e-5] [--aa 0] [--as 0]
                                  [--processes 1] [--out radiance.csv]
Needs oconv and rtrace on PATH, or `pip install pyradiance` (its bundled binaries are used).
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys
import time

here = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--repeats", type=int, default=16, help="independent rtrace evaluations per point (standard error)")
ap.add_argument("--ab", type=int, default=16, help="ambient bounces")
ap.add_argument("--ad", type=int, default=128, help="ambient divisions")
ap.add_argument("--lw", type=float, default=1e-5, help="limit weight")
ap.add_argument("--aa", type=float, default=0.0, help="ambient accuracy (0: no cache, pure Monte Carlo)")
ap.add_argument("--as", dest="ss", type=int, default=0, help="ambient super-samples (with --aa > 0)")
ap.add_argument("--processes", type=int, default=1, help="rtrace processes (-n)")
ap.add_argument("--out", default=os.path.join(here, "radiance.csv"))
a = ap.parse_args()
if a.aa < 0 or a.ss < 0 or a.processes < 1 or a.repeats < 1:
    sys.exit("--aa and --as must be >= 0, --processes and --repeats >= 1")
cached = a.aa > 0
if cached:
    a.repeats = 1  # cached values are not independent repeats


def tool(name):
    p = shutil.which(name)
    if p:
        return p
    try:
        import pyradiance  # noqa: F401  (ships the Radiance binaries)

        p = os.path.join(os.path.dirname(pyradiance.__file__), "bin", name)
        if os.path.exists(p):
            return p
    except ImportError:
        pass
    sys.exit(f"{name} not found: install Radiance or `pip install pyradiance`")


def raypath(rtrace):
    """RAYPATH with Radiance's library (rayinit.cal, which the faces' one-sided `mixfunc` needs for Rdot)."""
    paths = [p for p in os.environ.get("RAYPATH", "").split(os.pathsep) if p] or [".", "/usr/local/lib/ray"]
    root = os.path.dirname(os.path.dirname(os.path.realpath(rtrace)))
    for lib in (os.path.join(root, "lib"), os.path.join(root, "lib", "ray")):
        if os.path.exists(os.path.join(lib, "rayinit.cal")) and lib not in paths:
            paths.append(lib)
    return os.pathsep.join(paths)


with open(os.path.join(here, "points.csv")) as f:
    rows = list(csv.DictReader(f))
oct_path = os.path.join(here, "scene.oct")
with open(oct_path, "wb") as f:
    subprocess.run([tool("oconv"), os.path.join(here, "scene.rad")], stdout=f, check=True)
lines = []
for r in rows:
    p = [float(r[k]) for k in ("x", "y", "z")]
    n = [float(r[k]) for k in ("nx", "ny", "nz")]
    lift = float(r["lift"])
    o = [p[i] + lift * n[i] for i in range(3)]
    lines.extend([f"{o[0]!r} {o[1]!r} {o[2]!r} {n[0]!r} {n[1]!r} {n[2]!r}\n"] * a.repeats)
cmd = [tool("rtrace"), "-I", "-h", "-u+", "-n", str(a.processes), "-ab", str(a.ab), "-aa", repr(a.aa),
       "-ad", str(a.ad), "-as", str(a.ss),
       "-lw", str(a.lw), "-lr", str(-abs(4 * a.ab)), "-dj", "1", "-ds", "0.02", "-dt", "0", "-dc", "1",
       "-ss", "0", "-st", "1", oct_path]
t0 = time.time()
env = dict(os.environ, RAYPATH=raypath(cmd[0]))
run = subprocess.run(cmd, input="".join(lines), capture_output=True, text=True, env=env)
if run.returncode != 0:
    sys.exit(f"rtrace failed ({run.returncode}): {run.stderr.strip()}")
out = run.stdout.split()
vals = [float(v) for v in out]
if len(vals) != 3 * len(lines):
    sys.exit(f"rtrace returned {len(vals)} numbers for {len(lines)} rays")
with open(a.out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["x", "y", "z", "r", "g", "b"] + ([] if cached else ["se_r", "se_g", "se_b"]))
    for i, r in enumerate(rows):
        rho = [float(r[k]) for k in ("rho_r", "rho_g", "rho_b")]
        e = [float(r[k]) for k in ("e_r", "e_g", "e_b")]
        b, se = [], []
        for c in range(3):
            h = [vals[3 * (i * a.repeats + k) + c] for k in range(a.repeats)]
            mean = sum(h) / len(h)
            var = sum((x - mean) ** 2 for x in h) / max(len(h) - 1, 1)
            b.append(e[c] + rho[c] * mean)
            se.append(rho[c] * math.sqrt(var / len(h)))
        w.writerow([r["x"], r["y"], r["z"]] + [repr(v) for v in (b if cached else b + se)])
print(f"radiance: {len(rows)} points x {a.repeats} repeats in {time.time() - t0:.1f} s -> {a.out}")
print("  " + " ".join(cmd[:-1]))
