#!/usr/bin/env bash
# Regenerates the README's quickstart figures and table source: runs the quickstart experiment (release build)
# and copies its headline outputs to results/headline/quickstart/, the only results checked into git.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo run --release -- run experiments/quickstart.toml --force
out=results/headline/quickstart
mkdir -p "$out"
cp results/quickstart/figures/frontier-cornell.png results/quickstart/figures/convergence-cornell.png \
   results/quickstart/images/contact-sheet-cornell.png results/quickstart/runs.csv "$out"/
echo "updated $out; print the README table with: python3 scripts/readme-table.py"
