"""Counts that show the package's shape: lines by folder, imports inside functions, import
circles between modules, ``Any`` annotations, tests of a device's or a run's name, module
names used twice.

Run from the repository root::

    python benchmarks/architecture.py [PACKAGE_DIR]
"""

from __future__ import annotations

import ast
import re
import sys
from collections import Counter
from pathlib import Path

DEVICE_TEST = re.compile(r"""(device|\.name)\s*[!=]=\s*["']cpu["']|["']cpu["']\s*[!=]=""")


def modules(root: Path) -> dict[str, Path]:
    """Every module of the package under ``root`` by its dotted name."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def imports(name: str, path: Path, known: set[str]) -> tuple[set[str], set[str], int, int]:
    """The package modules ``name`` imports at its top level and inside functions, and the
    count of its imports inside functions (all, and of package modules)."""
    tree = ast.parse(path.read_text())
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    top: set[str] = set()
    nested: set[str] = set()
    inner = inner_own = 0
    for node in ast.walk(tree):
        if not isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        targets = []
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")
                parent = parent[: len(parent) - node.level + 1]
                base = ".".join([*parent, base] if base else parent)
            targets = [
                f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names
            ]
        else:
            targets = [a.name for a in node.names]
        own = [t for t in targets if t in known]
        if node.col_offset > 0 and _type_checking(tree, node):
            continue  # for the type checker alone: no import at run time
        if node.col_offset > 0:
            inner += 1
            inner_own += bool(own)
            nested.update(own)
        else:
            top.update(own)
    return top, nested, inner, inner_own


def _type_checking(tree: ast.AST, node: ast.AST) -> bool:
    return any(
        isinstance(block, ast.If)
        and "TYPE_CHECKING" in ast.unparse(block.test)
        and any(n is node for n in ast.walk(block))
        for block in ast.walk(tree)
    )


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def main(root: Path) -> None:
    mods = modules(root)
    known = set(mods)
    graph: dict[str, set[str]] = {}
    graph_all: dict[str, set[str]] = {}
    inner = inner_own = total_imports = 0
    lines: Counter[str] = Counter()
    anys = device_tests = 0
    for name, path in mods.items():
        top, nested, n_inner, n_own = imports(name, path, known)
        graph[name] = {t for t in top if t != name and not name.startswith(t + ".")}
        graph_all[name] = graph[name] | {
            t for t in nested if t != name and not name.startswith(t + ".")
        }
        text = path.read_text()
        inner += n_inner
        inner_own += n_own
        total_imports += n_own + len(top)
        folder = path.parent.name if path.parent != root else "(root)"
        lines[folder] += text.count("\n")
        anys += len(re.findall(r"\bAny\b", text)) - text.count("import Any")
        device_tests += sum(
            1
            for line in text.splitlines()
            if DEVICE_TEST.search(line) and not line.lstrip().startswith("#")
        )
    names = Counter(p.name for p in mods.values() if p.name != "__init__.py")
    print(f"lines: {sum(lines.values())}")
    for folder, n in sorted(lines.items(), key=lambda kv: -kv[1]):
        print(f"  {folder:14s} {n:6d}")
    print(f"tests of a device's name ('cpu'): {device_tests}")
    print(
        f"imports of package modules inside functions: {inner_own} of {total_imports}"
        f" ({100 * inner_own / max(total_imports, 1):.0f}%); all imports in functions: {inner}"
    )
    found = circles(graph)
    print(f"import circles (top-level imports): {len(found)}")
    for comp in found:
        print("  " + " <-> ".join(comp))
    hidden = circles(graph_all)
    print(f"import circles, imports inside functions counted: {len(hidden)}")
    for comp in hidden:
        print(
            f"  {len(comp)} modules: " + ", ".join(m.removeprefix("petsc_contact.") for m in comp)
        )
    print(f"'Any' in annotations and code: {anys}")
    twice = sorted(n for n, c in names.items() if c > 1)
    print(f"module names used twice: {len(twice)}: {', '.join(twice)}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "petsc_contact").resolve())
