#!/usr/bin/env bash
# The experiment of docs/rl.md, "Does the board's latency matter in training?": PPO trains the
# example's CNN policy (examples/torch_nav_ppo.py) in the sparse forest twice, with no latency and
# with pi4b's, side by side (one core each, MINUTES of wall clock each, default 35); then each
# policy flies seeds 1-SEEDS (never trained on: training starts at seed 1000) on pi4b and on x86,
# beside the baseline and `fixed` in the same forests; the table (nav_latency_table.py) on stdout
# and the learning curves in OUT_DIR/learning_curves.png.
# A training that finished (OUT_DIR/nav-LATENCY.done) is not run again: re-running flies the
# trained policies again. Run from the repository root after ./scripts/build.sh.
# Usage: bench/rl/nav_latency_experiment.sh OUT_DIR [MINUTES] [SEEDS]
set -euo pipefail
[ $# -ge 1 ] && [ $# -le 3 ] || { echo "usage: $0 OUT_DIR [MINUTES] [SEEDS]" >&2; exit 2; }
out=$(realpath -m "$1")
minutes=${2:-35}
seeds=${3:-50}
mkdir -p "$out"
export PYTHONPATH=$PWD/build/python
enavi=$PWD/build/bin/enavi
forest=(--scenarios forest --param density=2 --param length=20 --seeds "$seeds")
for latency in none board; do
  [ -f "$out/nav-$latency.done" ] && continue
  ( /usr/bin/python3 examples/torch_nav_ppo.py --out "$out/nav-$latency.json" --board pi4b --latency "$latency" \
      --minutes "$minutes" > "$out/train-$latency.log" 2>&1 && touch "$out/nav-$latency.done" ) &
done
wait
for latency in none board; do
  [ -f "$out/nav-$latency.done" ] || { echo "training with latency $latency failed: $out/train-$latency.log" >&2; exit 1; }
  [ -s "$out/eval-$latency.json" ] ||
    "$enavi" eval --name "learned-$latency" --boards pi4b,x86 --methods learned --policy "$out/nav-$latency.json" \
      --world-root "$out" "${forest[@]}" --json > "$out/eval-$latency.json"
done
[ -s "$out/eval-stacks.json" ] ||
  "$enavi" eval --name forest-stacks --boards pi4b,x86 --methods baseline,fixed "${forest[@]}" --json > "$out/eval-stacks.json"
/usr/bin/python3 bench/rl/nav_latency_table.py "$out"
