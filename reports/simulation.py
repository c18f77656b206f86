"""Outputs of a run: trajectory.npz, summary.json and a quick plot in the paper's units.

Paper units (reports/units.py): time in tau, lengths in 2R. Files keep raw units.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.dynamics.trajectory import Trajectory
from diskfriction.files import save_json, save_npz, write_atomic
from diskfriction.reports.units import PaperUnits
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


def plot_run(traj: Trajectory, scene: Scene, path: Path, disk: int = 4) -> None:
    """M(t) (log), C_x(t) with C_y inset, and disk `disk`'s x-y trajectory, paper units."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    units = PaperUnits.of(scene)
    tau, d = units.time, units.length
    t = traj.t / tau
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(12, 3.6))
    a.semilogy(t, np.maximum(traj.M / d**2, 1e-30))
    a.set(xlabel=r"$t/\tau$", ylabel=r"$M(t)$ [$(2R)^2$]", title=f"F_x = {traj.F_x:g}")
    b.plot(t, (traj.C_x - traj.C_x[0]) / d)
    b.set(xlabel=r"$t/\tau$", ylabel=r"$C_x - C_x(0)$ [2R]")
    inset = b.inset_axes([0.55, 0.12, 0.4, 0.3])
    inset.plot(t, (traj.C_y - traj.C_y[0]) / d, lw=0.5)
    inset.set_title(r"$C_y - C_y(0)$", fontsize=7)
    inset.tick_params(labelsize=6)
    i = min(disk, scene.N) - 1
    c.plot((traj.x[:, i] - traj.x[0, i]) / d, (traj.y[:, i] - traj.y[0, i]) / d, lw=0.5)
    c.set(xlabel=r"$x - x(0)$ [2R]", ylabel=r"$y - y(0)$ [2R]", title=f"disk {i + 1}")
    for ax, when in ((a, traj.breach_t), (b, traj.onset_t)):
        if np.isfinite(when).any():
            ax.axvline(np.nanmin(when) / tau, color="C3", lw=0.6)
    fig.tight_layout()
    write_atomic(Path(path), lambda tmp: fig.savefig(tmp, dpi=100, format="png"))
    plt.close(fig)
