"""Outputs of any problem's branch (`diskfriction bifurcate --problem`): branch.npz,
collisions.json, special_points.json and the diagram, in the problem's own names and units.

The same files as the disks' (reports/bifurcation.py), with the parameter's name where the
disks have F_x: branch.npz holds the parameter's values under its name, u, eigenvalues,
condition, n_complex, residual, and the strings parameter, units, matrix; collisions.json one record per
collision keyed by the parameter's name (bifurcation.collision_record); special_points.json
the folds, branch points and Hopf points.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.continuation.api import BifurcationProblem, BranchResult
from diskfriction.continuation.detection.bifurcations import SpecialPoint
from diskfriction.files import save_json, save_npz
from diskfriction.models.chain.records import RECORD_KEYS, collision_record, pair_condition
from diskfriction.reports.bifurcation import diagram_axes, draw_spectrum, save_diagram
from diskfriction.reports.figures import relabel

BRANCH_KEYS = ("u", "eigenvalues", "condition", "n_complex", "residual", "parameter", "units",
               "matrix")
"""The arrays of branch.npz besides the parameter's values."""
RESERVED = frozenset(BRANCH_KEYS + RECORD_KEYS + ("value_re", "value_im"))
"""Names a parameter cannot have: they key the other entries of the files."""
FOLD, BRANCH, HOPF = ("s", "k"), ("D", "C2"), ("*", "C0")
"""Marker and colour of a fold, a branch point and a Hopf point on the diagram."""


def parameter_label(spec: BifurcationProblem) -> str:
    """'P [k/l]', or the bare name without units."""
    return f"{spec.parameter} [{spec.units}]" if spec.units else spec.parameter


def special_point_record(point: SpecialPoint, parameter: str) -> dict:
    """A fold, branch point or Hopf point as a JSON object: kind ("fold", "branch", "hopf"),
    the parameter's value, bracket, the value (0 at a fold or branch point, the eigenvalue
    i omega at a Hopf point) and u."""
    return {parameter: float(point.p), "kind": point.kind,
            "bracket": [float(b) for b in point.bracket], "value_re": float(np.real(point.value)),
            "value_im": float(np.imag(point.value)), "u": np.asarray(point.u, dtype=float).tolist()}


def save_outputs(out: Path, result: BranchResult, spec: BifurcationProblem) -> None:
    """DIR/branch.npz, DIR/collisions.json, DIR/special_points.json, each written atomically."""
    b, name = result.branch, spec.parameter
    save_npz(Path(out) / "branch.npz", **{name: b.p}, u=b.u, eigenvalues=b.eigenvalues,
             condition=b.condition, n_complex=b.n_complex, residual=b.residual,
             parameter=np.array(name), units=np.array(spec.units), matrix=np.array(spec.matrix))
    save_json(Path(out) / "collisions.json", collision_json(result, spec))
    save_json(Path(out) / "special_points.json",
              [special_point_record(s, name) for s in special_points(result)])


def collision_json(result: BranchResult, spec: BifurcationProblem) -> list[dict]:
    """collisions.json's records of a problem's run, with the pairs' condition numbers."""
    b = result.branch
    return [collision_record(c, spec.parameter, spec.matrix, None,
                             pair_condition(b.p, b.condition, c, result.collisions))
            for c in result.collisions]


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
