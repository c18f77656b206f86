"""Figs. 3, 4 and 7: single runs from branch points, and the centre-of-mass velocity."""
from __future__ import annotations

import numpy as np

from diskfriction.reports.compute.runs import missing
from diskfriction.reports.analysis import PAPER_VCM
from diskfriction.reports.figures import EVENTS, first_event, legend, mark_events, new_figure, slid_word
from diskfriction.reports.registry import Section
from diskfriction.reports.simulation import SPIRAL_PERIODS, draw_spiral
from diskfriction.reports.sections.common import ensemble_need, failures, fmt, run_need, table
from diskfriction.reports.units import TIME_LABEL

NEEDS_SIMULATE = lambda: missing("diskfriction.dynamics.simulate")  # noqa: E731
NEEDS_ENSEMBLE = lambda: missing("diskfriction.studies.ensemble")  # noqa: E731


def protocol(ctx) -> str:
    s = ctx.settings
    return (f"Each run starts at the equilibrium on the branch from rest at exactly F_x, with a "
            f"random velocity kick of amplitude {s.kick:g} (raw 2R per raw time; seed {s.seed}) "
            f"and runs to t = {s.t_end:g} raw = {s.t_end / ctx.units.time:.4g} tau "
            f"(dynamics.simulate, default dt). The paper's protocol is in its unavailable "
            f"Supplemental Material.\n")


# ---------------------------------------------------------------- Fig. 3


def fig3_needs(scene, settings):
    return [run_need(scene, settings, F) for F in settings.fig3_loads]


def fig3_render(ctx):
    u = ctx.units
    fig, ax = new_figure(figsize=(7, 4.2))
    rows = []
    for need in fig3_needs(ctx.scene, ctx.settings):
        r = ctx.get(need.label)
        if r is None:
            continue
        F, sm = need.params["F_x"], r["summary"]
        ok = r["t"] > 0
        ax.loglog(r["t"][ok] / u.time, r["M"][ok] / u.length**2, lw=0.7, label=f"F_x = {F:g}")
        breach = first_event(sm, "first_breach")
        rows.append([f"{F:g}", fmt(sm["M_max"] / u.length**2), fmt(r["M"][-1] / u.length**2),
                     "no" if breach is None else fmt(breach / u.time, 4), slid_word(sm["slid"]),
                     fmt(None if sm["sigma_measured"] is None else sm["sigma_measured"] * u.time),
                     fmt(sm["sigma_predicted"] * u.time)])
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(r"$M(t)$ [$(2R)^2$]")
    ax.legend(fontsize=8)
    ax.set_title(f"Fig. 3, {ctx.scene.name}: mean-square displacement", fontsize=9)
    fig.tight_layout()
    text = [ctx.figure(fig, "fig3", "Fig. 3: M(t) = (1/N) sum |r_i(t) - r_i(0)|^2 at the paper's "
                       "loads, log-log"), protocol(ctx)]
    text.append(table(["F_x", "max M [(2R)^2]", "M at the end", "first breach [tau]", "slid",
                       "growth rate, measured [1/tau]", "predicted (M^-1 J) [1/tau]"], rows))
    return "\n".join(text) + failures(ctx)


# ---------------------------------------------------------------- Fig. 4


def fig4_needs(scene, settings):
    return [run_need(scene, settings, settings.fig4_F_x)]


def fig4_render(ctx):
    u, s = ctx.units, ctx.settings
    need = fig4_needs(ctx.scene, s)[0]
    r = ctx.get(need.label)
    if r is None:
        return failures(ctx)
    fig, ax = new_figure(figsize=(6.5, 5))
    sm = r["summary"]
    draw_spiral(fig, ax, r["disk_t"], r["disk_x"] - r["disk_x"][0], r["disk_y"] - r["disk_y"][0],
                sm["fit"]["period"], first_event(sm, "first_breach"), u, s.fig4_disk)
    fig.suptitle(f"Fig. 4, {ctx.scene.name}: disk {s.fig4_disk} at F_x = {s.fig4_F_x:g}", fontsize=10)
    fig.tight_layout()
    return "\n".join([ctx.figure(fig, "fig4", f"Fig. 4: the x-y path of disk {s.fig4_disk}'s centre "
                                 f"over the {SPIRAL_PERIODS} oscillation periods before the first "
                                 f"Coulomb breach of any disk, coloured by time: the spiral of "
                                 f"growing amplitude that ends in the breach"), protocol(ctx)]) + failures(ctx)


# ---------------------------------------------------------------- Fig. 7


def fig7_needs(scene, settings):
    runs = [run_need(scene, settings, F) for F in (settings.fig7_F_x,) + tuple(settings.vcm_loads)]
    unique = list({n.label: n for n in runs}.values())
    return unique + ([] if NEEDS_ENSEMBLE() else [ensemble_need(scene, settings, "vcm")])


