#!/usr/bin/env bash
# fuzz_total.sh STATS_DIR MIN TEST...: the inputs every harness ran (CTest runs this after them);
# fails when a harness did not finish or the total is below MIN.
set -euo pipefail
stats=$1 min=$2
shift 2
total=0
printf '%-22s %8s %11s %8s\n' harness inputs regressions seconds
for t in "$@"; do
  name=${t#fuzz_}
  [ -f "$stats/$name" ] || { echo "$name: no result (did its test pass?)"; exit 1; }
  read -r runs regressions seconds <"$stats/$name"
  printf '%-22s %8d %11d %8s\n' "$name" "$runs" "$regressions" "$seconds"
  total=$((total + runs))
done
echo "fuzz total: $total inputs"
[ "$total" -ge "$min" ] || { echo "fuzz total below $min"; exit 1; }
