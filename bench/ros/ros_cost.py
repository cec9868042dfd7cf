#!/usr/bin/env python3
"""What ROS costs on a board (docs/results.md, "What ROS costs on a board"): each flight of one of
our methods through the ROS bridge (enavi_ros_node, method name METHOD_ros or METHOD_ros_SUFFIX)
against the same method's flight natively on the emulated clock in the same run: flight time,
path length (a different route explains most of a different flight time), navigation CPU in % of one board core (native: the navstack process from /proc, and its jobs;
bridge: the node's process from /proc), and where the node's CPU goes by thread.

Input: the JSON of `enavi eval --json` (a list of results) or `enavi fly --json` records, one or
several files; a METHOD_ros_SUFFIX method is a variant (e.g. fixed_ros_clock100) compared with
METHOD too. Output: Markdown tables on stdout. Exit 2 on unreadable input.

Usage: ros_cost.py RESULTS.json [MORE.json ...]
"""

import collections
import json
import re
import statistics
import sys

THREAD = re.compile(r"([\w.-]+)/([\w.-]+) ([0-9.]+) %")
NATIVE_THREAD = re.compile(r"([\w.-]+) ([0-9.]+) %")


def load(paths):
    out = []
    for p in paths:
        try:
            with open(p, encoding="utf-8") as f:
                data = json.load(f)
        except (OSError, ValueError) as e:
            print(f"ros_cost: {p}: {e}", file=sys.stderr)
            sys.exit(2)
        out += data if isinstance(data, list) else [data]
    return out


def node_threads(r):
    """The node's CPU by kind of thread, % of a board core (ros.threads: the busiest 12)."""
    kinds = collections.Counter()
    note = r["notes"].get("ros.threads", "")
    for proc, thread, pct in THREAD.findall(note.split(":", 1)[-1]):
        if proc == "roslaunch":
            kinds["roslaunch"] += float(pct)
        elif thread.startswith("nav-worker"):
            kinds["jobs"] += float(pct)
        elif thread == "ros-clock":
            kinds["/clock"] += float(pct)
        elif thread == "ros-inputs":
            kinds["inputs"] += float(pct)
        elif thread == "nav-command":
            kinds["command"] += float(pct)
        elif thread == "nav-release":
            kinds["release"] += float(pct)
        else:
            kinds["roscpp"] += float(pct)  # roscpp's own threads: sockets, its /clock, rosout, XML-RPC
    return kinds


def native_process(r):
    """(process %, jobs %) of the emulated clock's navstack process."""
    note = r["notes"].get("emulation.proc_util", "")
    m = re.match(r"navstack process ([0-9.]+) %", note)
    jobs = sum(float(p) for name, p in NATIVE_THREAD.findall(note.split("(/proc per thread:", 1)[-1])
               if name.startswith("nav-worker"))
    return (float(m.group(1)) if m else float("nan")), jobs


def node_cpu(r):
    return sum(float(v.split()[0]) for k, v in r["notes"].items() if k.startswith("process.") and k != "process.roslaunch")


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    results = load(sys.argv[1:])
    native, bridged = collections.defaultdict(list), collections.defaultdict(list)
    for r in results:
        m = re.match(r"^(\w+?)_ros(?:_(\w+))?$", r["method"])
        if m:
            bridged[(r["board"], m.group(1), m.group(2) or "", r["scenario"], r["seed"])].append(r)
        else:
            native[(r["board"], r["method"], r["scenario"], r["seed"])].append(r)

    def spread(values, digits):
        mean = statistics.mean(values)
        if len(values) == 1:
            return f"{mean:.{digits}f}"
        return f"{mean:.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"

    print("Per flight pair (mean, and range over repeats): flight time in s, CPU in % of one board core.")
    print()
    print("| board | method | scenario | flights native / ROS | flight time native | flight time ROS | diff | "
          "path m native / ROS | native process (jobs) | ROS node | its jobs, roscpp, /clock, inputs, command | roslaunch |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    summary = collections.defaultdict(list)
    for (board, method, variant, scenario, seed), flights in sorted(bridged.items()):
        nat = native.get((board, method, scenario, seed))
        if not nat:
            continue
        tn = [n["flight_time_s"] for n in nat]
        tr = [r["flight_time_s"] for r in flights]
        path = (statistics.mean(n["path_length_m"] for n in nat), statistics.mean(r["path_length_m"] for r in flights))
        pn = [native_process(n)[0] for n in nat]
        jn = [native_process(n)[1] for n in nat]
        cr = [node_cpu(r) for r in flights]
        th = [node_threads(r) for r in flights]
        kinds = {k: statistics.mean(t[k] for t in th) for k in ("jobs", "roscpp", "/clock", "inputs", "command", "roslaunch")}
        failed = [f"{x['method']} {x['end_reason']}" for x in nat + flights if x["end_reason"] != "goal_reached"]
        name = method + (f" ({variant})" if variant else "")
        diff = 100 * (statistics.mean(tr) - statistics.mean(tn)) / statistics.mean(tn)
        print(f"| {board} | {name} | {scenario} | {len(nat)} / {len(flights)} | {spread(tn, 2)} | {spread(tr, 2)} | "
              f"{diff:+.1f} % | {path[0]:.1f} / {path[1]:.1f} | {spread(pn, 1)} ({statistics.mean(jn):.1f}) | {spread(cr, 1)} | "
              f"{kinds['jobs']:.1f}, {kinds['roscpp']:.1f}, {kinds['/clock']:.1f}, {kinds['inputs']:.1f}, "
              f"{kinds['command']:.1f} | {kinds['roslaunch']:.1f} |" + (f" not at the goal: {', '.join(failed)}" if failed else ""))
        summary[(board, name)].append((statistics.mean(tn), statistics.mean(tr), statistics.mean(pn),
                                       statistics.mean(jn), statistics.mean(cr), kinds["jobs"], diff))

    print()
    print("Per board and method, means over the scenarios:")
    print()
    print("| board | method | scenarios | flight time native / ROS | diff (range over scenarios) | "
          "nav CPU native process / ROS node | jobs native / ROS | ROS node - native process |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for (board, name), rows in sorted(summary.items()):
        mean = lambda i: statistics.mean(r[i] for r in rows)
        diffs = [r[6] for r in rows]
        print(f"| {board} | {name} | {len(rows)} | {mean(0):.2f} / {mean(1):.2f} | "
              f"{100 * (mean(1) - mean(0)) / mean(0):+.1f} % ({min(diffs):+.1f} to {max(diffs):+.1f}) | "
              f"{mean(2):.1f} / {mean(4):.1f} | {mean(3):.1f} / {mean(5):.1f} | {mean(4) - mean(2):+.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
