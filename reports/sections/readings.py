"""Readings: the Fig. 2 claims under the readings docs/model.md#stability calls ambiguous (inertia c, matrix,
pre-compression eps)."""
from __future__ import annotations

import dataclasses

import numpy as np

from diskfriction.reports import analysis as A
from diskfriction.reports.registry import Section
from diskfriction.reports.figures import new_figure
from diskfriction.reports.sections.common import branch_need, failures, spectra_need, table
from diskfriction.reports.units import F_X_LABEL


def readings(scene, settings) -> list[tuple[str, str, object]]:
    """(name, matrix, scene variant): J for each eps (c does not enter J), M^-1 J for each
    c and eps."""
    out = []
    for eps in settings.eps_values:
        out.append((f"J, eps={eps:g}", "J", dataclasses.replace(scene, eps=eps)))
        for c in settings.inertias:
            out.append((f"M^-1 J, c={c:g}, eps={eps:g}", "M^-1 J",
                        dataclasses.replace(scene, eps=eps, inertia=c)))
    return out


def needs(scene, settings):
    out = []
    for name, matrix, variant in readings(scene, settings):
        out += [branch_need(variant, settings, matrix, f"branch[{name}]"),
                spectra_need(variant, settings, matrix, f"spectra[{name}]")]
    return out


def plot(ctx, found):
    """Per eps, the largest Im lambda of each reading against F_x on a log axis (all real: a
    gap), J dashed over the M^-1 J lines (with c = 4 they coincide), the paper's values and
    loads; the legend right of the panels."""
    from matplotlib.lines import Line2D

    eps_values = ctx.settings.eps_values
    fig, axes = new_figure(1, len(eps_values), figsize=(4.2 * len(eps_values) + 2.2, 4),
                           sharey=True, squeeze=False)
    for ax, eps in zip(axes[0], eps_values):
        colors = iter(f"C{k}" for k in range(10) if k != 3)  # red: the paper's values
        for name, matrix, variant, b in (f for f in found if f[2].eps == eps):
            leg = b["leg"] == 1
            im = A.max_imag(b["eigenvalues"][leg]) / ctx.units.eigenvalue(matrix)
            J = matrix == "J"
            ax.plot(b["F_x"][leg], np.where(im > 0, im, np.nan), lw=1.2 if J else 0.9,
                    ls="--" if J else "-", color="k" if J else next(colors), zorder=3 if J else 2,
                    label=name.split(", eps")[0])
        ax.plot(list(A.PAPER_IM), list(A.PAPER_IM.values()), "rx", ms=8, zorder=4, label="paper (J)")
        for F in A.PAPER_COMPLEX_LOADS:
            ax.axvline(F, color="0.4", ls=":", lw=0.9)
        ax.axvline(A.PAPER_REAL_LOAD, color="0.4", ls="-.", lw=0.9)
        ax.set_yscale("log")
        ax.set_title(f"eps = {eps:g}", fontsize=9)
        ax.set_xlabel(F_X_LABEL, fontsize=8)
    axes[0, 0].set_ylabel(r"largest Im $\lambda$ [$k_n (2R)^{1/2}$ for J, $1/\tau^2$ for M^-1 J]",
                          fontsize=8)
    handles, _ = axes[0, -1].get_legend_handles_labels()
    handles += [Line2D([], [], color="0.4", ls=":", lw=0.9, label="paper: complex at these loads"),
                Line2D([], [], color="0.4", ls="-.", lw=0.9, label="paper: all real at this load"),
                Line2D([], [], ls="", label="a gap: all eigenvalues real")]
    axes[0, -1].legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle("Readings: the largest Im lambda against F_x per reading of the model", fontsize=9)
    fig.tight_layout()
    return fig


def render(ctx):
    found, rows = [], []
    for name, matrix, variant in readings(ctx.scene, ctx.settings):
        b, sp = ctx.get(f"branch[{name}]"), ctx.get(f"spectra[{name}]")
        claims = A.fig2_claims(b, sp, ctx.units.eigenvalue(matrix) if sp is not None else 1.0)
        held = sum(c.holds is True for c in claims)
        rows.append([name] + [f"{A.mark(c.holds)} ({c.ours})" for c in claims] + [f"{held}/{len(claims)}"])
        if b is not None:
            found.append((name, matrix, variant, b))
    header = ["reading"] + [c.name for c in A.fig2_claims(None, None, 1.0)] + ["holds"]
    text = []
    if found:
        text.append(ctx.figure(plot(ctx, found), "readings", "Readings: the largest Im lambda of "
                               "each reading against F_x, one panel per eps, the paper's three "
                               "values (J) as red crosses"))
    text.append(table(header, rows))
    text.append("c enters only M^-1 J (I = c m R^2), so J is listed once per eps. eps = 0 starts "
                "the branch at the singular rest state (pairs at delta = 0, N rolling modes), "
                "eps > 0 at a regular one with every pair compressed (docs/chain.md, The "
                "equilibrium branch). "
                "'Second pair' reads: a pair present at 0.083 was born after 0.04 (tracked "
                "eigenvalue followed back to where it was last real). Im claims: within a factor "
                f"{A.FACTOR:g} of the paper's value, in each matrix's paper unit.\n")
    return "\n".join(text) + failures(ctx)


SECTION = Section("readings", "Readings: c, matrix, eps", needs, render)
