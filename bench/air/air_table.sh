#!/usr/bin/env bash
# The table of docs/results.md, "Wind, turbulence and movers": baseline, fixed and E-Navi on the
# paper's matrix (5 boards x s1-s5, seed 1, virtual clock) in still air and in light, moderate
# and severe Dryden turbulence, and on 5 boards x the two mover worlds (park-people,
# street-traffic) x seeds 1-3; each eval's results as JSON in OUT_DIR, then the table
# (air_table.py) on stdout. About 21 minutes on 2 idle cores (2026-12-06).
# Usage: bench/air/air_table.sh OUT_DIR   (from the repository root, after ./scripts/build.sh)
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 OUT_DIR" >&2; exit 2; }
out=$1
mkdir -p "$out"
enavi=./build/bin/enavi
methods=baseline,fixed,enavi
for air in none light moderate severe; do
  [ -s "$out/air-$air.json" ] ||
    "$enavi" eval --name "air-$air" --preset paper --seeds 1 --methods "$methods" --turbulence "$air" --json > "$out/air-$air.json"
done
[ -s "$out/movers.json" ] ||
  "$enavi" eval --name movers --boards tx2,pi4b,nx,opi5,x86 --scenarios park-people,street-traffic \
    --methods "$methods" --seeds 3 --json > "$out/movers.json"
/usr/bin/python3 bench/air/air_table.py "still air=$out/air-none.json" "light=$out/air-light.json" \
  "moderate=$out/air-moderate.json" "severe=$out/air-severe.json" "movers=$out/movers.json"