def fig7_render(ctx):
    u, s = ctx.units, ctx.settings
    fig, ((cx_ax, cy_ax), (loads_ax, vcm_ax)) = new_figure(2, 2, figsize=(11, 7.5))
    main = ctx.get(run_need(ctx.scene, s, s.fig7_F_x).label)
    text = []
    if main is not None:
        t = main["t"] / u.time
        cx_ax.plot(t, (main["C_x"] - main["C_x"][0]) / u.length, lw=0.8)
        events = {event: first_event(main["summary"], event) for event in EVENTS}
        marks = mark_events(cx_ax, events, u.time)
        mark_events(cy_ax, events, u.time)
        if marks:
            legend(cx_ax, marks, fontsize=7, loc="upper left")
        cy_ax.plot(t, (main["C_y"] - main["C_y"][0]) / u.length, lw=0.4, color="C1")
        text.append(f"At F_x = {s.fig7_F_x:g}: C_y ranges over "
                    f"{main['summary']['C_y_range'] / u.length:.3g} (2R) in the whole run; "
                    f"V_cm over the last half = {main['summary']['V_cm'] / u.velocity:.3g} 2R/tau.\n")
    cx_ax.set(xlabel=TIME_LABEL, ylabel=r"$C_x - C_x(0)$ [$2R$]")
    cx_ax.set_title(f"centre of mass along the load, F_x = {s.fig7_F_x:g}", fontsize=9)
    cy_ax.set(xlabel=TIME_LABEL, ylabel=r"$C_y - C_y(0)$ [$2R$]")
    cy_ax.set_title(f"centre of mass across the load, F_x = {s.fig7_F_x:g}", fontsize=9)
    for F in s.vcm_loads:
        r = ctx.get(run_need(ctx.scene, s, F).label)
        if r is not None:
            loads_ax.plot(r["t"] / u.time, (r["C_x"] - r["C_x"][0]) / u.length, lw=0.7, label=f"{F:g}")
    loads_ax.set(xlabel=TIME_LABEL, ylabel=r"$C_x - C_x(0)$ [$2R$]")
    loads_ax.set_title("centre of mass along the load, one run per F_x", fontsize=9)
    loads_ax.legend(fontsize=7, title="F_x", title_fontsize=7, loc="upper left")
    ens = ctx.get("ensemble[vcm]")
    if ens is not None:
        loads = np.array(s.vcm_loads)
        V = [ens["V_cm"][str(F)] for F in loads]
        vcm_ax.errorbar(loads, [np.nan if e["value"] is None else e["value"] / u.velocity for e in V],
                        yerr=[0.0 if e["error"] is None else e["error"] / u.velocity for e in V],
                        fmt="o", ms=4, capsize=2,
                        label=f"mean of {s.vcm_realizations} runs (standard error)")
        fit = ens["V_cm_fit"]
        if fit is not None:
            a, b = fit["intercept"]["value"] / u.velocity, fit["slope"]["value"] / u.velocity
            vcm_ax.plot(loads, a + b * loads, "-", lw=0.8, label=f"fit {a:.2g} + {b:.2g} F_x")
            text.append(f"Fit over {fit['slope']['n']} loads: V_cm = {a:.3g} + {b:.3g} F_x (2R/tau); "
                        f"paper: -1.3e-5 + 4.5e-4 F_x.\n")
        paper_a, paper_b = PAPER_VCM
        vcm_ax.plot(loads, paper_a + paper_b * loads, "k:", lw=0.8,
                    label=f"paper: {paper_a:.2g} + {paper_b:.2g} F_x")
        vcm_ax.legend(fontsize=7, loc="upper left")
    else:
        vcm_ax.text(0.5, 0.5, "V_cm(F_x): not built", ha="center", transform=vcm_ax.transAxes)
        text.append(f"V_cm(F_x): not built: {NEEDS_ENSEMBLE() or 'the ensemble failed'}.\n")
    vcm_ax.set(xlabel="$F_x$ [raw force]", ylabel=r"$V_{cm}$ [$2R/\tau$]")
    vcm_ax.set_title("centre-of-mass velocity over the last half of each run", fontsize=9)
    fig.suptitle(f"Fig. 7, {ctx.scene.name}: the centre of mass", fontsize=10)
    fig.tight_layout()
    text.insert(0, ctx.figure(fig, "fig7", "Fig. 7: the centre of mass; C_x(t) and C_y(t) at "
                              f"F_x = {s.fig7_F_x:g} with the first breach and onset of sliding, "
                              "C_x(t) for several F_x, and V_cm against F_x with the linear fit "
                              "(the paper's insets as panels of their own)"))
    text.append(protocol(ctx))
    return "\n".join(text) + failures(ctx)


FIG3 = Section("fig3", "Fig. 3: M(t)", fig3_needs, fig3_render, NEEDS_SIMULATE)
FIG4 = Section("fig4", "Fig. 4: a disk spirals out", fig4_needs, fig4_render, NEEDS_SIMULATE)
FIG7 = Section("fig7", "Fig. 7: centre of mass", fig7_needs, fig7_render, NEEDS_SIMULATE)
