"""The package's house rules, read from its source: the command line only parses, calls and
prints (the files are written by the library), and no function is longer than a screen."""

from __future__ import annotations

import ast

from conftest import ROOT

PACKAGE = ROOT / "petsc_contact"
LONGEST = 60  # lines, from ``def`` to the end of the body, docstring included
WRITERS = {"atomic_h5", "replaced", "storage"}  # io.atomic's: how the library writes files


def _trees(folder: str = "") -> dict[str, ast.Module]:
    """Each module of the package (or of its ``folder``) parsed, by its path in the package."""
    paths = sorted((PACKAGE / folder).rglob("*.py"))
    return {str(p.relative_to(PACKAGE)): ast.parse(p.read_text()) for p in paths}


def _mode(call: ast.Call, position: int) -> str:
    """The mode a call of ``open`` or ``h5py.File`` gives (``"r"`` when it gives none)."""
    given = [k.value for k in call.keywords if k.arg == "mode"]
    if len(call.args) > position:
        given.append(call.args[position])
    if not given:
        return "r"
    return given[0].value if isinstance(given[0], ast.Constant) else "?"


def _writes(tree: ast.Module) -> list[str]:
    """What in a module writes a file: the library's writers imported, ``open`` or
    ``h5py.File`` for writing, a folder made."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found += [a.name for a in node.names if a.name in WRITERS]
        elif isinstance(node, ast.Call):
            name = ast.unparse(node.func)
            if name == "open" and _mode(node, 1) not in ("r", "rb"):
                found.append(f"open(..., {_mode(node, 1)!r})")
            elif name.endswith("h5py.File") and _mode(node, 1) != "r":
                found.append(f"h5py.File(..., {_mode(node, 1)!r})")
            elif name in ("os.makedirs", "os.mkdir"):
                found.append(name)
    return found


def test_the_command_line_writes_no_file_itself():
    """``cli/`` parses, calls the library and prints: the modules under it import none of the
    library's writers and open no file for writing, so that every file a command writes is
    written by the library."""
    trees = _trees("cli")
    assert len(trees) >= 8
    writing = {path: found for path, tree in trees.items() if (found := _writes(tree))}
    assert not writing, f"cli modules that write files: {writing}"


def test_the_command_line_reads_no_results_file():
    """Results files are read by the library too (``paper.redraw``, ``theory_run``):
    no module under ``cli/`` imports h5py."""
    importing = [
        path
        for path, tree in _trees("cli").items()
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        and "h5py" in {a.name for a in node.names} | {getattr(node, "module", None)}
    ]
    assert not importing, f"cli modules that read HDF5 files: {importing}"


def test_the_writes_are_found():
    """The check above finds each kind of write it looks for."""
    source = (
        "from ..io.atomic import atomic_h5\n"
        "open(p, 'w')\nopen(p)\nh5py.File(p, 'a')\nh5py.File(p, mode='r')\nos.makedirs(d)\n"
    )
    assert _writes(ast.parse(source)) == [
        "atomic_h5", "open(..., 'w')", "h5py.File(..., 'a')", "os.makedirs",
    ]  # fmt: skip


def test_no_function_is_longer_than_a_screen():
    """Every function of the package, methods and nested ones included, is at most
    :data:`LONGEST` lines long, its docstring included: a longer one is split into helpers
    with names that say what each part does."""
    long = [
        f"{path}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1} lines)"
        for path, tree in _trees().items()
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and (node.end_lineno or 0) - node.lineno + 1 > LONGEST
    ]
    assert not long, "functions over 60 lines:\n" + "\n".join(long)
