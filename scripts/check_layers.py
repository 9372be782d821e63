#!/usr/bin/env python3
"""Checks the module rules of docs/design/architecture.md against the sources' own includes.

  scripts/check_layers.py [SOURCE_DIR]     (the ctest `architecture_layers`)

For every tracked C++ file of a library module (tests, benchmarks programs and fuzzers aside,
which may include any module), each `#include "folder/..."` must name a module the table allows;
and no chain of includes between the repository's headers may come back to where it began.
Prints every violation (file:line, the include, the rule) and exits 1 when there is any.
"""
import os
import re
import subprocess
import sys

# Module -> the modules its library code may include (itself always). Kept in step with the
# table "may include" of docs/design/architecture.md.
BELOW_PIPELINE = {"core", "io", "mesh", "sampling", "section", "compare", "render", "photogrammetry",
                  "relief", "view"}
ALLOWED = {
    "core": set(),
    "io": {"core"},
    "mesh": {"core", "io"},
    "sampling": {"core", "io"},
    "section": {"core"},
    "compare": {"core", "io"},
    "render": {"core", "io"},
    "photogrammetry": {"core", "io"},
    "relief": {"core", "io", "photogrammetry"},
    "view": {"core", "io", "render"},
    "pipeline": BELOW_PIPELINE,
    "bench": BELOW_PIPELINE | {"pipeline"},
    "apps": BELOW_PIPELINE | {"pipeline", "bench"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def module_of(path):
    """The module a repository path belongs to, or None (tests, fuzz, examples, generated...)."""
    parts = path.split("/")
    if parts[0] == "reconstruction" and len(parts) > 2:
        return parts[1]
    return parts[0] if parts[0] in ALLOWED else None


def exempt(path):
    """Files that may include any module: unit tests and benchmark programs."""
    name = os.path.basename(path)
    return name.endswith("_test.cc") or name.endswith("_bench.cc")


def main():
    source = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                             os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    listed = subprocess.run(["git", "-C", source, "ls-files", "*.h", "*.cc"], capture_output=True, text=True)
    files = listed.stdout.split() if listed.returncode == 0 else []
    if not files:
        print("SKIP: no git checkout at " + source)
        return 0
    tracked = set(files)
    problems = []
    graph = {}
    for path in files:
        with open(os.path.join(source, path), encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n")
        graph[path] = []
        mod = module_of(path)
        for number, line in enumerate(lines, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            target = m.group(1)
            if target in tracked:
                graph[path].append((target, number))
            if mod is None or exempt(path):
                continue
            other = module_of(target)
            if target.startswith("tests/"):
                problems.append(f"{path}:{number}: includes {target}: library code never includes test helpers")
            elif other is not None and other != mod and other not in ALLOWED[mod]:
                problems.append(f"{path}:{number}: includes {target}: {mod} may include "
                                f"{', '.join(sorted(ALLOWED[mod])) or 'nothing'} (not {other})")
    # Include circles: a depth-first search over the repository's own includes.
    state = {}
    stack = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for target, number in graph.get(node, []):
            if state.get(target) == 1:
                cycle = stack[stack.index(target):] + [target]
                problems.append(f"{node}:{number}: include circle: " + " -> ".join(cycle))
            elif target not in state:
                visit(target)
        stack.pop()
        state[node] = 2

    sys.setrecursionlimit(10000)
    for node in sorted(graph):
        if node not in state:
            visit(node)
    for p in problems:
        print(p)
    print(f"{len(files)} files, {sum(len(v) for v in graph.values())} includes of the repository's own "
          f"files: {len(problems)} violation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
