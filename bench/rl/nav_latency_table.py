#!/usr/bin/env python3
"""The table and curves of bench/rl/nav_latency_experiment.sh from its OUT_DIR: each policy (trained
with no latency, with pi4b's) and the classic stacks flown on pi4b and x86 in the same forests;
success, collisions, flight time, the inference's board time and the navigation CPU. Learning
curves (success rate and return over environment steps, a moving mean over 20 iterations) to
OUT_DIR/learning_curves.png.

    PYTHONPATH=build/python /usr/bin/python3 bench/rl/nav_latency_table.py OUT_DIR
"""

import csv
import json
import os
import re
import sys

import enavi

WINDOW = 20


def rows_of(path, label=None):
    with open(path) as f:
        results = json.load(f)
    cells = {}
    for r in results:
        cells.setdefault((label or r["method"], r["board"]), []).append(r)
    return cells


def inference_ms(r):
    m = re.search(r"mean job ([0-9.]+) ms", r["notes"].get("task.perception", ""))
    return float(m.group(1)) if m and r["method"] == "learned" else None


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def curve(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(f)]
    steps = [float(r["env_steps"]) for r in rows]
    success, ret = [], []
    for i in range(len(rows)):
        window = [r for r in rows[max(0, i - WINDOW + 1):i + 1] if int(r["episodes"]) > 0]
        n = sum(int(r["episodes"]) for r in window)
        success.append(sum(float(r["success_rate"]) * int(r["episodes"]) for r in window) / n if n else float("nan"))
        ret.append(sum(float(r["mean_return"]) * int(r["episodes"]) for r in window) / n if n else float("nan"))
    return steps, success, ret, rows


def main():
    out = sys.argv[1]
    cells = {}
    cells.update(rows_of(os.path.join(out, "eval-none.json"), "learned, trained with no latency"))
    cells.update(rows_of(os.path.join(out, "eval-board.json"), "learned, trained with pi4b's latency"))
    cells.update(rows_of(os.path.join(out, "eval-stacks.json")))
    print("| method | flown on | flights | success | collisions | other ends | flight time s (successes) "
          "| inference ms | nav CPU % |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for (method, board), rs in cells.items():
        n = len(rs)
        ok = [r for r in rs if r["success"]]
        hit = sum(1 for r in rs if r["collided"])
        times = [r["flight_time_s"] for r in ok]
        ms = [inference_ms(r) for r in rs]
        ms = None if None in ms else sum(ms) / n
        print("| %s | %s | %d | %d (%.0f %%) | %d | %d | %s | %s | %.1f |" % (
            method, board, n, len(ok), 100.0 * len(ok) / n, hit, n - len(ok) - hit,
            fmt(sum(times) / len(times) if times else None, ".1f"), fmt(ms, ".2f"),
            sum(r["nav_cpu_util_pct"] for r in rs) / n))
    panels = [("success rate (moving mean over %d iterations)" % WINDOW, "success", []),
              ("episode return (moving mean)", "return", [])]
    for latency, name in (("none", "trained with no latency"), ("board", "trained with pi4b's latency")):
        steps, success, ret, rows = curve(os.path.join(out, "nav-%s.csv" % latency))
        panels[0][2].append((name, steps, success))
        panels[1][2].append((name, steps, ret))
        print("\n%s: %d iterations, %d environment steps in %.0f s, %d training episodes" % (
            name, len(rows), steps[-1], float(rows[-1]["wall_s"]), sum(int(r["episodes"]) for r in rows)))
    png = os.path.join(out, "learning_curves.png")
    enavi.save_chart_png(png, "PPO in the sparse forest (pi4b)", "environment steps", panels)
    print("learning curves: %s" % png)


if __name__ == "__main__":
    main()
