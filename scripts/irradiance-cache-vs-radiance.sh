#!/usr/bin/env bash
# radlab's irradiance cache against Radiance 6's (`rtrace -I` with -aa > 0) on the same scene and points, with
# the same ambient accuracy, divisions and bounces, both against radlab's path-traced reference (issue 43's
# side-by-side). A benchmark, not a test: it needs Radiance's oconv/rtrace (on PATH, or `pip install
# pyradiance`) and, for the default scene, the scanned meshes in ../shared/data/meshes.
#
#   bash scripts/irradiance-cache-vs-radiance.sh [SCENE] [POINTS] [OUT]
#
# Environment: AA (0.2), AD (512), AS (256), AB (8), PROCS (2: rtrace processes and radlab threads),
# REF_SAMPLES (8192 paths a point for the reference).
set -euo pipefail
scene=${1:-experiments/scenes/elephant-room.toml}
points=${2:-512}
out=${3:-results/ic-vs-radiance}
aa=${AA:-0.2} ad=${AD:-512} as=${AS:-256} ab=${AB:-8} procs=${PROCS:-2} ref=${REF_SAMPLES:-8192}
radlab=target/release/radlab
cargo build --release -q -p radlab-runner
rm -rf "$out" && mkdir -p "$out"
"$radlab" export "$scene" --to radiance --out "$out/rad" --points "$points"
echo "reference: pathtrace, $ref paths a point"
"$radlab" probe "$scene" --method pathtrace --set samples="$ref" --points "$out/rad/points.csv" \
    --threads "$procs" > "$out/reference.csv"
# Wall time of each whole command (scene loading, octree or BVH build and the answers).
t0=$(date +%s.%N)
python3 "$out/rad/radiance-points.py" --aa "$aa" --as "$as" --ad "$ad" --ab "$ab" --processes "$procs" \
    --out "$out/radiance.csv"
t1=$(date +%s.%N)
"$radlab" probe "$scene" --method irradiance-cache --set accuracy="$aa" --set samples="$ad" \
    --points "$out/rad/points.csv" --threads "$procs" > "$out/radlab.csv"
t2=$(date +%s.%N)
t_rad=$(python3 -c "print($t1 - $t0)") t_ic=$(python3 -c "print($t2 - $t1)")
python3 - "$out" "$t_rad" "$t_ic" <<'PY'
import csv, sys
out, t_rad, t_ic = sys.argv[1], sys.argv[2], sys.argv[3]
def load(f):
    return [sum(float(r[k]) for k in "rgb") for r in csv.DictReader(open(f))]
ref = load(f"{out}/reference.csv")
rows = []
for name, f, t in [("Radiance rtrace -I", "radiance.csv", t_rad), ("radlab irradiance-cache", "radlab.csv", t_ic)]:
    v = load(f"{out}/{f}")
    rel = [abs(a - b) / b for a, b in zip(v, ref) if b > 0]
    l1 = sum(abs(a - b) for a, b in zip(v, ref)) / sum(ref)
    rows.append(f"| {name} | {float(t):.1f} | {100 * l1:.2f}% | {100 * sum(rel) / len(rel):.2f}% | {100 * max(rel):.1f}% |")
print("| renderer | wall s | relative L1 | mean relative | max relative |\n|---|---|---|---|---|")
print("\n".join(rows))
PY
