"""What `diskfriction verify` shows: verify.png, which windows of the bifurcation diagram slide
and the growth rates measured against the spectrum's (rows of studies.verify.window_run), and
verify.md, the table of a chain's windows or of a packing's runs.

Paper units (reports/units.py): eigenvalues of the windows' matrix in its paper unit, growth
rates in 1/tau, F_x as the paper quotes it; the tables in raw units. Plots and tables only: no
physics.
"""
from __future__ import annotations

import collections
import math
from pathlib import Path

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.reports.bifurcation import draw_spectrum
from diskfriction.reports.figures import (OUTCOME_STYLE, legend, new_figure, outcome_patches, slid_word,
                                          save_figure)
from diskfriction.reports.units import F_X_LABEL, PaperUnits
from diskfriction.scenes import Scene

REAL_WINDOW_ALPHA = 0.4
"""Opacity of a window without a complex pair of the windows' matrix, relative to one with."""


def outcome(row: dict) -> bool | None:
    """The run's outcome: True slid, False stayed, None not resolved (slid None)."""
    return None if row["slid"] is None else bool(row["slid"])


def shade_outcomes(ax, rows: list[dict]) -> list:
    """Shade each row's window [F_start, F_stop] by its run's outcome (figures.OUTCOME_STYLE),
    lighter and hatched where the window has no complex pair; returns the patches, in row
    order."""
    patches = []
    for row in rows:
        a, b = row["window"]
        style = OUTCOME_STYLE[outcome(row)]
        real = row["complex_pairs"] == 0
        patches.append(ax.axvspan(min(a, b), max(a, b), facecolor=style["color"],
                                  edgecolor=style["color"] if style["hatch"] is None else "0.3",
                                  alpha=style["alpha"] * (REAL_WINDOW_ALPHA if real else 1.0),
                                  hatch=style["hatch"] or ("//" if real else None), lw=0,
                                  zorder=0))
    return patches


