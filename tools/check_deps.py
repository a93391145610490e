#!/usr/bin/env python3
"""Checks that includes follow the module order of docs/design.md §4.

    base < engine, traces < graph < bounds, search < analysis
                                    search < scheduling < replay < runner
                 record, analysis, runner < study < tools

A module may include its own headers and those of the modules below it (DEPS, closed
transitively); base includes no other module; bounds (GLPK) and search (threads) are siblings,
and neither scheduling, replay nor runner sees bounds or analysis, so they never link GLPK;
replay (the model) sees no runner (the driver, sweeps and outputs on it);
record (the renderer) is included only from study, tools and the tests; test code only from
the tests, but for the replay's oracle (tests/oracle/) in the benchmarks (tools/bench/); OpenVDB headers
appear only in record. Every target exports the project root as its include path, so a wrong
edge through a header is caught by nothing else.

Usage: tools/check_deps.py [ROOT]   (exit 1 and one line per wrong include)
"""
import pathlib
import re
import sys

# The modules each module stands on directly; ALLOWED closes it transitively.
DEPS = {
    "base": set(),
    "engine": {"base"},
    "traces": {"base"},
    "record": {"traces"},
    "graph": {"traces"},
    "bounds": {"graph"},
    "search": {"graph"},
    "analysis": {"bounds", "search"},
    "scheduling": {"search"},
    "replay": {"engine", "scheduling"},
    "runner": {"replay"},
    "study": {"analysis", "runner", "record"},
    "tools": {"study", "record", "analysis", "runner"},
}


def closure(deps):
    """Every module each module may include: its DEPS and theirs, transitively."""
    allowed = {}
    for mod in deps:
        seen, todo = set(), list(deps[mod])
        while todo:
            d = todo.pop()
            if d not in seen:
                seen.add(d)
                todo.extend(deps[d])
        allowed[mod] = seen
    return allowed


ALLOWED = closure(DEPS)
# Tests and fuzz targets may include any module; OpenVDB still only in record's tests.
ANY = {"tests", "fuzz"}
OPENVDB_OK = ("record/", "tests/record/")
# The benchmarks that measure against the replay's independent oracle may include it.
ORACLE = "tests/oracle/"
ORACLE_OK = ("tools/bench/",)
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def module_of(rel):
    """The module a project path belongs to, or None for paths outside the modules."""
    top = rel.split("/", 1)[0]
    if top in ALLOWED or top in ANY:
        return top
    return None


def check(root):
    errors = []
    sources = [p for ext in ("*.h", "*.cpp", "*.cc") for p in root.rglob(ext)]
    for path in sorted(sources):
        rel = path.relative_to(root).as_posix()
        if rel.startswith("build") or "/build" in rel.split("/", 1)[0]:
            continue
        mod = module_of(rel)
        if mod is None:
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            bracket, target = m.groups()
            if "openvdb" in target.lower() or "nanovdb" in target.lower():
                if not rel.startswith(OPENVDB_OK):
                    errors.append(f"{rel}:{n}: OpenVDB header <{target}> outside record")
                continue
            if bracket != '"':
                continue
            dep = module_of(target)
            if target.startswith(ORACLE) and rel.startswith(ORACLE_OK):
                continue
            if dep is None or dep == mod or mod in ANY:
                continue
            if dep not in ALLOWED[mod] and dep not in ANY:
                errors.append(f"{rel}:{n}: {mod} includes {target} ({dep} is not below {mod})")
            elif dep in ANY:
                errors.append(f"{rel}:{n}: {mod} includes test code {target}")
    return errors


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    errors = check(root)
    for e in errors:
        print(e)
    if errors:
        print(f"check_deps: {len(errors)} include(s) against the module order of docs/design.md §4")
        return 1
    print("check_deps: every include follows the module order")
    return 0


if __name__ == "__main__":
    sys.exit(main())
