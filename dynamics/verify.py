"""Which complex pairs make the chain slide: one run in every window of a branch.

The windows are the intervals between consecutive collisions of the branch's stability matrix
(each with a constant number of complex pairs). At each window's midpoint the equilibrium is
reached from rest, perturbed along the largest complex pair of M^-1 J (the matrix of the
dynamics) or, when M^-1 J is all real, by a random velocity kick, and integrated to t_end.
"""
from __future__ import annotations

from typing import Callable, Optional

from diskfriction.continuation.equilibrium import equilibrium_at
from diskfriction.continuation.sweep import DiskBranch, sweep
from diskfriction.continuation.windows import Window, complex_windows
from diskfriction.dynamics.simulate import simulate, summarize
from diskfriction.dynamics.start import Perturbation, spectrum
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def windows(branch: DiskBranch) -> list[Window]:
    """The complex windows of a branch from rest (continuation/windows.py)."""
    return complex_windows(branch.F_x[0], branch.F_x[-1], branch.n_complex[0],
                           [(c.p, c.kind) for c in branch.collisions])


def verify_windows(scene: Scene, matrix: str, t_end: float, amplitude: float,
                   progress: Optional[Callable[[str, Optional[float]], None]] = None) -> list[dict]:
    """One row per window (raw units): window, complex_pairs, F_x, perturbation,
    sigma_predicted, sigma_measured, M_max, slid, V_cm. progress(stage, fraction or None):
    the stage "sweep ...", then "runs" with the fraction of windows done."""
    report = progress or (lambda stage, fraction=None: None)
    system = System.from_scene(scene)
    report(f"sweep F_x 0 -> {scene.F_x_range[1]:g} ({matrix})", None)
    todo = windows(sweep(system, 0.0, scene.F_x_range[1], matrix))
    report(f"one run to t = {t_end:g} in each of {len(todo)} windows", 0.0)
    rows = []
    for k, (a, b, pairs) in enumerate(todo):
        F = 0.5 * (a + b)
        eq = equilibrium_at(system, F)
        kind = "eigenvector" if spectrum(system, eq.q, eq.xi).pairs.size else "random-velocity"
        s = summarize(simulate(system, eq.q, eq.xi, F, t_end,
                               perturbation=Perturbation(kind, amplitude, k)))
        rows.append({"window": [a, b], "complex_pairs": pairs, "F_x": F, "perturbation": kind,
                     "sigma_predicted": s["sigma_predicted"], "sigma_measured": s["sigma_measured"],
                     "M_max": s["M_max"], "slid": s["slid"], "V_cm": s["V_cm"]})
        report(f"one run to t = {t_end:g} in each of {len(todo)} windows", (k + 1) / len(todo))
    return rows
