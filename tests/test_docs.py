"""The README and docs/cli.md describe the package as it is: its folders and modules, and every
option each command's ``--help`` shows."""

from __future__ import annotations

import argparse
import re
from dataclasses import fields

import pytest
from conftest import ROOT

import petsc_contact
from petsc_contact.cli.arguments import DEMO, build_parser
from petsc_contact.cli.common import describe
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.options import OPTIONS, SECTIONS, options_of, run_default, with_tables

PACKAGE = ROOT / "petsc_contact"
UNLISTED = {"__init__", "__main__"}  # modules of a folder the layout need not name
OWN = {  # options of a command with a name the table describes for other commands
    "plot": ("output", "sweep"),
    "study": ("quiet",),
    "experiment": ("modulus", "output", "plot", "thickness"),
}


def _layout() -> tuple[dict[str, str], list[str]]:
    """The README's layout block: each package folder's description (continuation lines joined)
    and the top-level paths it names."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("\n## Layout\n", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```\n(.*?)```", section, flags=re.S)
    assert block, "the layout section holds a code block"
    folders: dict[str, str] = {}
    top: list[str] = []
    current = None
    for line in block.group(1).splitlines():
        name, _, text = line.strip().partition(" ")
        if not line.startswith(" "):  # a top-level path
            top.append(name)
            current = None
        elif not line.startswith("   "):  # "  folder/   description": a package folder
            current = name.rstrip("/")
            folders[current] = text.strip()
        else:  # the description of the folder above goes on
            assert current is not None, f"a continuation line under no folder: {line!r}"
            folders[current] += " " + line.strip()
    return folders, top


def _modules_named(description: str) -> list[str]:
    """``prose: module (what it holds), module, more prose: module, ...``: the modules a
    folder's description names (the first word of each comma-separated item, with
    parentheses and the prose before a colon left out)."""
    while re.search(r"\([^()]*\)", description):
        description = re.sub(r"\s*\([^()]*\)", "", description)
    items = [item.rsplit(":", 1)[-1] for item in description.split(",")]
    return [item.split()[0] for item in items if item.strip()]


def test_the_readme_layout_lists_every_folder_and_module():
    """Every folder of the package is in the README's layout, every module named there is in
    its folder, and every module of a folder is named (``__init__`` and ``__main__`` aside)."""
    folders, top = _layout()
    assert top[0] == "petsc_contact/"
    for path in top[1:]:
        assert (ROOT / path).is_dir(), f"the layout names {path}, which is not a folder"
    real = sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py"))
    assert sorted(folders) == real, "the layout's folders are the package's"
    for folder, description in folders.items():
        named = _modules_named(description)
        present = {p.stem for p in (PACKAGE / folder).glob("*.py")} - UNLISTED
        missing = [m for m in named if m not in present]
        assert not missing, f"{folder}/ has no module {missing} (named in the README layout)"
        unnamed = sorted(present - set(named))
        assert not unnamed, f"{folder}/ {unnamed} are not named in the README layout"
        assert len(named) == len(set(named)), f"{folder}/ names a module twice"


def test_the_package_docstring_names_every_folder():
    """The package's docstring names each folder (its layers) in ``double backquotes``."""
    doc = petsc_contact.__doc__ or ""
    for init in PACKAGE.glob("*/__init__.py"):
        assert f"``{init.parent.name}``" in doc, init.parent.name


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_cli_docs_list_every_option_of_every_command():
    """Every long option any command's ``--help`` shows is in docs/cli.md.  The page is
    organised by groups of options shared by several commands (surface, run, plot,
    compare), so an option counts wherever the page names it, as a whole word
    (``--sweep`` is not found in ``--sweep-x``)."""
    doc = (ROOT / "docs" / "cli.md").read_text()
    commands = _commands()
    assert len(commands) >= 10  # the parser's commands were found
    missing = {}
    for name, parser in commands.items():
        options = {s for a in parser._actions for s in a.option_strings if s.startswith("--")}
        absent = [
            o for o in sorted(options) if not re.search(rf"(?<![\w-]){re.escape(o)}(?![\w-])", doc)
        ]
        if absent:
            missing[name] = absent
        assert re.search(rf"^petsc-contact {name}\b", doc, flags=re.M), f"no usage of {name}"
    assert not missing, f"options not in docs/cli.md: {missing}"


