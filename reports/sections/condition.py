"""Non-normality: the condition number of every complex pair against F_x.

kappa = |l| |r| / |l^H r| of an eigenvalue (tracking.condition_numbers) bounds how far a
perturbation of the matrix moves it, |d lambda| <= kappa |dA|, and the transient growth a
perturbation can show before the eigenvalues take over grows with it (the giant-amplification
literature: Charan, Gendelman, Procaccia, Sheffer, arXiv:2001.06862). It is 1 for a normal
matrix and diverges like |F_x - F_c|^(-1/2) at each collision F_c, where the pair's left and
right vectors become orthogonal.
"""
from __future__ import annotations

import numpy as np

from diskfriction.reports.figures import legend, new_figure
from diskfriction.reports.registry import Section
from diskfriction.reports.sections.common import (MATRICES, branch_need, computed_branches,
                                                  failures, fmt, table)


def needs(scene, settings):
    return [branch_need(scene, settings, m) for m in MATRICES]


def pair_curves(b: dict) -> list[tuple[int, np.ndarray]]:
    """(label, mask of leg-1 points where it is the upper member of a complex pair), for each
    label that ever is one."""
    eig, leg = b["eigenvalues"], b["leg"] == 1
    upper = (eig.imag > 0) & (b["n_complex"][:, None] > 0) & leg[:, None]
    return [(i, upper[:, i]) for i in np.flatnonzero(upper.any(axis=0))]


def plot(ctx):
    """Per matrix: kappa of each complex pair's upper member at the accepted points (one line
    per tracked eigenvalue, log scale), the largest kappa among the real eigenvalues in grey,
    the collisions dotted."""
    from matplotlib.lines import Line2D

    fig, axes = new_figure(1, 2, sharex=True, figsize=(11, 4.2))
    for ax, matrix in zip(np.atleast_1d(axes), MATRICES):
        b = ctx.get(f"branch[{matrix}]")
        if b is None:
            ax.set_title(f"{matrix}: failed")
            continue
        F, kappa, leg = b["F_x"], b["condition"], b["leg"] == 1
        real = np.where(np.abs(b["eigenvalues"].imag) == 0, kappa, np.nan)
        ax.semilogy(F[leg], np.nanmax(np.where(np.isfinite(real), real, 0.0), axis=1)[leg],
                    color="0.6", lw=1.0)
        for k, (label, mask) in enumerate(pair_curves(b)):
            ax.semilogy(F, np.where(mask, kappa[:, label], np.nan), ".-", ms=2.5, lw=1.0,
                        color=f"C{k % 10}")
        for p in b["collision_F_x"]:
            ax.axvline(p, color="k", ls=":", lw=0.5)
        ax.set_xlabel("F_x")
        ax.set_ylabel("condition number |l| |r| / |l^H r|")
        ax.set_title(matrix, fontsize=9)
        legend(ax, [Line2D([], [], color="C0", marker=".", label="a complex pair (upper member)"),
                    Line2D([], [], color="0.6", label="largest among the real eigenvalues"),
                    Line2D([], [], color="k", ls=":", lw=0.5, label="collisions")],
               fontsize=6, loc="upper left")
    fig.suptitle(f"{ctx.scene.name}: non-normality of the tracked matrix against F_x", fontsize=10)
    fig.tight_layout()
    return fig


def render(ctx):
    text = [ctx.figure(plot(ctx), "condition", "Condition numbers of the complex pairs against "
                       "F_x (log scale): how far the matrix is from normal where the pairs live")]
    rows = []
    for matrix, b in computed_branches(ctx):
        kappa, leg = b["condition"], b["leg"] == 1
        for label, mask in pair_curves(b):
            k = int(np.argmax(np.where(mask, kappa[:, label], -np.inf)))
            rows.append([matrix, label, f"{b['F_x'][mask][0]:.6f}", f"{b['F_x'][mask][-1]:.6f}",
                         fmt(float(kappa[k, label])), f"{b['F_x'][k]:.6f}"])
        finite = kappa[leg][np.isfinite(kappa[leg])]
        text.append(f"{matrix}: median condition number over the leg's eigenvalues and points "
                    f"{fmt(float(np.median(finite)) if finite.size else None)}, largest "
                    f"{fmt(float(finite.max()) if finite.size else None)}.\n")
    if rows:
        text.append("Each tracked eigenvalue that is the upper member of a complex pair: where "
                    "it is complex (first and last accepted point) and its largest condition "
                    "number there (at accepted points; it diverges at the collisions that "
                    "bound it):\n")
        text.append(table(["matrix", "label", "first F_x", "last F_x", "largest kappa", "at F_x"],
                          rows))
    return "\n".join(text) + failures(ctx)


SECTION = Section("condition", "Non-normality: condition numbers of the complex pairs", needs,
                  render)
