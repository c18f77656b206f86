"""Fig. 2: the spectrum against F_x for J and M^-1 J, complex windows and collisions marked."""
from __future__ import annotations


from diskfriction.models.chain.windows import complex_spans, leg_windows
from diskfriction.reports.bifurcation import draw_spectrum
from diskfriction.reports.figures import legend, new_figure
from diskfriction.reports.registry import Section
from diskfriction.reports.sections.common import (MATRICES, branch_need, computed_branches,
                                                  failures, table)
from diskfriction.words import count


def needs(scene, settings):
    return [branch_need(scene, settings, m) for m in MATRICES]


LEGEND_ROOM = 1.75
"""Height of the Im panels over the extent of their lines: the top part holds the legend."""


def plot(ctx):
    """Two columns (J, M^-1 J), rows Im and Re (reports.bifurcation.draw_spectrum), the
    paper's loads dotted."""
    from matplotlib.lines import Line2D

    fig, axes = new_figure(2, 2, sharex=True, figsize=(11, 7.5))
    for col, matrix in enumerate(MATRICES):
        b = ctx.get(f"branch[{matrix}]")
        top, bottom = axes[:, col]
        if b is None:
            top.set_title(f"{matrix}: failed")
            continue
        unit = ctx.units.eigenvalue(matrix)
        collisions = list(zip(b["collision_F_x"], b["collision_kind"],
                              b["collision_eigenvalue"] / unit))
        handles = draw_spectrum(top, bottom, b["F_x"], b["eigenvalues"] / unit, b["leg"],
                                b["n_complex"], collisions, matrix)
        for F in ctx.settings.loads:
            top.axvline(F, color="k", ls=":", lw=0.7)
        handles.append(Line2D([], [], color="k", ls=":", lw=0.7, label="the paper's loads"))
        top.set_title(matrix, fontsize=9)
        low, high = top.get_ylim()
        top.set_ylim(low, low + LEGEND_ROOM * (high - low))  # the legend above the lines
        legend(top, handles, fontsize=6, loc="upper left", ncol=2, framealpha=0.9)
    fig.suptitle(f"Fig. 2, {ctx.scene.name}: spectrum against F_x", fontsize=10)
    fig.tight_layout()
    return fig


def render(ctx):
    text = [ctx.figure(plot(ctx), "fig2", "Fig. 2: Im and Re of every eigenvalue of J (left, "
                       "the paper's matrix) and M^-1 J (right) against F_x, paper units")]
    rows = []
    for matrix, b in computed_branches(ctx):
        unit = ctx.units.eigenvalue(matrix)
        spans = complex_spans(leg_windows(b["F_x"], b["n_complex"], b["leg"],
                                          zip(b["collision_F_x"], b["collision_kind"])))
        win = ", ".join(f"{lo:.4f}-{hi:.4f}" for lo, hi in spans)
        text.append(f"{matrix}: {b['points']} points, legs: {', '.join(b['status'])}, "
                    f"{count(len(b['collision_kind']), 'collision')}; complex windows: {win or 'none'}.\n")
        rows += [[matrix, f"{p:.6f}", kind, f"{lam / unit:.5g}", "" if ok else "unresolved"]
                 for p, kind, lam, ok in zip(b["collision_F_x"], b["collision_kind"],
                                              b["collision_eigenvalue"], b["collision_resolved"])]
    if rows:
        text.append("Located collisions (|dF_x| <= 1e-10), the double eigenvalue in paper units:\n")
        text.append(table(["matrix", "F_x", "kind", "lambda", "note"], rows))
    return "\n".join(text) + failures(ctx)


SECTION = Section("fig2", "Fig. 2: spectrum against F_x", needs, render)
