#!/usr/bin/env python3
"""scripts/check_deps.py fails on a planted upward include in a navstack probe (and on a server
probe that includes bench/, the top layer, on a ros probe that includes workers/ or server/, and on
a method interface that links RL)
and passes on a clean one (a method folder's library, enavi_add_method, included), through both of its
routes: the source scan and the compiler's dependency output (the probe is run through the
compiler with -M, as the build does with -MD), the latter also with the probe compiled through a
generated file that includes it, as in a unity build.

Usage: check_deps_probe_test.py --checker PY --compiler CXX --source-dir REPO [--system-include DIR]...
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile

LAYERS = ("api", "worlds", "navstack", "workers", "server", "bench", "ros")  # the folders a probe tree links in


def make_tree(root, repo, probe_text, probe_layer):
    """A tree laid out like the repository: its layers linked in, <probe_layer>/probe/probe.cc added."""
    for layer in LAYERS:
        if layer != probe_layer:
            os.symlink(os.path.join(repo, layer), os.path.join(root, layer))
    os.makedirs(os.path.join(root, probe_layer, "probe"))
    for entry in os.listdir(os.path.join(repo, probe_layer)):
        os.symlink(os.path.join(repo, probe_layer, entry), os.path.join(root, probe_layer, entry))
    with open(os.path.join(root, probe_layer, "probe", "probe.cc"), "w") as f:
        f.write(probe_text)


def depfile_of(root, compiler, system_includes, unity, probe_layer):
    """The compiler's dependency output for the probe (headers it cannot find count as generated);
    unity: compiled through a generated file that includes it, as a CMake unity build does."""
    source = os.path.join(root, probe_layer, "probe", "probe.cc")
    if unity:
        unity_dir = os.path.join(root, "build", probe_layer, "CMakeFiles", "probe.dir", "Unity")
        os.makedirs(unity_dir)
        with open(os.path.join(unity_dir, "unity_0_cxx.cxx"), "w") as f:
            f.write(f'#include "{source}"\n')
        source = os.path.join(unity_dir, "unity_0_cxx.cxx")
    out = os.path.join(root, "probe.cc.o.d")
    cmd = [compiler, "-std=c++20", "-M", "-MG", "-MT", "probe.cc.o", "-MF", out, "-I", root]
    for d in system_includes:
        cmd += ["-isystem", d]
    cmd.append(source)
    subprocess.run(cmd, check=True, cwd=root)
    return out


def make_link_tree(root, repo, link_bench):
    """A tree with a library in bench/probe and one in server/probe that links it (link_bench) or not."""
    for layer in LAYERS:
        if layer not in ("server", "bench"):
            os.symlink(os.path.join(repo, layer), os.path.join(root, layer))
    for layer, body in (("bench", "add_library(enavi_bench_probe probe.cc probe.h)\n"),
                        ("server", "add_library(enavi_server_probe probe.cc)\n" +
                         ("target_link_libraries(enavi_server_probe PRIVATE enavi_bench_probe)\n"
                          if link_bench else ""))):
        os.makedirs(os.path.join(root, layer, "probe"))
        for name, text in (("CMakeLists.txt", body), ("probe.h", ""), ("probe.cc", "")):
            with open(os.path.join(root, layer, "probe", name), "w") as f:
                f.write(text)


def make_method_tree(root, repo, links):
    """A tree with a method folder navstack/methods/probe (enavi_add_method, LIBS <links>) whose source
    includes our stack's header and the method interface's; navstack/ is a copy, so that the
    checker reads its libraries (it does not follow symlinked folders)."""
    for layer in LAYERS:
        if layer != "navstack":
            os.symlink(os.path.join(repo, layer), os.path.join(root, layer))
    shutil.copytree(os.path.join(repo, "navstack"), os.path.join(root, "navstack"))
    methods = os.path.join(root, "navstack", "methods")
    os.makedirs(os.path.join(methods, "probe"))
    files = {
        "CMakeLists.txt": "enavi_add_method(probe\n  FUNCTIONS ProbeMethod\n  HEADER probe.h\n"
                          f"  SOURCES probe.cc probe.h\n  LIBS {links})\n",
        "probe.h": '#include "navstack/methods/method.h"\n',
        "probe.cc": '#include "navstack/methods/probe/probe.h"\n#include "navstack/stack/nav_stack.h"\n',
    }
    for name, text in files.items():
        with open(os.path.join(methods, "probe", name), "w") as f:
            f.write(text)


def make_method_api_tree(root, repo, extra_link):
    """A copy of navstack/ whose method interface also links `extra_link`."""
    for layer in LAYERS:
        if layer != "navstack":
            os.symlink(os.path.join(repo, layer), os.path.join(root, layer))
    shutil.copytree(os.path.join(repo, "navstack"), os.path.join(root, "navstack"))
    path = os.path.join(root, "navstack", "methods", "CMakeLists.txt")
    with open(path) as f:
        text = f.read()
    line = "target_link_libraries(enavi_method_api INTERFACE enavi::planning enavi::runtime)"
    assert line in text, "the probe edits the method interface's link line"
    with open(path, "w") as f:
        f.write(text.replace(line, line[:-1] + " " + extra_link + ")"))


def run_checker(checker, root, only, depfile=None):
    cmd = [sys.executable, checker, "--source-dir", root, "--only", only]
    if depfile:
        cmd += ["--depfile", depfile]
    return subprocess.run(cmd, capture_output=True, text=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--checker", required=True)
    parser.add_argument("--compiler", required=True)
    parser.add_argument("--source-dir", required=True)
    parser.add_argument("--system-include", action="append", default=[])
    args = parser.parse_args()
    repo = os.path.abspath(args.source_dir)

    # (layer of the probe, probe, expected exit code, text the report must contain)
    cases = [
        ("navstack", '#include "workers/sim/episode.h"\n', 1, "workers/sim/episode.h"),
        ("navstack", '#include "server/cli/commands.h"\n', 1, "server/cli/commands.h"),
        ("navstack", '#include "bench/farm/farm_processes.h"\n', 1, "bench/farm/farm_processes.h"),
        ("navstack", "#include <btBulletDynamicsCommon.h>\n", 1, "Bullet"),
        ("navstack", "#include <embree3/rtcore.h>\n", 1, "Embree"),
        ("navstack", '#include "api/dds.h"\n', 1, "api/dds.h"),
        ("navstack", '#include "navstack/runtime/task.h"\n#include "api/episode.h"\n', 0, "clean"),
        # bench/ is the top layer: the CLI's bench cores live in server/bench, not bench/.
        ("server", '#include "bench/farm/farm_processes.h"\n', 1, "bench/farm/farm_processes.h"),
        ("server", '#include "server/bench/raycast_bench.h"\n#include "workers/sim/episode.h"\n', 0, "clean"),
        # Our ROS node (ros/) uses navstack and api only: not the farm's workers or server.
        ("ros", '#include "workers/sim/episode.h"\n', 1, "workers/sim/episode.h"),
        ("ros", '#include "server/cli/commands.h"\n', 1, "server/cli/commands.h"),
        ("ros", '#include "navstack/runtime/time_source.h"\n#include "api/ros_stack.h"\n', 0, "clean"),
    ]
    failures = []
    routes = (("sources", False), ("depfiles", False), ("unity", True))
    for layer, probe, expected, needle in cases:
        for route, unity in routes:
            with tempfile.TemporaryDirectory() as root:
                make_tree(root, repo, probe, layer)
                only = "sources" if route == "sources" else "depfiles"
                depfile = (depfile_of(root, args.compiler, args.system_include, unity, layer)
                           if only == "depfiles" else None)
                r = run_checker(args.checker, root, only, depfile)
                report = r.stdout + r.stderr
                ok = r.returncode == expected and needle in report
                print(f"{'ok  ' if ok else 'FAIL'} {route:8} exit {r.returncode} (want {expected}) "
                      f"for {layer} {probe.strip()!r}")
                if not ok:
                    failures.append(f"{route}: {layer} {probe.strip()!r}: exit {r.returncode}, wanted {expected} "
                                    f"and '{needle}' in:\n{report}")
    # CMake probes, on the source scan: (what, how to lay out the tree, expected exit, needle).
    cmake_cases = [
        # A library outside bench/ linking one of bench/ (without including it) breaks the rule too.
        ("a server library linking a bench/ library", lambda root: make_link_tree(root, repo, True), 1,
         "links enavi_bench_probe of bench/"),
        ("a server library not linking a bench/ library", lambda root: make_link_tree(root, repo, False), 0, "clean"),
        # A method folder's library (enavi_add_method) includes only what it links, as any library does.
        ("a method folder linking enavi::planning and including the stack's header",
         lambda root: make_method_tree(root, repo, "enavi::planning"), 1,
         "enavi_probe includes navstack/stack/nav_stack.h of enavi_stack, which it does not link"),
        ("a method folder linking enavi::stack and including the stack's header",
         lambda root: make_method_tree(root, repo, "enavi::stack"), 0, "clean"),
        # The method interface every method links stays narrow: linking RL (through anything) fails.
        ("the method interface linking enavi::rl", lambda root: make_method_api_tree(root, repo, "enavi::rl"), 1,
         "enavi_method_api links enavi_rl"),
        ("the method interface linking nothing more", lambda root: make_method_api_tree(root, repo, ""), 0, "clean"),
    ]
    for what, lay_out, expected, needle in cmake_cases:
        with tempfile.TemporaryDirectory() as root:
            lay_out(root)
            r = run_checker(args.checker, root, "sources")
            report = r.stdout + r.stderr
            ok = r.returncode == expected and needle in report
            print(f"{'ok  ' if ok else 'FAIL'} cmake    exit {r.returncode} (want {expected}) for {what}")
            if not ok:
                failures.append(f"cmake probe, {what}: exit {r.returncode}, wanted {expected} "
                                f"and '{needle}' in:\n{report}")
    for f in failures:
        print(f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
