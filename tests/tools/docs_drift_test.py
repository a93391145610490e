#!/usr/bin/env python3
"""Checks the docs' lists against the build, so that they cannot drift apart unnoticed.

Fuzz targets: the `raycell_fuzz_target(NAME ...)` calls of fuzz/CMakeLists.txt are exactly
the targets .ci/run's fuzz step runs (`fuzz/run.sh NAME`, directly or through a
`for VAR in ...` loop, in the step "fuzz..."), those named in docs/design.md §4 "fuzz/" and in CONTRIBUTING.md's
"Fuzz" section (each a list sentence starting "One libFuzzer target per parser of untrusted
input", its targets in backticks outside parentheses), and each has its corpus
fuzz/corpus/NAME/.

Modules: the top-level CMakeLists.txt's add_subdirectory list minus tests and fuzz is exactly
the module folders of the layout block of docs/design.md §4 (its lines `NAME/ ...`, minus the
folders that are not modules: tests, fuzz, docs, cmake, scenes) and the keys of tools/check_deps.py's DEPS;
every folder of the layout block exists.

Then it plants drift in a copy of those files (a name dropped from each list, an extra
module) and checks that each is reported. Run by ctest (docs_drift_test).

Usage: tests/tools/docs_drift_test.py ROOT   (exit 1 and one line per mismatch)
"""
import ast
import pathlib
import re
import shutil
import sys
import tempfile

NOT_BUILT_AS_MODULES = {"tests", "fuzz"}  # add_subdirectory'd, but not modules
NOT_MODULES_IN_LAYOUT = {"tests", "fuzz", "docs", "cmake", "scenes"}  # folders of the layout block
FILES = ["CMakeLists.txt", "fuzz/CMakeLists.txt", ".ci/run", "docs/design.md",
         "CONTRIBUTING.md", "tools/check_deps.py"]
LIST_START = "One libFuzzer target per parser of untrusted input"


class ParseError(Exception):
    pass


def cmake_code(text):
    """CMake text without comments (a # outside quotes starts one; good enough here)."""
    return "\n".join(line.split("#", 1)[0] for line in text.splitlines())


def fuzz_targets_of_cmake(text):
    names = re.findall(r"^\s*raycell_fuzz_target\(\s*([A-Za-z0-9_]+)", cmake_code(text), re.M)
    if not names:
        raise ParseError("fuzz/CMakeLists.txt: no raycell_fuzz_target(NAME ...) call")
    return names


def fuzz_targets_of_ci(text):
    """The NAMEs of `fuzz/run.sh NAME`, a $VAR resolved through `for VAR in LIST; do`."""
    m = re.search(r'^step "fuzz[^\n]*\n(.*?)(?=^step "|\Z)', text, re.M | re.S)
    if not m:
        raise ParseError('.ci/run: no step "fuzz..."')
    loops, names = {}, []
    for line in m.group(1).splitlines():
        if line.lstrip().startswith("#"):
            continue
        for var, values in re.findall(r"\bfor\s+(\w+)\s+in\s+([^;]*);", line):
            loops[var] = values.split()
        for arg in re.findall(r"\bfuzz/run\.sh\s+(\S+)", line):
            m = re.fullmatch(r'"?\$\{?(\w+)\}?"?', arg)
            if m:
                if m.group(1) not in loops:
                    raise ParseError(f".ci/run: fuzz/run.sh {arg}: no `for {m.group(1)} in` loop")
                names.extend(loops[m.group(1)])
            else:
                names.append(arg.strip("'\""))
    if not names:
        raise ParseError(".ci/run: no `fuzz/run.sh NAME` line in the fuzz step")
    return names


def section(text, heading_re, what):
    """The text of the Markdown section whose heading matches, up to the next heading of
    its level or above."""
    m = re.search(heading_re, text, re.M)
    if not m:
        raise ParseError(f"{what}: no heading matching {heading_re!r}")
    level = len(re.match(r"#+", m.group(0)).group(0))
    end = re.compile(r"^#{1,%d} " % level, re.M).search(text, m.end())
    return text[m.end():end.start() if end else len(text)]


