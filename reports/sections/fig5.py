"""Fig. 5: the forward front of first Coulomb breaches (V1) and the backward front of sliding (V2)."""
from __future__ import annotations

import warnings

import numpy as np

from diskfriction.reports.analysis import PAPER_V1, PAPER_V2
from diskfriction.reports.registry import Section
from diskfriction.reports.figures import new_figure
from diskfriction.reports.sections.common import ensemble_need, failures, table
from diskfriction.reports.sections.runs import NEEDS_ENSEMBLE


def needs(scene, settings):
    return [ensemble_need(scene, settings, "fronts")]


def relative(t: np.ndarray, x: np.ndarray, ref: int) -> tuple[np.ndarray, np.ndarray]:
    """Per disk, the mean over realizations of (t_i - t_ref, x_i - x_ref) [raw], realizations
    where disk `ref` has no event skipped."""
    ok = np.isfinite(t[:, ref])
    dt, dx = t[ok] - t[ok, ref:ref + 1], x[ok] - x[ok, ref:ref + 1]
    with warnings.catch_warnings():  # a disk without events in any realization: nan
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(dt, axis=0), np.nanmean(dx, axis=0)


def estimate(e: dict, unit: float) -> str:
    if e["value"] is None:
        return "n/a"
    err = "" if e["error"] is None else f" +- {e['error'] / unit:.2g}"
    return f"{e['value'] / unit:.3g}{err} (n = {e['n']})"


def render(ctx):
    ens = ctx.get("ensemble[fronts]")
    if ens is None:
        return failures(ctx)
    u, s, N = ctx.units, ctx.settings, ctx.scene.N
    fig, (upper, lower) = new_figure(2, 1, figsize=(7, 7))
    rows = []
    for F in s.ensemble_loads:
        key = repr(float(F))
        if f"first_breach_t@{key}" not in ens:
            continue
        dt, dx = relative(ens[f"first_breach_t@{key}"], ens[f"first_breach_x@{key}"], 0)
        upper.plot(dt / u.time, dx / u.length, "o-", ms=3, label=f"F_x = {F:g}")
        dt2, dx2 = relative(ens[f"onset_t@{key}"], ens[f"onset_x@{key}"], N - 1)
        lower.plot(dt2 / u.time, -dx2 / u.length, "o", ms=3, label=f"F_x = {F:g}")
        paper = PAPER_V1.get(round(F, 6))
        rows.append([f"{F:g}", estimate(ens["V1"][str(float(F))], u.velocity),
                     "-" if paper is None else f"{paper[0]:g} +- {paper[1]:g}"])
    upper.set_xlabel(r"$\tau_i - \tau_1$ [$\tau$] (first breach of disk i after disk 1's)")
    upper.set_ylabel(r"$x_i - x_1$ at the breach [$2R$]")
    lower.set_xlabel(r"$\tau^*_i - \tau^*_N$ [$\tau$] (onset of sliding of disk i after disk N's)")
    lower.set_ylabel(r"$x_N - x_i$ at the onset [$2R$]")
    for ax in (upper, lower):
        ax.legend(fontsize=7)
    upper.set_title(f"Fig. 5, {ctx.scene.name}: means over {s.realizations} realizations per load",
                    fontsize=9)
    fig.tight_layout()
    text = [ctx.figure(fig, "fig5", "Fig. 5: upper, the forward front of first Coulomb breaches "
                       "at the substrate; lower, the backward front of sliding onsets (per disk, "
                       "the mean over realizations)")]
    rows.append(["V2 (all loads)", estimate(ens["V2"], u.velocity), f"{PAPER_V2:g}"])
    text.append(table(["F_x", "ours [2R/tau]", "paper [2R/tau]"], rows))
    text.append(f"Ensemble: studies.ensemble.run_ensemble, {s.realizations} seeded random "
                f"velocity kicks of {s.kick:g} per load, runs to {s.ensemble_t_end:g} raw time; "
                f"V1 and V2 are per-realization slopes (module docstring), averaged "
                f"(standard error of the mean).\n")
    return "\n".join(text) + failures(ctx)


SECTION = Section("fig5", "Fig. 5: breach and sliding fronts", needs, render, NEEDS_ENSEMBLE)
