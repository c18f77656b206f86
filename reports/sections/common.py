"""Shared pieces of the sections: figures, Needs used by several sections, Markdown helpers."""
from __future__ import annotations

import dataclasses

import numpy as np

from diskfriction.matrices import Matrix
from diskfriction.reports.registry import Need
from diskfriction.reports.settings import Settings
from diskfriction.scenes import Scene

MATRICES = tuple(Matrix)  # both, in the paper's order: J first


def branch_need(scene: Scene, settings: Settings, matrix: str, label: str | None = None) -> Need:
    return Need(label or f"branch[{matrix}]", "branch", scene,
                {"matrix": matrix, "ds_divisions": settings.ds_divisions})


def computed_branches(ctx) -> list[tuple[str, dict]]:
    """(matrix, its branch result) for each of MATRICES whose branch need was computed."""
    found = [(m, ctx.get(f"branch[{m}]")) for m in MATRICES]
    return [(m, b) for m, b in found if b is not None]


def spectra_need(scene: Scene, settings: Settings, matrix: str, label: str | None = None) -> Need:
    return Need(label or f"spectra_at_loads[{matrix}]", "spectra_at", scene,
                {"matrix": matrix, "loads": list(settings.loads)})


def mode_needs(scene: Scene, settings: Settings) -> list[Need]:
    """Fig. 6's two states: the scene at F_x = mode_F_x, and a uniformly compressed ring at
    F_x = 0 (the scene itself if eps > 0, else the scene with eps = mode_eps)."""
    uniform = scene if scene.eps > 0 else dataclasses.replace(scene, eps=settings.mode_eps)
    return [Need(f"shear_mode[F_x={settings.mode_F_x:g}]", "shear_mode", scene,
                 {"F_x": settings.mode_F_x}),
            Need(f"shear_mode[F_x=0, eps={uniform.eps:g}]", "shear_mode", uniform, {"F_x": 0.0})]


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def failures(ctx) -> str:
    """One line per Need that failed, for the section's text."""
    return "".join(f"\n- `{label}` failed: {message}\n" for label, message in ctx.errors.items())


def fmt(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}g}"


def run_need(scene: Scene, settings: Settings, F_x: float) -> Need:
    """The single run at F_x that Figs. 3, 4, 7 and the paper table share."""
    return Need(f"trajectory[F_x={F_x:g}]", "trajectory", scene,
                {"F_x": F_x, "t_end": settings.t_end, "kick": settings.kick,
                 "seed": settings.seed, "disk": settings.fig4_disk})


def ensemble_need(scene: Scene, settings: Settings, which: str) -> Need:
    """"fronts": Fig. 5's ensemble (ensemble_loads x realizations); "vcm": Fig. 7's, over
    vcm_loads with vcm_realizations."""
    loads, count = ((settings.ensemble_loads, settings.realizations) if which == "fronts"
                    else (settings.vcm_loads, settings.vcm_realizations))
    return Need(f"ensemble[{which}]", "ensemble", scene,
                {"loads": list(loads), "realizations": count, "t_end": settings.ensemble_t_end,
                 "kick": settings.kick, "seed": settings.seed})
