"""Accuracy against cost: continuation, Jacobian, dynamics; each plot names its reference."""
from __future__ import annotations

import numpy as np

from diskfriction.reports.compute.runs import missing
from diskfriction.reports.registry import Need, Section
from diskfriction.reports.figures import label_points, new_figure, readable_log_axis
from diskfriction.reports.sections.common import failures, fmt, table


def needs(scene, settings):
    s = settings
    out = [Need("continuation[J]", "continuation_accuracy", scene,
                {"matrix": "J", "divisions": list(s.accuracy_divisions), "tol_ps": list(s.accuracy_tol_p),
                 "reference_divisions": s.reference_divisions, "reference_tol_p": s.reference_tol_p}),
           Need("jacobian", "jacobian_accuracy", scene,
                {"F_x": s.jacobian_F_x, "steps": list(s.jacobian_steps)})]
    if not missing("diskfriction.dynamics.simulate"):
        out.append(Need("dynamics", "dynamics_accuracy", scene,
                        {"F_x": s.dynamics_accuracy_F_x, "fractions": list(s.dt_fractions),
                         "reference_fraction": s.reference_dt_fraction,
                         "t_end": s.dynamics_accuracy_t_end}))
    return out


def _floor(values: np.ndarray) -> np.ndarray:
    """Errors of exactly 0 drawn at 1e-17 on a log axis."""
    return np.where(values > 0, values, 1e-17)


def _continuation(ax, c, s):
    for name, fmt_, marker in (("ds", "span/{:g}", "o-"), ("tol", "tol_p {:g}", "s-")):
        ax.loglog(c[f"{name}_seconds"], _floor(c[f"{name}_error"]), marker, ms=4,
                  label="ds_max = span/d (tol_p default)" if name == "ds"
                  else "bracket tol_p (ds_max default)")
    ax.set_xlabel("wall time of the sweep [s]")
    readable_log_axis(ax.xaxis)
    ax.set_ylabel("max collision-location error [raw force]")
    ax.set_title(f"continuation (J): reference ds = span/{s.reference_divisions}, "
                 f"tol_p = {s.reference_tol_p:g}", fontsize=8)
    ax.legend(fontsize=7)
    for name, fmt_ in (("ds", "span/{:g}"), ("tol", "tol_p {:g}")):
        label_points(ax, c[f"{name}_seconds"], _floor(c[f"{name}_error"]),
                     [fmt_.format(v) for v in c[f"{name}_values"]])


def _jacobian(ax, j):
    for order in (2, 4):
        ax.loglog(j["steps"], _floor(j[f"fd{order}_error"]), "o-", ms=4,
                  label=f"central differences, order {order} "
                        f"({np.median(j[f'fd{order}_seconds']) * 1e3:.2g} ms each)")
    ax.plot([], [], " ", label=f"reference: the generated J ({j['exact_seconds'] * 1e6:.2g} us each)")
    ax.set_xlabel("difference step h [raw length]")
    ax.set_ylabel("row-relative max error")
    ax.set_title("Jacobian: FD of the generated F vs the generated J", fontsize=8)
    ax.legend(fontsize=6)


def _dynamics(ax, d):
    ref = d["reference"]
    sigma_err = np.abs(d["sigma"] - d["sigma_predicted"]) / d["sigma_predicted"]
    ax.loglog(d["seconds"], _floor(sigma_err), "o-", ms=4, label="growth rate vs spectrum (rel.)")
    ax.loglog(d["seconds"], _floor(d["budget_error"]), "s-", ms=4, label="energy-budget drift [raw]")
    if ref["V_cm"]:
        ax.loglog(d["seconds"], _floor(np.abs(d["V_cm"] - ref["V_cm"]) / abs(ref["V_cm"])), "^-",
                  ms=4, label=f"V_cm vs dt fraction {ref['fraction']:g} (rel.)")
    ax.set_xlabel("wall time of the run [s]")
    readable_log_axis(ax.xaxis)
    ax.set_ylabel("error")
    ax.set_title("dynamics: dt = fraction x 2 / omega_max (fraction at each point)", fontsize=8)
    ax.legend(fontsize=6)
    label_points(ax, d["seconds"], _floor(d["budget_error"]), [f"{f:g}" for f in d["fraction"]])


