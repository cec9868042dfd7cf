#!/usr/bin/env bash
# run_fuzzer.sh BINARY FUZZ_SRC_DIR STATS_DIR RUNS: one harness's CTest run. Replays every
# regression input, then runs RUNS inputs grown from the seed corpus (in a scratch copy: the
# repository's corpus is not modified); writes STATS_DIR/<harness> = inputs run, on success only.
set -euo pipefail
bin=$1 src=$2 stats=$3 runs=$4
name=$(basename "$bin")
mkdir -p "$stats"
rm -f "$stats/$name"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
start=$(date +%s.%N)

regressions=0
if [ -d "$src/regressions/$name" ] && [ -n "$(ls -A "$src/regressions/$name")" ]; then
  regressions=$(find "$src/regressions/$name" -type f | wc -l)
  "$bin" -timeout=20 -rss_limit_mb=2048 "$src/regressions/$name"/* >"$work/regressions.log" 2>&1 ||
    { cat "$work/regressions.log"; echo "$name: a regression input fails again"; exit 1; }
fi

mkdir "$work/corpus"
cp "$src/corpus/$name"/* "$work/corpus/"
# Fixed seed: the same inputs on every run. A crash leaves crash-* in the test's directory.
"$bin" -runs="$runs" -seed=1 -max_len=8192 -timeout=20 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/" "$work/corpus" >"$work/fuzz.log" 2>&1 || {
  tail -n 60 "$work/fuzz.log"
  for f in "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-*; do
    [ -e "$f" ] || continue
    cp "$f" "$PWD/$name-$(basename "$f")"
    echo "$name: failing input kept as $PWD/$name-$(basename "$f") (add it to $src/regressions/$name/)"
  done
  exit 1
}
done_runs=$(sed -n 's/^Done \([0-9]*\) runs.*/\1/p' "$work/fuzz.log" | tail -n 1)
[ -n "$done_runs" ] || { tail -n 20 "$work/fuzz.log"; echo "$name: no 'Done N runs' line"; exit 1; }
elapsed=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
echo "$name: $done_runs inputs + $regressions regression inputs in $elapsed s"
echo "$done_runs $regressions $elapsed" >"$stats/$name"
