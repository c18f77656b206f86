"""Paper vs ours: every number docs/model.md#targets lists, ours beside it, the deviation, the reading."""
from __future__ import annotations

import numpy as np

from diskfriction.reports import analysis as A
from diskfriction.reports.figures import first_event, outcome_word
from diskfriction.reports.registry import Section
from diskfriction.reports.sections.common import (branch_need, ensemble_need, failures, fmt, mode_needs,
                                     run_need, spectra_need, table)
from diskfriction.reports.sections.fig6 import mode_numbers
from diskfriction.reports.sections.runs import NEEDS_ENSEMBLE, NEEDS_SIMULATE


def needs(scene, settings):
    out = [branch_need(scene, settings, "J"), spectra_need(scene, settings, "J")]
    out += mode_needs(scene, settings)
    if not NEEDS_SIMULATE():
        loads = dict.fromkeys(tuple(settings.fig3_loads) + (settings.fig4_F_x, settings.fig7_F_x))
        out += [run_need(scene, settings, F) for F in loads]
    if not NEEDS_ENSEMBLE():
        out += [ensemble_need(scene, settings, "fronts"), ensemble_need(scene, settings, "vcm")]
    return out


def ratio(ours, paper) -> str:
    if ours is None or paper in (None, 0) or not np.isfinite(ours):
        return "n/a"
    return f"x{ours / paper:.2f}"


def _fig2_rows(ctx, reading):
    branch = ctx.get("branch[J]")
    spectra = ctx.get("spectra_at_loads[J]")
    return [[f"Fig. 2: {c.name}", c.paper, c.ours, A.mark(c.holds), reading]
            for c in A.fig2_claims(branch, spectra, ctx.units.eig_J)]


def _fig6_rows(ctx):
    rows = []
    for need in mode_needs(ctx.scene, ctx.settings):
        mode = ctx.get(need.label)
        if mode is None:
            continue
        num = mode_numbers(mode, ctx.units)
        reading = f"J eigenvector, {need.label} (Fig. 6 section)"
        rows += [["Fig. 6: omega [1/tau]", f"{A.PAPER_OMEGA:g}", f"{num['omega']:.4f}",
                  ratio(num["omega"], A.PAPER_OMEGA), reading],
                 ["Fig. 6: wavelength [2R]", f"{A.PAPER_WAVELENGTH:g}", f"{num['wavelength']:.3g}",
                  ratio(num["wavelength"], A.PAPER_WAVELENGTH), reading],
                 ["V2 = omega / k [2R/tau]", f"{A.PAPER_V2:g}", f"{num['V2']:.4f}",
                  ratio(num["V2"], A.PAPER_V2), reading]]
    return rows


