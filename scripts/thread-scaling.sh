#!/usr/bin/env bash
# 2-thread speed-up of the solvers' parallel loops, measured as ratios in alternating runs (1 thread, then
# 2 threads, repeated), so that load from other processes hits both alike. Prints each run's solve wall time
# (the "s wall" of radlab's summary line), the medians and the ratio, and checks that faces.csv is
# bit-identical at 1 and 2 threads.
# Usage: scripts/thread-scaling.sh [RADLAB_BINARY] [ROUNDS] [METHODS...]
#   e.g. scripts/thread-scaling.sh target/release/radlab 7 progressive matrix
set -euo pipefail
bin=${1:-target/release/radlab}
rounds=${2:-7}
shift $(( $# < 2 ? $# : 2 ))
methods=("$@")
[ ${#methods[@]} -eq 0 ] && methods=(progressive matrix)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
for m in "${methods[@]}"; do
  : > "$out/$m-1" ; : > "$out/$m-2"
  for r in $(seq "$rounds"); do
    for t in 1 2; do
      line=$("$bin" --threads "$t" solve builtin:cornell --method "$m" --set reconstruction=constant \
        --out "$out/$m-run-$t" 2>&1 | grep ' s wall')
      s=$(sed -E 's/.* ([0-9.]+) s wall.*/\1/' <<<"$line")
      echo "$s" >> "$out/$m-$t"
      echo "$m round $r threads $t: $s s (load $(cut -d' ' -f1 /proc/loadavg))"
    done
    cmp -s "$out/$m-run-1/faces.csv" "$out/$m-run-2/faces.csv" || echo "$m: faces.csv DIFFERS between 1 and 2 threads"
  done
  m1=$(median < "$out/$m-1"); m2=$(median < "$out/$m-2")
  echo "$m: median of $rounds alternating runs: 1 thread $m1 s, 2 threads $m2 s, speed-up $(awk -v a="$m1" -v b="$m2" 'BEGIN {printf "%.3f", a / b}')×"
done