def test_cli_docs_option_tables_are_the_option_descriptions():
    """docs/cli.md's option tables are those :data:`OPTIONS` renders (``python -m
    petsc_contact.workflows.options docs/cli.md`` writes them), one per section."""
    doc = (ROOT / "docs" / "cli.md").read_text()
    for section in SECTIONS:
        assert f"<!-- options: {section} -->" in doc, f"docs/cli.md has no {section} table"
    assert with_tables(doc) == doc, (
        "docs/cli.md's option tables differ from OPTIONS: run "
        "python -m petsc_contact.workflows.options docs/cli.md"
    )


def test_every_run_field_is_an_option_and_takes_its_default_from_it():
    """Every field of ``Run`` is described in :data:`OPTIONS` (but the command and PETSc's
    options), spelt as Run.arguments() spells it, and its default is the option's
    (:func:`run_default`): a run's command line that gives a few options describes the Run
    of those fields alone, and the default Run has no argument to give."""
    described = {o.name for o in OPTIONS if o.field}
    assert described == {f.name for f in fields(Run)} - {"geometry", "options"}
    for option in OPTIONS:
        if option.field:
            assert option.flags[0] == "--" + option.name.replace("_", "-"), option
    assert Run().arguments() == ["periodic"]
    surface = {"grid": 8, "hurst": 0.7, "rms_slope": 0.1}
    for command, load in (("periodic", "pressures"), ("punch", "approaches")):
        line = ["--grid", "8", "--hurst", "0.7", "--rms-slope", "0.1", f"--{load}", "0.001"]
        args = build_parser().parse_args([command, *line, "--output", "x.h5"])
        run = Run(geometry=command, **surface, **{load: [1e-3]}, output="x.h5")
        assert describe(args) == run
        assert run.arguments() == [command, *line, "--output", "x.h5"]
    with pytest.raises(ValueError, match="needs one default"):
        run_default("sweep_of_nothing")


def test_each_command_has_the_options_described_for_it():
    """Each command's parser has every option :data:`OPTIONS` gives it, with its flags, its
    default (``demo``: the default scene's) and its help, and no other of the table's
    names."""
    commands = _commands()
    for name, parser in commands.items():
        actions = {a.dest: a for a in parser._actions}
        for option in options_of(name):
            action = actions[option.name]
            assert tuple(action.option_strings) == option.flags, option
            default = DEMO.get(option.name, option.default) if name == "demo" else option.default
            assert action.default == default, (name, option.name)
            help_ = option.help.replace("%", "%%").removesuffix(")")  # the default inside
            assert (action.help or "").startswith(help_), (name, option.name)
        others = {o.name for o in OPTIONS} - {o.name for o in options_of(name)}
        assert not others & {a.dest for a in parser._actions if a.option_strings}.difference(
            OWN.get(name, ())
        ), name


def test_the_punch_has_its_own_stiffness_and_alone_cuts_faces():
    """``punch --stiffness`` is the interfacial stiffness of Eq. 2, not the periodic one, and
    ``--cut-from`` is the punch's alone."""
    commands = _commands()
    stiffness = {name: next(a.help for a in commands[name]._actions if a.dest == "stiffness")
                 for name in ("periodic", "punch")}  # fmt: skip
    assert "Eq. 2" in stiffness["punch"] and "-dp0/du_bar" in stiffness["periodic"]
    with_cut = [n for n, p in commands.items() if any(a.dest == "cut_from" for a in p._actions)]
    assert with_cut == ["punch"]


def test_compare_reads_pressures_and_the_former_pressure_with_a_warning(capsys):
    """``compare --pressures P`` is the pressure; ``--pressure P`` still is, with a warning;
    ``--solvers`` names its default solvers."""
    from petsc_contact.workflows.compare import DEFAULT_SOLVERS

    parser = build_parser()
    line = ["compare", "--grid", "8", "--output", "c.h5"]
    assert parser.parse_args([*line, "--pressures", "1e-3"]).pressure == 1e-3
    assert capsys.readouterr().err == ""
    assert parser.parse_args([*line, "--pressure", "2e-3"]).pressure == 2e-3
    assert "--pressure is deprecated: use --pressures" in capsys.readouterr().err
    solvers = next(o for o in OPTIONS if o.name == "solvers")
    assert ",".join(DEFAULT_SOLVERS) in (solvers.shown_default or "")