def render(ctx):
    s = ctx.settings
    panels = [(label, draw) for label, draw in (("continuation[J]", lambda ax, r: _continuation(ax, r, s)),
                                                ("jacobian", _jacobian), ("dynamics", _dynamics))
              if ctx.get(label) is not None]
    text = []
    if panels:
        fig, axes = new_figure(1, len(panels), figsize=(4.6 * len(panels), 4.2), squeeze=False)
        fig.tight_layout()  # first, so that the point labels are placed on the final axes
        for ax, (label, draw) in zip(axes[0], panels):
            draw(ax, ctx.get(label))
        fig.tight_layout()
        text.append(ctx.figure(fig, "accuracy", "Accuracy against cost; each panel names its "
                               "reference"))
    c = ctx.get("continuation[J]")
    if c is not None:
        rows = [[f"ds_max = span/{v:g}", fmt(e), f"{t:.2f}", int(n)] for v, e, t, n in
                zip(c["ds_values"], c["ds_error"], c["ds_seconds"], c["ds_collisions"])]
        rows += [[f"tol_p = {v:g}", fmt(e), f"{t:.2f}", int(n)] for v, e, t, n in
                 zip(c["tol_values"], c["tol_error"], c["tol_seconds"], c["tol_collisions"])]
        text.append(f"Continuation (J, the scene's F_x range): error = max over the "
                    f"{c['reference_collisions']} reference collisions of the distance to the "
                    f"nearest located collision of the same kind; reference ds_max = "
                    f"span/{s.reference_divisions}, tol_p = {s.reference_tol_p:g} "
                    f"({c['reference_seconds']:.2f} s).\n")
        text.append(table(["setting", "error [raw force]", "time [s]", "collisions"], rows))
    j = ctx.get("jacobian")
    if j is not None:
        best = {o: int(np.argmin(j[f"fd{o}_error"])) for o in (2, 4)}
        text.append(f"Jacobian at the branch point at F_x = {s.jacobian_F_x:g} (smallest active "
                    f"overlap {j['min_overlap']:.2g}): the generated J costs "
                    f"{j['exact_seconds'] * 1e6:.1f} us; central differences of the generated F "
                    f"(history following q) reach at best {j['fd2_error'][best[2]]:.1e} "
                    f"(h = {j['steps'][best[2]]:g}, order 2) and {j['fd4_error'][best[4]]:.1e} "
                    f"(h = {j['steps'][best[4]]:g}, order 4), at {np.median(j['fd2_seconds']) * 1e3:.1f} "
                    f"and {np.median(j['fd4_seconds']) * 1e3:.1f} ms. Reference: the generated J, "
                    f"itself within 3e-10 of a 50-digit reference (docs/chain.md, What you can "
                    f"rely on; benchmarks/jacobian_accuracy.py). Steps larger than an overlap cross the "
                    f"contact's opening, where F is not smooth.\n")
    d = ctx.get("dynamics")
    if d is not None:
        rows = [[f"{f:g}", f"{dt:.3g}", f"{t:.2f}", fmt(sg), fmt(b), fmt(v)] for f, dt, t, sg, b, v in
                zip(d["fraction"], d["dt"], d["seconds"], d["sigma"], d["budget_error"], d["V_cm"])]
        ref = d["reference"]
        rows.append([f"{ref['fraction']:g} (reference)", f"{ref['dt']:.3g}", f"{ref['seconds']:.2f}",
                     fmt(ref["sigma"]), fmt(ref["budget_error"]), fmt(ref["V_cm"])])
        text.append(f"Dynamics at F_x = {s.dynamics_accuracy_F_x:g}, start: {d['start']}, to "
                    f"t = {s.dynamics_accuracy_t_end:g} raw. Growth rate reference: the "
                    f"spectrum's sigma = {d['sigma_predicted']:.5g} raw; energy: exact "
                    f"conservation of the budget; V_cm: the finest dt. Raw units in this table.\n")
        text.append(table(["dt fraction", "dt [raw]", "time [s]", "sigma [raw]", "budget drift [raw]",
                           "V_cm [raw]"], rows))
    return "\n".join(text) + failures(ctx)


SECTION = Section("accuracy", "Accuracy against cost", needs, render)
