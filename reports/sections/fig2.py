"""Fig. 2: the spectrum against F_x for J and M^-1 J, complex windows and collisions marked."""
from __future__ import annotations

import numpy as np

from diskfriction.reports.analysis import windows
from diskfriction.reports.bifurcation import draw_spectrum
from diskfriction.reports.registry import Section
from diskfriction.reports.sections.common import MATRICES, branch_need, failures, new_figure, table


def needs(scene, settings):
    return [branch_need(scene, settings, m) for m in MATRICES]


def plot(ctx):
    """Two columns (J, M^-1 J), rows Im and Re; windows with a complex pair shaded, the
    paper's loads dashed."""
    fig, axes = new_figure(2, 2, sharex=True, figsize=(11, 6.5))
    for col, matrix in enumerate(MATRICES):
        b = ctx.get(f"branch[{matrix}]")
        top, bottom = axes[:, col]
        if b is None:
            top.set_title(f"{matrix}: failed")
            continue
        unit = ctx.units.eigenvalue(matrix)
        collisions = list(zip(b["collision_F_x"], b["collision_kind"],
                              b["collision_eigenvalue"] / unit))
        draw_spectrum(top, bottom, b["F_x"], b["eigenvalues"] / unit, b["leg"], collisions, matrix)
        leg = b["leg"] == 1
        for lo, hi in windows(b["F_x"][leg], b["n_complex"][leg]):
            top.axvspan(lo, hi, color="C1", alpha=0.12, lw=0)
        for F in ctx.settings.loads:
            top.axvline(F, color="k", ls=":", lw=0.7)
        top.set_title(f"{matrix}: {int(np.sum(np.array(b['collision_kind']) == 'birth'))} births ^, "
                      f"{int(np.sum(np.array(b['collision_kind']) == 'death'))} deaths v; "
                      f"shaded: a complex pair; dotted: the paper's loads", fontsize=8)
    fig.suptitle(f"Fig. 2, {ctx.scene.name}: spectrum against F_x", fontsize=10)
    fig.tight_layout()
    return fig


def render(ctx):
    text = [ctx.figure(plot(ctx), "fig2", "Fig. 2: Im and Re of every eigenvalue of J (left, "
                       "the paper's matrix) and M^-1 J (right) against F_x, paper units")]
    rows = []
    for matrix in MATRICES:
        b = ctx.get(f"branch[{matrix}]")
        if b is None:
            continue
        unit = ctx.units.eigenvalue(matrix)
        leg = b["leg"] == 1
        win = ", ".join(f"{lo:.4f}-{hi:.4f}" for lo, hi in windows(b["F_x"][leg], b["n_complex"][leg]))
        text.append(f"{matrix}: {b['points']} points, status {', '.join(b['status'])}, "
                    f"{len(b['collision_kind'])} collisions; complex windows (sampled): {win or 'none'}.\n")
        rows += [[matrix, f"{p:.6f}", kind, f"{lam / unit:.5g}", "" if ok else "unresolved"]
                 for p, kind, lam, ok in zip(b["collision_F_x"], b["collision_kind"],
                                              b["collision_eigenvalue"], b["collision_resolved"])]
    if rows:
        text.append("Located collisions (|dF_x| <= 1e-10), the double eigenvalue in paper units:\n")
        text.append(table(["matrix", "F_x", "kind", "lambda", "note"], rows))
    return "\n".join(text) + failures(ctx)


SECTION = Section("fig2", "Fig. 2: spectrum against F_x", needs, render)
