"""Which complex pairs make the chain slide: one run in every window of a branch.

The windows are the intervals between consecutive collisions of the branch's stability matrix
(each with a constant number of complex pairs). At each window's midpoint the equilibrium is
reached from rest, perturbed along the largest complex pair of M^-1 J (the matrix of the
dynamics) or, when M^-1 J is all real, by a random velocity kick, and integrated to t_end.
"""
from __future__ import annotations

from typing import Callable, Optional

from diskfriction.models.chain.equilibrium import check_reached, equilibrium_at
from diskfriction.continuation.branch import Branch
from diskfriction.models.chain.sweep import sweep
from diskfriction.models.chain.windows import Window, leg_windows
from diskfriction.dynamics.simulate import inaccuracy, simulate, summarize
from diskfriction.dynamics.start import Perturbation, spectrum
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
from diskfriction.words import count


def windows(branch: Branch) -> list[Window]:
    """The windows of a swept branch's requested leg (models.chain.windows.leg_windows)."""
    return leg_windows(branch.F_x, branch.n_complex, branch.leg, [(c.p, c.kind) for c in branch.collisions])


def window_run(system: System, window: Window, index: int, t_end: float, amplitude: float) -> dict:
    """One run at the midpoint F_x = (start + stop) / 2 of `window` (raw units): from the
    equilibrium there, perturbed along the largest complex pair of M^-1 J (or, if M^-1 J is
    all real, by a random velocity kick seeded with `index`), to t_end. The row: window,
    complex_pairs, F_x, perturbation, sigma_predicted, sigma_measured, M_max, accurate, slid
    (None if the run is not accurate, with its reason), V_cm.
    Raises NoEquilibrium if the branch from rest does not reach F_x."""
    a, b, pairs = window
    F = 0.5 * (a + b)
    eq = equilibrium_at(system, F)
    spec = spectrum(system, eq.q, eq.xi)  # decides the start, and simulate steps with it
    kind = "eigenvector" if spec.pairs.size else "random-velocity"
    s = summarize(simulate(system, eq.q, eq.xi, F, t_end,
                           perturbation=Perturbation(kind, amplitude, index), spec=spec))
    row = {"window": [a, b], "complex_pairs": pairs, "F_x": F, "perturbation": kind,
           "sigma_predicted": s["sigma_predicted"], "sigma_measured": s["sigma_measured"],
           "M_max": s["M_max"], "accurate": s["accurate"], "slid": s["slid"], "V_cm": s["V_cm"]}
    return row if s["accurate"] else row | {"reason": inaccuracy(s)}


def verify_windows(scene: Scene, matrix: str, t_end: float, amplitude: float,
                   progress: Optional[Callable[[str, Optional[float]], None]] = None
                   ) -> tuple[Branch, list[dict]]:
    """The branch whose windows were run (from rest to the scene's F_x range end), and one row
    per window (window_run), in order; raises NoEquilibrium when the branch ends short of the
    range end. progress(stage, fraction or None): the stage "sweep ...", then "runs" with the
    fraction of windows done."""
    report = progress or (lambda stage, fraction=None: None)
    system = System.from_scene(scene)
    report(f"sweep F_x 0 -> {scene.F_x_range[1]:g} ({matrix})", None)
    branch = sweep(system, 0.0, scene.F_x_range[1], matrix)
    check_reached(system, branch, scene.F_x_range[1])  # windows beyond its end were never seen
    todo = windows(branch)
    stage = f"one run to t = {t_end:g} in each of {count(len(todo), 'window')}"
    report(stage, 0.0)
    rows = []
    for k, window in enumerate(todo):
        rows.append(window_run(system, window, k, t_end, amplitude))
        report(stage, (k + 1) / len(todo))
    return branch, rows
