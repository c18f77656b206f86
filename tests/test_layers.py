"""The layers of the tree (docs/architecture.md): a module imports only from its own folder and
the layers below it, never from a layer above or a sibling. Read from the sources with ast, so
an import inside a function counts too."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = [
    {"diskfriction"},            # errors, files, memory, words: what every layer may use
    {"scenes"},
    {"symbolic"},
    {"continuation"},            # the generic core: knows nothing of disks
    {"dynamics"},                # Newtonian dynamics from a state, on a scene's kernels
    {"models"},                  # the geometries (models/chain, models/packing) and their registry
    {"studies", "peers"},        # verify, ensembles, maps; the LAMMPS cross-check
    {"reports"},
    {"cli"},
]
RANK = {folder: k for k, layer in enumerate(LAYERS) for folder in layer}
ENTRY_POINTS = {"diskfriction/__main__.py"}  # `python -m diskfriction` starts the command line
FRONT = re.compile(r"^models/\w+/commands(_\w+)?\.py$")
"""A geometry's front (models/<geometry>/commands.py: what the commands do for its scenes, and
the commands_*.py it is split into) is part of the command line's layer, though it lives in its
model's folder."""


def imported_names(nodes) -> set[str]:
    """The diskfriction.* modules the import statements among `nodes` name (absolute imports;
    a relative import stays in its own folder)."""
    found = set()
    for node in nodes:
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else []
        found |= {name for name in names if name.split(".")[0] == "diskfriction"}
    return found


def folder_of(name: str) -> str:
    """The folder (layer) of a diskfriction.* module name ("diskfriction" for the bottom
    modules; "cli" for a geometry's front)."""
    parts = name.split(".")
    if FRONT.match("/".join(parts[1:]) + ".py"):
        return "cli"
    return parts[1] if len(parts) > 1 and parts[1] in RANK else "diskfriction"


def modules_of(folder: str) -> list[Path]:
    """The sources of a layer's folder (a geometry's front counts as the command line's)."""
    paths = sorted(ROOT.glob("models/*/commands*.py")) if folder == "cli" else []
    return paths + [p for p in sorted((ROOT / folder).rglob("*.py"))
                    if not FRONT.match(p.relative_to(ROOT).as_posix())]


def imported_folders(path: Path) -> set[str]:
    """The diskfriction.<folder> names a module imports, inside functions too."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {folder_of(name) for name in imported_names(ast.walk(tree))}


def violations() -> list[str]:
    """'module -> folder' for every import of a layer above the module's or of a sibling."""
    found = []
    for folder, rank in RANK.items():
        for path in modules_of(folder):
            name = path.relative_to(ROOT).as_posix()
            if name in ENTRY_POINTS:
                continue
            for other in imported_folders(path) - {folder}:
                if RANK[other] >= rank:
                    found.append(f"{name} -> diskfriction.{other}")
    return found


def test_no_module_imports_a_layer_above_it_or_a_sibling():
    assert violations() == []


def test_every_installed_folder_has_a_layer():
    """A new top-level package must be placed in LAYERS (and in docs/architecture.md)."""
    folders = {p.parent.name for p in ROOT.glob("*/__init__.py")} - {"tests", "benchmarks", "examples"}
    assert folders <= set(RANK), folders - set(RANK)


def test_the_rule_catches_an_upward_import(tmp_path, monkeypatch):
    """The check reads what it should: an import of the studies from the core is caught."""
    core = tmp_path / "continuation"
    core.mkdir()
    (core / "x.py").write_text("def f():\n    from diskfriction.studies.maps import grid_values\n")
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    assert violations() == ["continuation/x.py -> diskfriction.studies"]


def imported_closure(folder: str) -> set[str]:
    """The folders `folder`'s modules import, directly or through the folders they import."""
    seen, todo = set(), [folder]
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        for path in modules_of(current):
            if path.relative_to(ROOT).as_posix() not in ENTRY_POINTS:
                todo += imported_folders(path) - seen
    return seen


def test_the_code_version_of_resumable_runs_covers_every_folder_they_run():
    """A map cell or ensemble realization on disk is reused while the code version
    (studies.cluster.code_version) is the same: it must digest every folder the studies'
    code reaches, or an edit of that folder (models/packing/shear.py, say) would leave stale cells
    that a rerun takes as current."""
    from diskfriction.studies.cluster import RUN_SOURCES

    reached = {"diskfriction" if f == "diskfriction" else f"diskfriction.{f}"
               for f in imported_closure("studies")}
    assert reached <= set(RUN_SOURCES), reached - set(RUN_SOURCES)


@pytest.mark.slow
def test_the_code_version_of_cached_report_results_covers_every_folder_they_run():
    """A report computation's cached result is reused while its code version is the same
    (reports/registry.py): its depends must hold every folder it reaches (its own imports, its
    module's, and those of the computations' modules it imports), or an edit there (the
    chain's sweep in models/chain/, say) would leave a stale result that the report shows."""
    import inspect
    import textwrap

    from diskfriction.reports.compute import COMPUTATIONS

    for each in COMPUTATIONS.values():
        module = inspect.getmodule(each.function)
        names = imported_names(ast.parse(Path(module.__file__).read_text(encoding="utf-8")).body)
        names |= imported_names(ast.walk(ast.parse(textwrap.dedent(inspect.getsource(each.function)))))
        folders = {folder_of(name) for name in names}
        for name in names:
            if name.startswith("diskfriction.reports.compute."):
                path = name.removeprefix("diskfriction.").replace(".", "/") + ".py"
                folders |= imported_folders(ROOT / path)
        reached = set().union(*(imported_closure(f) for f in folders - {"reports"}))
        wanted = {"diskfriction" if f == "diskfriction" else f"diskfriction.{f}" for f in reached}
        assert wanted <= set(each.depends), (each.name, wanted - set(each.depends))


def test_a_geometry_front_counts_as_the_command_line(tmp_path, monkeypatch):
    """models/<geometry>/commands.py sits on the command line's layer: it may import cli/, and
    a study importing it is caught as an upward import."""
    front = tmp_path / "models" / "shape"
    front.mkdir(parents=True)
    (front / "commands.py").write_text("from diskfriction.cli.common import CommandError\n")
    (front / "model.py").write_text("from diskfriction.continuation import Options\n")
    studies = tmp_path / "studies"
    studies.mkdir()
    (studies / "x.py").write_text("from diskfriction.models.shape.commands import prepare\n")
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    assert violations() == ["studies/x.py -> diskfriction.cli"]
