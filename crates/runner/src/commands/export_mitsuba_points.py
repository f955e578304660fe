#!/usr/bin/env python3
"""Radiosity at radlab's evaluation points from Mitsuba 3 (written by `radlab export --to mitsuba`).

Loads scene.xml and estimates the irradiance H at each point (lifted along its normal by the `lift` column) as
the sum of two parts per sample, so each sample is one independent estimate of H:
- direct (`--direct emitter`, the default): the light seen from the point itself, by Mitsuba's emitter
  sampling with a shadow ray, L cos / pdf;
- the rest: pi L along one cosine-weighted direction, L the incident radiance Mitsuba's own `path` integrator
  (unlimited depth) returns less the emission of the surface that direction meets (its reflection stays).
`--direct hemisphere` instead counts the emitters seen along the cosine-weighted directions (H = pi mean(L), the
plain estimator): unbiased too, but a small light is found only by the few directions that hit it, so its
standard error is several times larger where direct light dominates (a floor under a ceiling light).
Writes mitsuba.csv with x,y,z,r,g,b,se_r,se_g,se_b: B = E + rho H and its standard error over the samples (the
three channels come from the same paths, so their errors are correlated). `radlab compare` reads it.

Usage: python3 mitsuba-points.py [--spp 65536] [--direct emitter|hemisphere] [--variant llvm_ad_rgb] [--seed 1]
                                 [--out mitsuba.csv]
Needs `pip install mitsuba numpy` (llvm variants also need an LLVM shared library; scalar_rgb does not).
"""
import argparse
import csv
import math
import os
import time

import drjit as dr
import mitsuba as mi
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--spp", type=int, default=65536, help="samples per point")
ap.add_argument("--direct", choices=["emitter", "hemisphere"], default="emitter",
                help="direct light by emitter sampling at the point, or by the hemisphere directions alone")
ap.add_argument("--variant", default="llvm_ad_rgb")
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--batch", type=int, default=1 << 20, help="rays per Mitsuba call")
ap.add_argument("--out", default=os.path.join(here, "mitsuba.csv"))
a = ap.parse_args()
mi.set_variant(a.variant)
with open(os.path.join(here, "points.csv")) as f:
    rows = list(csv.DictReader(f))
P = np.array([[float(r[k]) for k in ("x", "y", "z")] for r in rows])
N = np.array([[float(r[k]) for k in ("nx", "ny", "nz")] for r in rows])
lift = np.array([float(r["lift"]) for r in rows])
rho = np.array([[float(r[k]) for k in ("rho_r", "rho_g", "rho_b")] for r in rows])
E = np.array([[float(r[k]) for k in ("e_r", "e_g", "e_b")] for r in rows])
scene = mi.load_file(os.path.join(here, "scene.xml"))
nee = a.direct == "emitter"
# Not `hide_emitters`: it ends a path at an emitter it hides, so an emitter's own reflection would be lost too.
integrator = mi.load_dict({"type": "path", "max_depth": -1, "hide_emitters": False})
n_pts = len(rows)
total = n_pts * a.spp
s1 = np.zeros((n_pts, 3))
s2 = np.zeros((n_pts, 3))
t0 = time.time()
for call, start in enumerate(range(0, total, a.batch)):
    idx = np.arange(start, min(start + a.batch, total)) // a.spp
    m = len(idx)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(a.seed * 1000003 + call, m)
    n = mi.Vector3f(N[idx, 0], N[idx, 1], N[idx, 2])
    frame = mi.Frame3f(n)
    o = mi.Point3f(*(P[idx] + lift[idx, None] * N[idx]).T)
    H = mi.Color3f(0.0)
    if nee:
        it = dr.zeros(mi.SurfaceInteraction3f, m)
        it.p, it.n, it.sh_frame = o, mi.Normal3f(n), frame
        ds, w = scene.sample_emitter_direction(it, sampler.next_2d(), True)
        H = w * dr.maximum(dr.dot(ds.d, n), 0.0)
    ray = mi.Ray3f(o, frame.to_world(mi.warp.square_to_cosine_hemisphere(sampler.next_2d())))
    L, _, _ = integrator.sample(scene, sampler, ray)
    if nee:  # the emission seen directly along the ray is counted by the emitter sample above
        si = scene.ray_intersect(ray)
        L = L - si.emitter(scene).eval(si, si.is_valid())
    L = np.array(H + math.pi * L, dtype=np.float64)
    L = L.T if L.ndim == 2 and L.shape[0] == 3 and L.shape[1] == m else L.reshape(m, 3)
    np.add.at(s1, idx, L)
    np.add.at(s2, idx, L * L)
H = s1 / a.spp
var = np.maximum(s2 / a.spp - H * H, 0.0) * a.spp / max(a.spp - 1, 1)
se_H = np.sqrt(var / a.spp)
B = E + rho * H
se = rho * se_H
with open(a.out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["x", "y", "z", "r", "g", "b", "se_r", "se_g", "se_b"])
    for i, r in enumerate(rows):
        w.writerow([r["x"], r["y"], r["z"]] + [repr(float(v)) for v in list(B[i]) + list(se[i])])
print(f"mitsuba {a.variant}, direct {a.direct}: {n_pts} points x {a.spp} samples in {time.time() - t0:.1f} s -> {a.out}")
