#!/usr/bin/env python3
"""Renders a scene exported from radlab (scene.json and one PLY per material, as written by the side-by-side
harness's `export` command, ../shared/bench/embree-sidebyside) with Mitsuba 3, for the path tracer's comparison
in docs/fair-comparison.md: the `path` integrator (unlimited depth), diffuse BSDFs of the exported reflectance,
area emitters of radiance E/pi, the exported pinhole camera, a box filter. Prints the samples per second of each
render after a first one (which includes the JIT compilation) and saves the last image as a .npy file.

Usage: python3 scripts/mitsuba-render.py EXPORT_DIR [VARIANT] [SPP] [THREADS] [RENDERS] [SEED]
  (defaults: llvm_ad_rgb 64 2 3 1; needs `pip install mitsuba numpy`, and Debian's libllvm19 for llvm variants)
"""
import json
import os
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

if len(sys.argv) < 2 or not os.path.isfile(os.path.join(sys.argv[1], "scene.json")):
    sys.exit(__doc__.split("\n\n")[-1].strip() + "\n(EXPORT_DIR must hold the export's scene.json)")
args = sys.argv[1:] + [None] * 6
d = args[0]
variant = args[1] or "llvm_ad_rgb"
spp, threads, renders, seed = (int(a) if a else v for a, v in zip(args[2:6], (64, 2, 3, 1)))
mi.set_variant(variant)
dr.set_thread_count(threads)
with open(os.path.join(d, "scene.json")) as f:
    js = json.load(f)
c = js["camera"]
scene = {
    "type": "scene",
    "integrator": {"type": "path", "max_depth": -1, "hide_emitters": False},
    "sensor": {
        "type": "perspective",
        "fov": c["fov_y_deg"],
        "fov_axis": "y",
        "to_world": mi.ScalarTransform4f().look_at(origin=c["eye"], target=c["target"], up=c["up"]),
        "film": {"type": "hdrfilm", "width": c["width"], "height": c["height"],
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp},
    },
}
for m in js["materials"]:
    shape = {"type": "ply", "filename": os.path.join(d, m["ply"]), "face_normals": True,
             "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["reflectance"]}}}
    if max(m["radiance"]) > 0:
        shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["radiance"]}}
    scene[m["name"]] = shape
scene = mi.load_dict(scene)
samples = c["width"] * c["height"] * spp
for r in range(renders + 1):
    t = time.time()
    img = mi.render(scene, spp=spp, seed=seed + r)
    dr.eval(img)
    dr.sync_thread()
    elapsed = time.time() - t
    if r > 0:
        print(f"mitsuba {variant} threads {threads}: {elapsed:.3f} s, {samples / elapsed / 1e6:.3f} M samples/s",
              flush=True)
np.save(os.path.join(d, f"mitsuba-{variant}-{seed}.npy"), np.array(img))