def listed_targets(text, what):
    """The backticked names at parenthesis depth 0 of the sentence that starts with
    LIST_START, from its colon to the first full stop outside parentheses and backticks."""
    start = text.find(LIST_START)
    if start < 0:
        raise ParseError(f"{what}: no sentence starting '{LIST_START}'")
    i, depth = start + len(LIST_START), 0
    while i < len(text) and not (text[i] == ":" and depth == 0):  # skip "(... design.md ...)"
        if depth == 0 and text[i] == "." and (i + 1 == len(text) or text[i + 1].isspace()):
            break  # the sentence ends without a list
        depth += {"(": 1, ")": -1}.get(text[i], 0)
        i += 1
    if i == len(text) or text[i] != ":":
        raise ParseError(f"{what}: the sentence '{LIST_START}' has no ':' before its list")
    names, depth, i = [], 0, i + 1
    while i < len(text):
        c = text[i]
        if c == "`":
            close = text.find("`", i + 1)
            if close < 0:
                raise ParseError(f"{what}: an unclosed backtick in the list of fuzz targets")
            if depth == 0:
                names.append(text[i + 1:close])
            i = close + 1
            continue
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
        elif c == "." and depth == 0 and (i + 1 == len(text) or text[i + 1].isspace()):
            break
        i += 1
    if not names:
        raise ParseError(f"{what}: the list of fuzz targets names none")
    return names


def fuzz_targets_of_design(text):
    what = 'docs/design.md §4 "fuzz/"'
    layout = section(text, r"^## 4\. ", "docs/design.md §4")
    m = re.search(r"^\*\*fuzz/\.\*\*", layout, re.M)
    if not m:
        raise ParseError(f"{what}: no paragraph starting **fuzz/.**")
    return listed_targets(layout[m.start():], what)


def fuzz_targets_of_contributing(text):
    return listed_targets(section(text, r"^## Fuzz\s*$", "CONTRIBUTING.md"),
                          'CONTRIBUTING.md "Fuzz"')


def modules_of_cmake(text):
    subdirs = re.findall(r"^\s*add_subdirectory\(\s*([A-Za-z0-9_./-]+)", cmake_code(text), re.M)
    if not subdirs:
        raise ParseError("CMakeLists.txt: no add_subdirectory")
    return [s for s in subdirs if s not in NOT_BUILT_AS_MODULES]


def folders_of_layout(text):
    layout = section(text, r"^## 4\. ", "docs/design.md §4")
    m = re.search(r"^```[^\n]*\n(.*?)^```", layout, re.M | re.S)
    if not m:
        raise ParseError("docs/design.md §4: no layout block (```)")
    folders = re.findall(r"^([A-Za-z0-9_.-]+)/(?:\s|$)", m.group(1), re.M)
    if not folders:
        raise ParseError("docs/design.md §4: the layout block lists no folder")
    return folders


def modules_of_check_deps(text):
    for node in ast.parse(text).body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and getattr(node.targets[0], "id", None) == "DEPS"
                and isinstance(node.value, ast.Dict)):
            return [ast.literal_eval(k) for k in node.value.keys]
    raise ParseError("tools/check_deps.py: no DEPS = {...}")


def compare(errors, reference_name, reference, others):
    """One line per source whose names differ from the reference's, or repeat one."""
    ref = set(reference)
    for name, got in others:
        seen = set()
        for n in got:
            if n in seen:
                errors.append(f"{name}: names {n} twice")
            seen.add(n)
        missing, extra = sorted(ref - seen), sorted(seen - ref)
        if missing or extra:
            parts = []
            if missing:
                parts.append("lacks " + ", ".join(missing))
            if extra:
                parts.append("names " + ", ".join(extra) + f", not in {reference_name}")
            errors.append(f"{name}: " + "; ".join(parts))


