"""Outputs of any problem's branch (`diskfriction bifurcate --problem`): branch.npz,
collisions.json, special_points.json and the diagram, in the problem's own names and units.

The same files as a chain's or a packing's (continuation/records.py), from the run's branch with
the problem's names (problem_branch): branch.npz holds the parameter's values under its name,
u, eigenvalues, condition, n_complex, residual, the special points' locations and the names;
collisions.json one object naming the parameter, with one record per collision;
special_points.json the folds, branch points and Hopf points, the same way.
"""
from __future__ import annotations

from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from diskfriction.continuation.api import BifurcationProblem, BranchResult
from diskfriction.continuation.branch import Branch
from diskfriction.continuation.detection.bifurcations import SpecialPoint
from diskfriction.continuation.records import collision_records, save_branch, save_collisions
from diskfriction.files import save_json
from diskfriction.reports.bifurcation import diagram_axes, draw_spectrum, save_diagram
from diskfriction.reports.figures import relabel

RESERVED = frozenset(f.name for f in fields(Branch)) - {"p"}
"""Names a parameter cannot have: they are the branch's own (and key the other entries of
branch.npz)."""
FOLD, BRANCH, HOPF = ("s", "k"), ("D", "C2"), ("*", "C0")
"""Marker and colour of a fold, a branch point and a Hopf point on the diagram."""
SPECIAL = {"fold": "folds", "branch_point": "branch_points", "hopf": "hopf"}
"""The labels of a problem's special points on its branch (Branch.labelled) and the
BranchResult's field of each."""


def parameter_label(spec: BifurcationProblem) -> str:
    """'P [k/l]', or the bare name without units."""
    return f"{spec.parameter} [{spec.units}]" if spec.units else spec.parameter


def problem_branch(result: BranchResult, spec: BifurcationProblem) -> Branch:
    """The run's branch with the problem's names (parameter, units, matrix, eigenvalue_units)
    and its special points labelled beside its event points: "fold", "branch_point", "hopf"
    (SPECIAL)."""
    return replace(result.branch, parameter=spec.parameter, units=spec.units, matrix=spec.matrix,
                   eigenvalue_units=spec.eigenvalue_units,
                   labelled={**result.branch.labelled,
                             **{label: tuple(getattr(result, name)) for label, name in SPECIAL.items()}})


def special_point_record(point: SpecialPoint) -> dict:
    """A fold, branch point or Hopf point as a JSON object: p, the parameter there; kind
    ("fold", "branch", "hopf"); bracket; value_re, value_im, the eigenvalue that marks it (0 at
    a fold or branch point, i omega at a Hopf point); u, the state there."""
    return {"p": float(point.p), "kind": point.kind,
            "bracket": [float(b) for b in point.bracket], "value_re": float(np.real(point.value)),
            "value_im": float(np.imag(point.value)), "u": np.asarray(point.u, dtype=float).tolist()}


def special_points_json(branch: Branch) -> dict:
    """special_points.json's object: the names (parameter, units, matrix, eigenvalue_units, as
    collisions.json's) and special_points, one record per point (special_point_record) in
    branch order."""
    points = sorted((s for label in SPECIAL for s in branch.labelled.get(label, ())),
                    key=lambda s: s.step)
    return {"parameter": branch.parameter, "units": branch.units, "matrix": str(branch.matrix),
            "eigenvalue_units": branch.eigenvalue_units,
            "special_points": [special_point_record(s) for s in points]}


def save_outputs(out: Path, result: BranchResult, spec: BifurcationProblem) -> None:
    """DIR/branch.npz, DIR/collisions.json, DIR/special_points.json, each written atomically."""
    branch = problem_branch(result, spec)
    save_branch(Path(out) / "branch.npz", branch)
    save_collisions(Path(out) / "collisions.json", branch)
    save_json(Path(out) / "special_points.json", special_points_json(branch))


def collision_json(result: BranchResult, spec: BifurcationProblem) -> list[dict]:
    """collisions.json's records of a problem's run (records.collision_records)."""
    return collision_records(problem_branch(result, spec))


def special_points(result: BranchResult) -> list[SpecialPoint]:
    """The folds, branch points and Hopf points of a run, in branch order."""
    return sorted(result.folds + result.branch_points + result.hopf, key=lambda s: s.step)


def plot_problem_diagram(result: BranchResult, spec: BifurcationProblem, title: str, path: Path) -> None:
    """Im and Re of every eigenvalue of the tracked matrix against the parameter
    (bifurcation.draw_spectrum), with the folds (open squares at Re = 0, where a real
    eigenvalue passes zero), branch points (open diamonds at Re = 0) and Hopf points (stars at
    Re = 0 and at Im = omega) marked and a dotted line at each."""
    from matplotlib.lines import Line2D

    b = result.branch
    fig, top, bottom = diagram_axes()
    handles = draw_spectrum(top, bottom, b.p, b.eigenvalues, np.ones(len(b), int), b.n_complex,
                            [(c.p, c.kind, c.eigenvalue) for c in result.collisions], spec.matrix,
                            x_label=parameter_label(spec), eig_unit=spec.eigenvalue_units)
    relabel(handles[0], f"branch {b.p[0]:.3g} -> {b.p[-1]:.3g}\n(one colour per eigenvalue)")
    for points, (marker, color), what in ((result.folds, FOLD, "fold"),
                                          (result.branch_points, BRANCH, "branch point"),
                                          (result.hopf, HOPF, "Hopf point")):
        for s in points:
            bottom.plot(s.p, 0.0, marker, color=color, ms=7, mfc="none")
            top.axvline(s.p, color=color, ls=":", lw=0.8)
            if s.kind == "hopf":
                top.plot(s.p, abs(np.imag(s.value)), marker, color=color, ms=7, mfc="none")
        if points:
            handles.append(Line2D([], [], ls="", marker=marker, color=color, mfc="none",
                                  label=f"{what} ({len(points)}), dotted line above"))
    save_diagram(fig, top, handles, title, path)