def _run_rows(ctx):
    u, s = ctx.units, ctx.settings
    if NEEDS_SIMULATE():
        return [["Figs. 3, 4, 7 (single runs)", "", NEEDS_SIMULATE(), "", ""]]
    rows = []
    reading = f"one run, kick {s.kick:g}, seed {s.seed}, t_end {s.t_end:g} raw"

    def run(F):
        return ctx.get(run_need(ctx.scene, s, F).label)

    for F in (0.03, 0.04):
        r = run(F) if F in s.fig3_loads else None
        M = None if r is None else r["summary"]["M_max"] / u.length**2
        rows.append([f"Fig. 3: M saturates at F_x = {F:g} [(2R)^2]", f"~{A.PAPER_M_SATURATION:g}",
                     fmt(M), ratio(M, A.PAPER_M_SATURATION), reading])
    r = run(0.062) if 0.062 in s.fig3_loads else None
    rows.append(["Fig. 3: M minute at 0.062 [(2R)^2]", "minute",
                 "n/a" if r is None else fmt(r["summary"]["M_max"] / u.length**2), "", reading])
    r = run(0.083) if 0.083 in s.fig3_loads else None
    if r is not None:
        breach = first_event(r["summary"], "first_breach")
        M_b = None if breach is None else float(np.interp(breach, r["t"], r["M"])) / u.length**2
        rows.append(["Fig. 3: M at the first breach, 0.083", "~1e-2 R (units as printed)",
                     fmt(M_b) + " (2R)^2", "", reading])
        rows.append(["Fig. 3: then sliding (M linear in t), 0.083", "yes",
                     outcome_word(r["summary"]["slid"]), "", reading])
    r = run(s.fig4_F_x)
    if r is not None:
        d = np.hypot(r["disk_x"] - r["disk_x"][0], r["disk_y"] - r["disk_y"][0]) / u.length
        tenth = max(1, d.size // 10)
        rows.append([f"Fig. 4: disk {s.fig4_disk} spirals out (F_x = {s.fig4_F_x:g})", "yes",
                     f"max |r - r(0)| {d[:tenth].max():.2g} -> {d[-tenth:].max():.2g} (2R)", "",
                     reading])
    r = run(s.fig7_F_x)
    if r is not None:
        rows.append([f"Fig. 7: C_y oscillates without growth (F_x = {s.fig7_F_x:g})", "yes",
                     f"range {r['summary']['C_y_range'] / u.length:.2g} (2R)", "", reading])
    return rows


def _ensemble_rows(ctx):
    u, s = ctx.units, ctx.settings
    if NEEDS_ENSEMBLE():
        return [["Fig. 5, V1/growth, Fig. 7 fit", "", NEEDS_ENSEMBLE(), "", ""]]
    rows = []
    fronts, vcm = ctx.get("ensemble[fronts]"), ctx.get("ensemble[vcm]")
    spectra = ctx.get("spectra_at_loads[J]")
    reading = f"{s.realizations} realizations per load, kick {s.kick:g}"
    ratios = []
    for F, (value, err) in A.PAPER_V1.items():
        e = None if fronts is None else fronts["V1"].get(str(float(F)))
        ours = None if e is None or e["value"] is None else e["value"] / u.velocity
        rows.append([f"Fig. 5: V1 at {F:g} [2R/tau]", f"{value:g} +- {err:g}", fmt(ours),
                     ratio(ours, value), reading])
        i = None if spectra is None else np.flatnonzero(np.isclose(spectra["loads"], F))
        if ours is not None and i is not None and i.size:
            im = A.max_imag(spectra["eigenvalues"][i[0]]) / u.eig_J
            if im > 0:
                ratios.append(ours / im)
    V2 = None if fronts is None or fronts["V2"]["value"] is None else fronts["V2"]["value"] / u.velocity
    rows.append(["Fig. 5: V2 (all loads) [2R/tau]", f"{A.PAPER_V2:g}", fmt(V2), ratio(V2, A.PAPER_V2),
                 reading])
    ours = f"{np.mean(ratios):.2g} +- {np.std(ratios):.2g} ({len(ratios)} loads)" if ratios else "n/a"
    rows.append(["V1 / growth rate", f"{A.PAPER_V1_OVER_GROWTH[0]:g} +- {A.PAPER_V1_OVER_GROWTH[1]:g}",
                 ours, ratio(np.mean(ratios), A.PAPER_V1_OVER_GROWTH[0]) if ratios else "n/a",
                 "V1 [2R/tau] / (max Im lambda of J / k_n) at the same load, as the paper divides"])
    fit = None if vcm is None else vcm["V_cm_fit"]
    for name, part, paper in (("intercept", "intercept", A.PAPER_VCM[0]), ("slope", "slope", A.PAPER_VCM[1])):
        ours = None if fit is None or fit[part]["value"] is None else fit[part]["value"] / u.velocity
        rows.append([f"Fig. 7: V_cm fit {name} [2R/tau]", f"{paper:g}", fmt(ours), ratio(ours, paper),
                     f"{s.vcm_realizations} realizations at F_x = {', '.join(f'{F:g}' for F in s.vcm_loads)}"])
    return rows


def render(ctx):
    reading = (f"J (the paper's matrix), eps = {ctx.scene.eps:g}, spectra at exactly each load; "
               f"Im in k_n (2R)^1/2")
    rows = _fig2_rows(ctx, reading) + _fig6_rows(ctx) + _run_rows(ctx) + _ensemble_rows(ctx)
    return (table(["claim", "paper", "ours", "deviation / holds", "reading"], rows)
            + "\nDeviation: ours / paper for numbers, yes/no for the claims; n/a where the "
              "computation is missing or failed.\n" + failures(ctx))


SECTION = Section("paper", "Paper vs ours", needs, render)