def draw_verify(top, bottom, F_x: np.ndarray, lam: np.ndarray, leg: np.ndarray,
                n_complex: np.ndarray, collisions: list[tuple[float, str, float]],
                rows: list[dict], matrix: str, rate_unit: float) -> list:
    """Top: Im lambda of `matrix` against F_x (bifurcation.draw_spectrum, paper units) with
    each window shaded by its run's outcome; bottom: the growth rate sigma of each run,
    predicted from M^-1 J and measured from M(t) (rows in raw units, divided by rate_unit), at
    the window's midpoint, over the same shading. Returns the legend handles."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = draw_spectrum(top, None, F_x, lam, leg, n_complex, collisions, matrix,
                            x_label="", shade=False)
    for ax in (top, bottom):
        shade_outcomes(ax, rows)
    F = np.array([r["F_x"] for r in rows])
    predicted = np.array([np.nan if r["sigma_predicted"] is None else r["sigma_predicted"]
                          for r in rows]) / rate_unit
    bottom.plot(F, predicted, "k+-", lw=0.6, ms=6, zorder=3)
    for kind in (True, False, None):
        picked = [r for r in rows if outcome(r) is kind and r["sigma_measured"] is not None]
        bottom.plot([r["F_x"] for r in picked], [r["sigma_measured"] / rate_unit for r in picked],
                    "o", ms=5, mfc=OUTCOME_STYLE[kind]["color"], mec="k", mew=0.5, zorder=4)
    bottom.set_xlabel(F_X_LABEL)
    bottom.set_ylabel(r"growth rate $\sigma$ [1/$\tau$]")
    handles += outcome_patches()
    handles += [Patch(facecolor="0.6", edgecolor="0.6", alpha=0.3, hatch="//",
                      label=f"hatched, lighter: no complex pair of {matrix}\nin the window"),
                Line2D([], [], color="k", marker="+", lw=0.6,
                       label=r"$\sigma$ predicted: largest Im$\sqrt{\lambda}$ of M^-1 J"),
                Line2D([], [], ls="", marker="o", mfc="w", mec="k", mew=0.5,
                       label=r"$\sigma$ measured from M(t), coloured by outcome"
                             "\n(none where M did not grow exponentially)")]
    return handles


def plot_verify(branch: Branch, rows: list[dict], scene: Scene, t_end: float,
                path: Path) -> None:
    """verify.png of a `diskfriction verify` run: draw_verify in the paper's units, the legend
    right of the panels, the scene, matrix and run length in the title."""
    units = PaperUnits.of(scene)
    unit = units.eigenvalue(branch.matrix)
    fig, (top, bottom) = new_figure(2, 1, sharex=True, figsize=(11, 7.5))
    handles = draw_verify(top, bottom, branch.F_x, branch.eigenvalues / unit, branch.leg,
                          branch.n_complex,
                          [(c.p, c.kind, c.eigenvalue / unit) for c in branch.collisions],
                          rows, branch.matrix, 1.0 / units.time)
    counts = [sum(outcome(r) is kind for r in rows) for kind in (True, False, None)]
    top.set_title(f"{scene.name}, N = {scene.N}: one run per window of {branch.matrix} to "
                  f"t = {t_end:g} raw ({t_end / units.time:.4g} tau): {counts[0]} slid, "
                  f"{counts[1]} stayed, {counts[2]} not resolved", fontsize=9)
    legend(top, handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.subplots_adjust(left=0.08, right=0.68, bottom=0.08, top=0.95, hspace=0.08)
    save_figure(fig, path)


def verify_table(rows: list[dict], matrix: str) -> str:
    """Markdown table of a chain's verify rows (raw units); slid reads yes, no or not resolved."""
    fmt = lambda v: "-" if v is None else f"{v:.4g}"
    lines = [f"Windows of {matrix}; sigma from M^-1 J (raw 1/time); M in raw length^2.", "",
             "| window F_x | pairs | F_x | sigma predicted | sigma measured | max M | slid |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        a, b = r["window"]
        lines.append(f"| {a:.5f} .. {b:.5f} | {r['complex_pairs']} | {r['F_x']:.5f} | "
                     f"{fmt(r['sigma_predicted'])} | {fmt(r['sigma_measured'])} | {fmt(r['M_max'])} | "
                     f"{slid_word(r['slid'])} |")
    return "\n".join(lines) + "\n"


def packing_verify_table(rows: list[dict]) -> str:
    """Markdown table of a packing's verify runs (raw units)."""
    lines = ["Runs from states of the shear branch; sigma = |Im sqrt(lambda)| of M^-1 J (raw "
             "1/time); distance mass-weighted, raw.", "",
             "| gamma | pairs | perturbation | sigma predicted | sigma measured | distance at "
             "the end | slid | at rest: d sigma_xy / sigma_xy | at rest: largest move [R] | "
             "at rest: contacts opened / formed | outcome |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['gamma']:.6g} | {r['complex_pairs']} | {r['perturbation']} | "
              f"{r['sigma_predicted']:.4g} | {shown(r['sigma_measured'], '.4g')} | {r['distance_end']:.3g} | "
              f"{'yes' if r['slid'] else 'no'} | {shown(r['stress_change_at_rest'], '.2e')} | "
              f"{shown(r['moved_at_rest'], '.2e')} | {opened_formed(r)} | {r['outcome']} |" for r in rows]
    lines.append("")
    for kind, label in (("eigenvector", "complex pairs"), ("random-velocity", "real states")):
        outcomes = collections.Counter(r["outcome"] for r in rows if r["perturbation"] == kind)
        if outcomes:
            lines.append(f"Runs from {label}: " + ", ".join(
                f"{n} {what}" for what, n in sorted(outcomes.items())) + ".")
    return "\n".join(lines) + "\n"


def shown(value, spec: str) -> str:
    """A number of the table in `spec`, '-' for none (None or nan)."""
    return "-" if value is None or math.isnan(value) else format(value, spec)


def opened_formed(row: dict) -> str:
    """'opened / formed' at rest, '-' where the relaxation failed."""
    if row["contacts_opened_at_rest"] is None:
        return "-"
    return f"{row['contacts_opened_at_rest']} / {row['contacts_formed_at_rest']}"