def check(root):
    """Every mismatch between the docs and the build under root, one line each."""
    errors = []

    def read(rel):
        return (root / rel).read_text()

    try:  # the fuzz targets
        targets = fuzz_targets_of_cmake(read("fuzz/CMakeLists.txt"))
        compare(errors, "fuzz/CMakeLists.txt", targets, [
            ("fuzz/CMakeLists.txt", targets),
            (".ci/run's fuzz step", fuzz_targets_of_ci(read(".ci/run"))),
            ('docs/design.md §4 "fuzz/"', fuzz_targets_of_design(read("docs/design.md"))),
            ('CONTRIBUTING.md "Fuzz"', fuzz_targets_of_contributing(read("CONTRIBUTING.md"))),
        ])
        for t in targets:
            if not (root / "fuzz" / "corpus" / t).is_dir():
                errors.append(f"fuzz target {t} has no seed corpus fuzz/corpus/{t}/")
    except (ParseError, OSError) as e:
        errors.append(f"cannot read the fuzz targets: {e}")

    try:  # the modules
        modules = modules_of_cmake(read("CMakeLists.txt"))
        layout = folders_of_layout(read("docs/design.md"))
        for f in layout:
            if not (root / f).is_dir():
                errors.append(f"docs/design.md §4 layout: {f}/ is not a folder")
        compare(errors, "CMakeLists.txt's add_subdirectory", modules, [
            ("CMakeLists.txt's add_subdirectory", modules),
            ("docs/design.md §4 layout", [f for f in layout if f not in NOT_MODULES_IN_LAYOUT]),
            ("tools/check_deps.py DEPS", modules_of_check_deps(read("tools/check_deps.py"))),
        ])
    except (ParseError, OSError, SyntaxError) as e:
        errors.append(f"cannot read the modules: {e}")
    return errors


def planted(root, tmp, rel, edit):
    """A copy of the checked files (and the folders the check looks for) under tmp, with
    edit applied to rel's text; edit must change it."""
    if tmp.exists():
        shutil.rmtree(tmp)
    for f in FILES:
        (tmp / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(root / f, tmp / f)
    for d in list(root.iterdir()) + list((root / "fuzz" / "corpus").iterdir()):
        if d.is_dir():
            (tmp / d.relative_to(root)).mkdir(parents=True, exist_ok=True)
    text = (tmp / rel).read_text()
    changed = edit(text)
    if changed == text:
        raise ParseError(f"planting drift in {rel}: the edit changed nothing")
    (tmp / rel).write_text(changed)
    return tmp


def self_test(root):
    """Plants one drift per source and checks each is reported, naming what drifted."""
    failures = []
    design = (root / "docs/design.md").read_text()
    design_target = fuzz_targets_of_design(design)[-1]
    contributing_target = fuzz_targets_of_contributing(
        (root / "CONTRIBUTING.md").read_text())[-1]
    layout_module = [f for f in folders_of_layout(design) if f not in NOT_MODULES_IN_LAYOUT][-1]

    def drop_in_fuzz_paragraph(text):  # unquote the last target of design's fuzz/ list
        start = text.index("**fuzz/.**")
        at = text.index(f"`{design_target}`", start)
        return text[:at] + design_target + text[at + len(design_target) + 2:]

    def drop_in_contributing(text):
        start = text.index(LIST_START, text.index("## Fuzz"))
        at = text.index(f"`{contributing_target}`", start)
        return text[:at] + contributing_target + text[at + len(contributing_target) + 2:]

    def drop_layout_line(text):
        return re.sub(rf"^{re.escape(layout_module)}/[^\n]*\n", "", text, count=1, flags=re.M)

    cases = [
        ("docs/design.md", drop_in_fuzz_paragraph, f"lacks {design_target}"),
        ("CONTRIBUTING.md", drop_in_contributing, f"lacks {contributing_target}"),
        (".ci/run", lambda t: re.sub(r"(fuzz/run\.sh\s+)(\w+)", r"\1renamed_target", t, count=1),
         "renamed_target"),
        ("fuzz/CMakeLists.txt", lambda t: t + "raycell_fuzz_target(unlisted_target LIBS x)\n",
         "unlisted_target"),
        ("docs/design.md", drop_layout_line, f"lacks {layout_module}"),
        ("tools/check_deps.py", lambda t: t.replace("DEPS = {", 'DEPS = {\n    "ghost": set(),', 1),
         "ghost"),
        ("CMakeLists.txt", lambda t: t + "add_subdirectory(ghost)\n", "ghost"),
    ]
    with tempfile.TemporaryDirectory() as d:
        for rel, edit, expected in cases:
            errors = check(planted(root, pathlib.Path(d) / "tree", rel, edit))
            if not any(expected in e for e in errors):
                failures.append(f"self-test: drift planted in {rel} ({expected}) was not "
                                f"reported; got {errors}")
    return failures


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    errors = check(root)
    if not errors:
        try:
            errors = self_test(root)
        except (ParseError, ValueError) as e:
            errors = [f"self-test: {e}"]
    for e in errors:
        print(e)
    if errors:
        print(f"docs_drift_test: {len(errors)} mismatch(es) between the docs and the build")
        return 1
    print("docs_drift_test: the fuzz targets and modules of the docs are the build's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
