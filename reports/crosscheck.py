"""The plot of a cross-check against another code (peers/crosscheck.py), in the paper's units."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.units import TIME_LABEL, PaperUnits
from diskfriction.scenes import Scene

FLOOR = 1e-18
"""Deviations below this are drawn at it (exactly equal frames, e.g. t = 0, on a log axis)."""


def plot_deviation(result, scene: Scene, path: Path) -> None:
    """The largest deviation over the disks of x, y (in 2R) and theta (rad) against t (tau),
    log scale."""
    units = PaperUnits.of(scene)
    scale = {"x": units.length, "y": units.length, "theta": 1.0}
    fig, ax = new_figure(figsize=(6.5, 4))
    for name, deviation in result.deviations().items():
        unit = "2R" if name != "theta" else "rad"
        ax.semilogy(result.t / units.time, np.maximum(deviation / scale[name], FLOOR), lw=0.9,
                    label=f"{name} [{unit}]")
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(f"max over disks |ours - LAMMPS| (equal: at {FLOOR:g})")
    ax.set_title(f"{scene.name}: F_x = {result.start.F_x:g} from {result.start.kind}, conventions "
                 f"{scene.effects.conventions}, LAMMPS {result.lammps_version}", fontsize=8)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
