#!/usr/bin/env python3
"""Flights in moving air and moving worlds (docs/results.md, "Wind, turbulence and movers"): per
condition and method, over every board, scenario and seed of its eval: flights, success rate,
collisions with the static world and with movers, mean flight time of the successful flights,
mean tracking error (setpoint_lag_p95_m: p95 of |reference - true position|), mean navigation
CPU (% of one board core); then, per condition, where E-Navi and the baseline differ most.

Input: CONDITION=FILE pairs, FILE the JSON of `enavi eval --json` (a list of results) flown in
that condition (e.g. severe=air-severe.json). Output: Markdown tables on stdout. Exit 2 on
unreadable input or a missing field.

Usage: air_table.py CONDITION=RESULTS.json [CONDITION=RESULTS.json ...]
"""

import collections
import json
import statistics
import sys


def fail(message):
    print(f"air_table: {message}", file=sys.stderr)
    sys.exit(2)


def load(args):
    out = []
    for arg in args:
        condition, sep, path = arg.partition("=")
        if not sep or not condition or not path:
            fail(f"{arg}: expected CONDITION=FILE")
        try:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        except (OSError, ValueError) as e:
            fail(f"{path}: {e}")
        for i, r in enumerate(data if isinstance(data, list) else [data]):
            for field in ("board", "method", "scenario", "success", "collided", "flight_time_s",
                          "setpoint_lag_p95_m", "nav_cpu_util_pct"):
                if field not in r:
                    fail(f"{path}: result {i}: no field '{field}'")
            out.append((condition, r))
    return out


def mean(values):
    return statistics.fmean(values) if values else float("nan")


def cell(results):
    ok = [r for r in results if r["success"]]
    mover = [r for r in results if r["collided"] and r.get("collided_with", "").startswith("mover:")]
    static = [r for r in results if r["collided"] and not r.get("collided_with", "").startswith("mover:")]
    return {
        "n": len(results),
        "success": 100.0 * len(ok) / len(results),
        "static": len(static),
        "mover": len(mover),
        "time": mean([r["flight_time_s"] for r in ok]),
        "tracking": mean([r["setpoint_lag_p95_m"] for r in results]),
        "cpu": mean([r["nav_cpu_util_pct"] for r in results]),
    }


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    rows = load(argv[1:])
    conditions = list(dict.fromkeys(c for c, _ in rows))
    methods = list(dict.fromkeys(r["method"] for _, r in rows))
    groups = collections.defaultdict(list)
    for c, r in rows:
        groups[(c, r["method"])].append(r)

    print("| condition | method | flights | success | hit static | hit mover | flight time s | tracking p95 m | nav CPU % |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for c in conditions:
        for m in methods:
            if (c, m) not in groups:
                continue
            x = cell(groups[(c, m)])
            print(f"| {c} | {m} | {x['n']} | {x['success']:.0f} % | {x['static']} | {x['mover']} | "
                  f"{x['time']:.1f} | {x['tracking']:.3f} | {x['cpu']:.1f} |")

    # Where E-Navi and the baseline differ most: per condition, board and scenario, the pair of
    # cells (over seeds) with the largest difference in success, then in flight time.
    if "enavi" in methods and "baseline" in methods:
        print()
        print("| condition | board | scenario | success enavi / baseline | collisions enavi / baseline | "
              "flight time s enavi / baseline |")
        print("| --- | --- | --- | --- | --- | --- |")
        by = collections.defaultdict(list)
        for c, r in rows:
            by[(c, r["board"], r["scenario"], r["method"])].append(r)
        for c in conditions:
            diffs = []
            for (cc, board, scenario, m), rs in by.items():
                if cc != c or m != "enavi" or (c, board, scenario, "baseline") not in by:
                    continue
                e, b = cell(rs), cell(by[(c, board, scenario, "baseline")])
                time_gap = abs(e["time"] - b["time"]) if e["time"] == e["time"] and b["time"] == b["time"] else 0.0
                diffs.append((abs(e["success"] - b["success"]), time_gap, board, scenario, e, b))
            if not diffs:
                continue
            _, _, board, scenario, e, b = max(diffs, key=lambda d: (d[0], d[1]))
            print(f"| {c} | {board} | {scenario} | {e['success']:.0f} % / {b['success']:.0f} % | "
                  f"{e['static'] + e['mover']} / {b['static'] + b['mover']} | {e['time']:.1f} / {b['time']:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
