#!/usr/bin/env python3
"""The dependency rules of the build (docs/design.md, "The dependency rules and their check"),
checked two ways:

  sources: every #include in api/, worlds/, navstack/, workers/ and server/ against the layer
           rules, every project header a library's sources include against the library's link
           closure (a target includes only its own headers and those of targets it links), no
           target outside bench/ links one of bench/, and the method interface
           (enavi::method_api, which every method links) links none of our stack's modules;
  depfiles: the compiler's dependency output (*.o.d under the build tree) of every navstack,
           workers, server and ros object, which also sees headers reached through other headers (a
           unity build's object counts for the sources it includes).

bench/ is the top of the tree: its programs may use any layer, server/ included, and no layer
includes or links bench/ code. ros/ (our navigation methods as a ROS node, built with ROS only)
sits beside workers/: it may use api/ and navstack/, never workers/, server/ or bench/.

Exits 1 listing each violation as FILE:LINE: rule, 2 on bad arguments, 0 when the tree is clean.
"""

import argparse
import os
import re
import sys

LAYERS = ("api", "worlds", "navstack", "workers", "server", "ros")

# Third-party headers a layer must never see, by the include path's first component (sources)
# or by a directory in the resolved path (depfiles).
BULLET = re.compile(r"^(bt[A-Z]\w*\.h|Bullet\w*/|LinearMath/)")
EMBREE = re.compile(r"^embree\d*/")
CYCLONE = re.compile(r"^(dds/|ddsc/|idl/|api/dds\.h$)")
THIRD_PARTY_DIRS = (
    ("Bullet", re.compile(r"/(bullet|Bullet\w*|LinearMath)/")),
    ("Embree", re.compile(r"/embree\d*/")),
    ("Cyclone DDS", re.compile(r"/(dds|ddsc|ddsrt)/")),
)

# What each layer must not include: (pattern on the include text, what it is).
FORBIDDEN = {
    "api": [(re.compile(r"^(navstack|workers|server|bench)/"), "api includes a higher layer or bench/")],
    "worlds": [(re.compile(r"^(navstack|workers|server|bench)/"), "worlds includes a higher layer or bench/")],
    "navstack": [
        (re.compile(r"^(workers|server|bench)/"), "navstack includes workers/, server/ or bench/"),
        (BULLET, "navstack includes a Bullet header"),
        (EMBREE, "navstack includes an Embree header"),
        (CYCLONE, "navstack includes a Cyclone DDS header"),
    ],
    "workers": [(re.compile(r"^(server|bench)/"), "workers includes server/ or bench/")],
    # bench/ sits above server/: its programs measure server code too (ingest, the dashboard).
    "server": [(re.compile(r"^bench/"), "server includes bench/")],
    # Our ROS node runs a method as a user's stack would: on navstack and api, nothing of the farm's.
    "ros": [(re.compile(r"^(workers|server|bench)/"), "ros includes workers/, server/ or bench/")],
}

# The generated file a CMake unity build compiles in place of a target's sources.
UNITY_SOURCE = re.compile(r"/Unity/unity_\d+_\w+\.\w+$")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
SOURCE_EXT = (".h", ".cc", ".cpp", ".hpp")


def layer_of(rel):
    first = rel.split("/", 1)[0]
    return first if first in LAYERS else None


def source_files(root):
    for layer in FORBIDDEN:
        for dirpath, _, names in os.walk(os.path.join(root, layer)):
            for name in sorted(names):
                if name.endswith(SOURCE_EXT):
                    yield os.path.relpath(os.path.join(dirpath, name), root)


