#!/usr/bin/env python3
"""Checks that every #include in host/ and cli/ follows the floors docs/ARCHITECTURE.md declares, and that bench/'s
Python imports follow its two layers.

The document is the source of truth: its ```floors block lists the folders from the ground floor up, one floor a
line (folders on one line share a floor and may not include each other), then `beside` lines of the form
`ref: core cl data ops mlp` for a folder outside the floors that may include only the listed folders and that no
floor may include. A folder may include its own files and any folder on a lower floor. A folder under host/ that
the document does not name, or a floor that includes upward or sideways, fails the check with one line per include.

bench/ (read with ast, every import at any level): a study (bench/studies/NAME.py) may import bench/lib/ and no other
study (shared code goes to bench/lib/); a bench/lib/ module never imports a study; a Python file directly in bench/
(outside lib/ and studies/) fails too. One line per offending import.

  scripts/check_layers.py [ROOT]           (ROOT: the project's root, default: this script's parent folder)
  scripts/check_layers.py --graph [ROOT]   prints each folder and the folders it includes, and checks nothing
Exit status 0 when every include is allowed, 1 with the offending includes listed otherwise, 2 on a bad document.
"""
import ast
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/[^"]+"', re.MULTILINE)


def read_floors(doc: pathlib.Path):
    text = doc.read_text(encoding="utf-8")
    block = re.search(r"```floors\n(.*?)```", text, re.DOTALL)
    if not block:
        sys.exit(f"{doc}: no ```floors block (the layering this check enforces)")
    floor_of, beside = {}, {}
    for line in block.group(1).splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        if ":" in line:
            name, allowed = line.split(":", 1)
            beside[name.strip()] = set(allowed.split())
        else:
            level = len(set(floor_of.values()))
            for name in line.split():
                floor_of[name] = level
    return floor_of, beside


def allowed(source: str, target: str, floor_of, beside) -> bool:
    if source == target:
        return True
    if source in beside:
        return target in beside[source]
    if target in beside:
        return False  # nothing on the floors includes a folder beside them (e.g. the reference)
    return target in floor_of and floor_of[target] < floor_of[source]


def source_files(root: pathlib.Path):
    for top in ("host", "cli"):
        for path in sorted((root / top).rglob("*")):
            if path.suffix in (".hpp", ".cpp", ".h", ".cc"):
                yield path


def folder_of(root: pathlib.Path, path: pathlib.Path) -> str:
    rel = path.relative_to(root).parts
    return rel[1] if rel[0] == "host" else rel[0]  # host/<folder>/…, cli/…


def include_graph(root: pathlib.Path):
    """{folder: {folders it includes}} over host/ and cli/, whatever the document says."""
    graph = {}
    for path in source_files(root):
        source = folder_of(root, path)
        targets = graph.setdefault(source, set())
        for match in INCLUDE.finditer(path.read_text(encoding="utf-8")):
            target = match.group(1)
            if target != source and ((root / "host" / target).is_dir() or target == "cli"):
                targets.add(target)
    return graph


def python_imports(path: pathlib.Path):
    """(line, module) for each import in a Python file, `from a import b` as both a and a.b."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            yield node.lineno, node.module
            for alias in node.names:
                yield node.lineno, f"{node.module}.{alias.name}"


def bench_problems(root: pathlib.Path):
    """bench/'s Python imports against its layers: studies import bench/lib/, never each other; lib never a study."""
    bench = root / "bench"
    studies = {p.stem for p in (bench / "studies").glob("*.py")}
    problems = [f"{p.relative_to(root)}: a Python file directly in bench/; a study goes in bench/studies/, shared "
                "code in bench/lib/" for p in sorted(bench.glob("*.py"))]

    def study_named(module):  # a study imported as its file name (the studies' sys.path) or as studies.NAME
        parts = module.split(".")
        if parts[0] == "studies" and len(parts) > 1:
            return parts[1]
        return parts[0] if parts[0] in studies else None

    for layer in ("studies", "lib"):
        for path in sorted((bench / layer).glob("*.py")):
            for line, module in python_imports(path):
                target = study_named(module)
                if target is None or (layer == "studies" and target == path.stem):
                    continue
                rule = ("a study may not import another study (move the shared code to bench/lib/)"
                        if layer == "studies" else "bench/lib/ may not import a study")
                problems.append(f"{path.relative_to(root)}:{line}: imports the study {target}: {rule}")
    return sorted(set(problems))


def main() -> int:
    args = sys.argv[1:]
    graph_only = "--graph" in args
    args = [a for a in args if a != "--graph"]
    root = pathlib.Path(args[0] if args else pathlib.Path(__file__).resolve().parent.parent)
    if graph_only:
        for folder, targets in sorted(include_graph(root).items()):
            print(f"{folder} -> {' '.join(sorted(targets)) or '(nothing)'}")
        return 0
    floor_of, beside = read_floors(root / "docs" / "ARCHITECTURE.md")
    known = set(floor_of) | set(beside)
    problems = []
    for folder in sorted(p.name for p in (root / "host").iterdir() if p.is_dir()):
        if folder not in known:
            problems.append(f"host/{folder}/: not named in docs/ARCHITECTURE.md's floors")
    for path in source_files(root):
        source = folder_of(root, path)
        text = path.read_text(encoding="utf-8")
        for match in INCLUDE.finditer(text):
            target = match.group(1)
            if target not in known:
                continue  # a system or third-party header written with quotes
            if not allowed(source, target, floor_of, beside):
                line = text.count("\n", 0, match.start()) + 1
                problems.append(f"{path.relative_to(root)}:{line}: {source}/ may not include {target}/ "
                                f"(\"{match.group(0).strip()}\")")
    bench = bench_problems(root) if (root / "bench").is_dir() else []
    for p in problems + bench:
        print(p)
    floors = " < ".join(" ".join(sorted(n for n, f in floor_of.items() if f == level))
                        for level in sorted(set(floor_of.values())))
    print(f"check_layers: {len(problems)} include(s) against the floors {floors}"
          + "".join(f"; {n} beside ({' '.join(sorted(a))})" for n, a in beside.items())
          + f"; {len(bench)} bench import(s) against bench/lib < bench/studies")
    return 1 if problems or bench else 0


if __name__ == "__main__":
    sys.exit(main())
