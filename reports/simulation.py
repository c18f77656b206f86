"""Outputs of a run: trajectory.npz, summary.json and run.png in the paper's units.

Paper units (reports/units.py): time in tau, lengths in 2R. Files keep raw units.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.dynamics.trajectory import Trajectory
from diskfriction.files import save_json, save_npz
from diskfriction.reports.figures import (EVENTS, first_event, legend, mark_events, new_figure,
                                          save_figure, slid_word)
from diskfriction.reports.units import TIME_LABEL, PaperUnits
from diskfriction.scenes import Scene


def save_run(out: Path, traj: Trajectory, summary: dict) -> None:
    """DIR/trajectory.npz (t, q, v, energy columns, slip, breach and onset per disk) and
    DIR/summary.json, each written atomically."""
    save_npz(Path(out) / "trajectory.npz", t=traj.t, q=traj.q, v=traj.v, energy=traj.energy,
             energy_columns=np.array(["E_kin", "U_n", "U_load", "W_t", "W_slip"]),
             slip=traj.slip, breach_t=traj.breach_t, breach_x=traj.breach_x,
             onset_t=traj.onset_t, onset_x=traj.onset_x, F_x=np.array(traj.F_x),
             dt=np.array(traj.dt), M=traj.M, C_x=traj.C_x, C_y=traj.C_y)
    save_json(Path(out) / "summary.json", summary)


def plot_run(traj: Trajectory, summary: dict, scene: Scene, path: Path, disk: int = 4) -> None:
    """run.png, paper units (time in tau, lengths in 2R), four panels: M(t) with the growth-rate
    fit (draw_growth); C_x(t); C_y(t); disk `disk`'s spiral in the x-y plane (draw_spiral, the
    paper's Fig. 4). The first breach and first onset of sliding of any disk are vertical lines
    on the time panels, keyed on the C_x panel; the title says the scene, load, perturbation
    and outcome (summary: dynamics.simulate.summarize)."""
    units = PaperUnits.of(scene)
    tau, d = units.time, units.length
    t = traj.t / tau
    fig, ((m_ax, cx_ax), (cy_ax, xy_ax)) = new_figure(2, 2, figsize=(12, 8))
    draw_growth(m_ax, traj.t, traj.M, summary, units)
    events = {event: first_event(summary, event) for event in EVENTS}
    marks = mark_events(cx_ax, events, tau)
    for ax in (m_ax, cy_ax):
        mark_events(ax, events, tau)
    m_ax.set(xlabel=TIME_LABEL, ylabel=r"$M(t)$ [$(2R)^2$]",
             title="mean-square displacement of the disks from their start")
    m_ax.legend(fontsize=7, loc="lower right")
    cx_ax.plot(t, (traj.C_x - traj.C_x[0]) / d, lw=0.8, color="C0")
    cx_ax.set(xlabel=TIME_LABEL, ylabel=r"$C_x - C_x(0)$ [2R]", title="centre of mass along the load")
    if marks:
        legend(cx_ax, marks, fontsize=7, loc="upper left")
    cy_ax.plot(t, (traj.C_y - traj.C_y[0]) / d, lw=0.5, color="C0")
    cy_ax.set(xlabel=TIME_LABEL, ylabel=r"$C_y - C_y(0)$ [2R]", title="centre of mass across the load")
    i = min(disk, scene.N) - 1
    draw_spiral(fig, xy_ax, traj.t, traj.x[:, i] - traj.x[0, i], traj.y[:, i] - traj.y[0, i],
                summary["fit"]["period"], events["first_breach"], units, i + 1)
    p = traj.perturbation
    fig.suptitle(f"{scene.name}: N = {scene.N}, F_x = {traj.F_x:g}, {p.kind} perturbation "
                 f"{p.amplitude:g} (raw), to t = {t[-1]:.4g} tau; slid: {slid_word(summary['slid'])}",
                 fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)


SPIRAL_PERIODS = 20
"""Periods of the growing oscillation drawn before the first breach: enough turns to see the
amplitude grow (by e^(sigma T) per turn), few enough that they stay apart."""


def draw_spiral(fig, ax, t: np.ndarray, dx: np.ndarray, dy: np.ndarray, period: Optional[float],
                breach: Optional[float], units: PaperUnits, disk: int):
    """The paper's Fig. 4 on `ax`: one disk's displacement (dx, dy) from its start [raw length]
    at times t [raw] over the SPIRAL_PERIODS oscillation periods before `breach`, the first
    Coulomb breach of any disk (where the spiral of growing amplitude ends in sliding), as a
    line coloured by time with a colour bar; the breach starred. Without a breach or a period:
    the whole run, and the title says so."""
    end = breach if breach is not None else t[-1]
    if period is not None and np.isfinite(period):
        start, what = max(end - SPIRAL_PERIODS * period, t[0]), f"the {SPIRAL_PERIODS} periods before"
    else:
        start, what = t[0], "from the start to"
    shown = (t >= start) & (t <= end)
    x, y, when = dx[shown] / units.length, dy[shown] / units.length, t[shown] / units.time
    x_power, y_power = (power_of_ten(v) for v in (x, y))
    x, y = x / 10.0**x_power, y / 10.0**y_power
    ax.plot(x, y, lw=0.3, color="0.6", zorder=1)
    points = ax.scatter(x, y, c=when, s=2.0, cmap="viridis", zorder=2)
    fig.colorbar(points, ax=ax, label=TIME_LABEL)
    if breach is not None:
        ax.plot(x[-1], y[-1], "r*", ms=10, zorder=3, label="first Coulomb breach (any disk)")
        ax.legend(fontsize=7, loc="best")
    ax.set(xlabel=rf"$x - x(0)$ [$10^{{{x_power}}}$ 2R]", ylabel=rf"$y - y(0)$ [$10^{{{y_power}}}$ 2R]")
    ax.set_title(f"disk {disk}: its path over {what} "
                 + ("the first breach" if breach is not None else "the end (no breach)"), fontsize=9)
    return points


def draw_growth(ax, t: np.ndarray, M: np.ndarray, summary: dict, units: PaperUnits) -> None:
    """M(t) on a log axis (t, M raw), with the window of the growth-rate fit (summary["fit"]:
    dynamics/growth.py) shaded and the fitted envelope exp(2 sigma t) dashed from its first
    point (the largest M in the window's first period), labelled with sigma measured and
    predicted in 1/tau; without a fit, the legend says why."""
    tau, d = units.time, units.length
    grown = M > 0
    ax.semilogy(t[grown] / tau, M[grown] / d**2, lw=0.6, color="C0", label="M(t)")
    fit = summary["fit"]
    if fit["sigma"] is None:
        ax.plot([], [], " ", label=f"no growth-rate fit: {fit['reason']}")
        return
    first = (t >= fit["t_start"]) & (t <= fit["t_start"] + fit["period"])
    span = np.array([fit["t_start"], fit["t_end"]])
    ax.axvspan(*span / tau, color="C1", alpha=0.2, lw=0,
               label=f"growth-rate fit window ({fit['blocks']} periods)")
    ax.semilogy(span / tau, M[first].max() / d**2 * np.exp(2 * fit["sigma"] * (span - span[0])),
                "k--", lw=1.5, label=rf"$e^{{2\sigma t}}$: $\sigma$ = {fit['sigma'] * tau:.4g} / $\tau$ "
                rf"(predicted {summary['sigma_predicted'] * tau:.4g})")


def power_of_ten(values: np.ndarray) -> int:
    """The power of ten of the largest |value| (0 for none or all zero): the unit an axis of
    these values is labelled in, so that its ticks read 0.5, 1, 2 rather than 0.00005."""
    big = float(np.max(np.abs(values), initial=0.0))
    return int(np.floor(np.log10(big))) if big > 0 else 0