def includes_of(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE.match(line)
            if m:
                yield number, m.group(2)


def check_layers(root):
    problems = []
    for rel in source_files(root):
        layer = layer_of(rel)
        for number, inc in includes_of(os.path.join(root, rel)):
            for pattern, rule in FORBIDDEN[layer]:
                if pattern.search(inc):
                    problems.append(f"{rel}:{number}: {rule} ({inc})")
    return problems


# --- Targets from the CMakeLists: explicit source lists and link libraries ---

COMMAND = re.compile(r"\b(add_library|target_link_libraries|enavi_add_method)\s*\(([^)]*)\)", re.S)
# enavi_add_method(<name> FUNCTIONS .. HEADER .. SOURCES .. LIBS ..) (cmake/EnaviHelpers.cmake): the
# library enavi_<name>, alias enavi::<name>, on the method interface.
METHOD_KEYWORDS = ("FUNCTIONS", "HEADER", "SOURCES", "LIBS")


def cmake_targets(root):
    """{target: {"dir", "headers", "links"}} for every enavi library with a source list."""
    targets, aliases = {}, {}
    for dirpath, dirs, names in os.walk(root):
        dirs[:] = [d for d in dirs if not d.startswith(".") and d not in ("build", "tests")]
        if "CMakeLists.txt" not in names:
            continue
        rel_dir = os.path.relpath(dirpath, root)
        with open(os.path.join(dirpath, "CMakeLists.txt"), encoding="utf-8") as f:
            text = re.sub(r"#[^\n]*", "", f.read())
        for command, body in COMMAND.findall(text):
            words = body.split()
            if not words:
                continue
            name = words[0]
            if command == "enavi_add_method":
                args, key = {}, None
                for w in words[1:]:
                    if w in METHOD_KEYWORDS:
                        key = w
                        args[key] = []
                    elif key:
                        args[key].append(w)
                aliases["enavi::" + name] = "enavi_" + name
                files = {os.path.normpath(os.path.join(rel_dir, w))
                         for w in args.get("SOURCES", []) + args.get("HEADER", []) if w.endswith(SOURCE_EXT)}
                targets["enavi_" + name] = {"dir": rel_dir, "files": files,
                                            "links": set(args.get("LIBS", [])) | {"enavi::method_api"}}
            elif command == "add_library":
                if len(words) >= 3 and words[1] == "ALIAS":
                    aliases[name] = words[2]
                else:
                    files = {os.path.normpath(os.path.join(rel_dir, w)) for w in words[1:]
                             if w.endswith(SOURCE_EXT) and "$" not in w}
                    targets[name] = {"dir": rel_dir, "files": files, "links": set()}
            elif name in targets:
                targets[name]["links"].update(w for w in words[1:] if w not in ("PUBLIC", "PRIVATE", "INTERFACE"))
    for t in targets.values():
        t["links"] = {aliases.get(l, l) for l in t["links"]} & set(targets)
    return targets


def closure(targets, name):
    seen, todo = {name}, [name]
    while todo:
        for dep in targets[todo.pop()]["links"]:
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return seen


def check_targets(root):
    """A library's sources include only project headers of targets in its link closure."""
    targets = cmake_targets(root)
    owner = {f: name for name, t in targets.items() for f in t["files"] if f.endswith(".h")}
    problems = []
    for name, t in sorted(targets.items()):
        allowed = closure(targets, name)
        for rel in sorted(t["files"]):
            if not os.path.exists(os.path.join(root, rel)):
                continue
            for number, inc in includes_of(os.path.join(root, rel)):
                dep = owner.get(inc)
                if dep and dep not in allowed:
                    problems.append(f"{rel}:{number}: {name} includes {inc} of {dep}, which it does not link")
    return problems


def check_unused_links(root):
    """A library links only targets whose headers it includes (imports of ours, not third party)."""
    targets = cmake_targets(root)
    owner = {f: name for name, t in targets.items() for f in t["files"] if f.endswith(".h")}
    problems = []
    for name, t in sorted(targets.items()):
        used = set()
        for rel in t["files"]:
            if os.path.exists(os.path.join(root, rel)):
                used.update(owner.get(inc) for _, inc in includes_of(os.path.join(root, rel)))
        for dep in sorted(t["links"] - used):
            if targets[dep]["files"]:
                problems.append(f"{t['dir']}/CMakeLists.txt: {name} links {dep} but includes none of its headers")
    return problems


def check_bench_links(root):
    """No target outside bench/ links a target defined in bench/ (bench/ is the top layer)."""
    targets = cmake_targets(root)
    in_bench = {name for name, t in targets.items() if t["dir"].split("/", 1)[0] == "bench"}
    problems = []
    for name, t in sorted(targets.items()):
        if name in in_bench:
            continue
        for dep in sorted(t["links"] & in_bench):
            problems.append(f"{t['dir']}/CMakeLists.txt: {name} links {dep} of bench/, the top layer")
    return problems


# What every method links stays narrow: a method links our stack's perception, eci, RL, strategy
# or the stack itself only when it uses them (docs/design.md).
METHOD_API_FORBIDS = ("enavi_rl", "enavi_strategy", "enavi_eci", "enavi_perception", "enavi_adapt",
                      "enavi_stack", "enavi_episode")


def check_method_api(root):
    """enavi_method_api's link closure holds none of METHOD_API_FORBIDS."""
    targets = cmake_targets(root)
    if "enavi_method_api" not in targets:
        return []
    reached = closure(targets, "enavi_method_api")
    return [f"{targets['enavi_method_api']['dir']}/CMakeLists.txt: enavi_method_api links {name} (through "
            f"its link closure): the method interface every method links must not pull in our stack's modules"
            for name in METHOD_API_FORBIDS if name in reached]


# --- The compiler's dependency output ---

def depfile_deps(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read().replace("\\\n", " ")
    _, _, deps = text.partition(": ")
    first_rule = deps.split("\n", 1)[0]
    return first_rule.split()


def check_depfile(path, source_root, build_root):
    """Violations in one object's dependencies; the object's layer is its source's."""
    deps = depfile_deps(path)
    if not deps:
        return []
    base = os.path.dirname(path)
    # Makefile depfiles are relative to the object's target directory's build folder.
    anchor = build_root
    resolved = []
    for d in deps:
        if os.path.isabs(d):
            resolved.append(os.path.normpath(d))
            continue
        for start in (os.path.join(build_root, os.path.relpath(base, build_root).split("/CMakeFiles/")[0]),
                      build_root, base):
            p = os.path.normpath(os.path.join(start, d))
            if os.path.exists(p):
                resolved.append(p)
                break
        else:
            resolved.append(os.path.normpath(os.path.join(anchor, d)))
    source_root = os.path.abspath(source_root)
    rel_source = os.path.relpath(os.path.abspath(resolved[0]), source_root)
    if UNITY_SOURCE.search(resolved[0]):
        # A unity object: its layer is that of the target's sources the generated file includes.
        included = (os.path.relpath(os.path.abspath(p), source_root) for p in resolved[1:]
                    if p.endswith((".cc", ".cpp")))
        rel_source = next((r for r in included if layer_of(r)), rel_source)
    layer = layer_of(rel_source)
    if layer not in ("navstack", "workers", "server", "ros"):
        return []
    problems = []
    for p in resolved[1:]:
        real = os.path.abspath(p)
        rel = os.path.relpath(real, source_root)
        if not rel.startswith(".."):
            dep_layer = layer_of(rel)
            if rel.split("/", 1)[0] == "bench":
                problems.append(f"{rel_source}: {layer} depends on bench code {rel}")
            elif layer == "server":
                continue
            elif layer == "navstack" and dep_layer in ("workers", "server"):
                problems.append(f"{rel_source}: navstack depends on {rel}")
            elif layer == "workers" and dep_layer == "server":
                problems.append(f"{rel_source}: workers depends on {rel}")
            elif layer == "ros" and dep_layer in ("workers", "server"):
                problems.append(f"{rel_source}: ros depends on {rel}")
            elif layer == "navstack" and rel == "api/dds.h":
                problems.append(f"{rel_source}: navstack depends on the Cyclone DDS wrapper {rel}")
        elif layer == "navstack":
            for what, pattern in THIRD_PARTY_DIRS:
                if pattern.search(real):
                    problems.append(f"{rel_source}: navstack depends on {what} ({real})")
    return problems


def check_depfiles(source_root, build_root, explicit):
    files = list(explicit)
    if build_root:
        for dirpath, _, names in os.walk(build_root):
            files += [os.path.join(dirpath, n) for n in sorted(names) if n.endswith(".o.d")]
    problems = []
    for f in files:
        problems += check_depfile(f, source_root, build_root or os.path.dirname(f))
    return problems, len(files)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source-dir", required=True, help="the repository (or a probe tree laid out like it)")
    parser.add_argument("--build-dir", help="a build tree whose *.o.d depfiles to check")
    parser.add_argument("--depfile", action="append", default=[], help="one more depfile to check")
    parser.add_argument("--only", choices=("sources", "depfiles"), help="run one of the two checks")
    args = parser.parse_args()
    if not os.path.isdir(args.source_dir):
        print(f"check_deps: --source-dir {args.source_dir}: not a directory", file=sys.stderr)
        return 2
    if args.build_dir and not os.path.isdir(args.build_dir):
        print(f"check_deps: --build-dir {args.build_dir}: not a directory", file=sys.stderr)
        return 2
    problems, depfiles = [], 0
    if args.only != "depfiles":
        problems += check_layers(args.source_dir)
        problems += check_targets(args.source_dir) + check_unused_links(args.source_dir)
        problems += check_bench_links(args.source_dir) + check_method_api(args.source_dir)
    if args.only != "sources":
        dep_problems, depfiles = check_depfiles(args.source_dir, args.build_dir, args.depfile)
        problems += dep_problems
    for p in problems:
        print(p)
    if problems:
        print(f"check_deps: {len(problems)} violation(s)", file=sys.stderr)
        return 1
    print(f"check_deps: clean ({depfiles} depfile(s) read)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
