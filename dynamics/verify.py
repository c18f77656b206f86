"""Which complex pairs make the chain slide: one run in every window of a branch.

The windows are the intervals between consecutive collisions of the branch's stability matrix
(each with a constant number of complex pairs). At each window's midpoint the equilibrium is
reached from rest, perturbed along the largest complex pair of M^-1 J (the matrix of the
dynamics) or, when M^-1 J is all real, by a random velocity kick, and integrated to t_end.
"""
from __future__ import annotations

from typing import Callable, Optional

from diskfriction.continuation.sweep import DiskBranch, sweep
from diskfriction.dynamics.ensemble import equilibrium
from diskfriction.dynamics.simulate import simulate, summarize
from diskfriction.dynamics.start import Perturbation, spectrum
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def windows(branch: DiskBranch) -> list[tuple[float, float, int]]:
    """(F_a, F_b, complex pairs) of the intervals between consecutive collisions."""
    edges = [float(branch.F_x[0])] + [c.p for c in branch.collisions] + [float(branch.F_x[-1])]
    count, out = int(branch.n_complex[0]), []
    for k, (a, b) in enumerate(zip(edges, edges[1:])):
        out.append((a, b, count))
        if k < len(branch.collisions):
            count += 1 if branch.collisions[k].kind == "birth" else -1
    return out


def verify_windows(scene: Scene, matrix: str, t_end: float, amplitude: float,
                   progress: Optional[Callable[[float, float], None]] = None) -> list[dict]:
    """One row per window (raw units): window, complex_pairs, F_x, perturbation,
    sigma_predicted, sigma_measured, M_max, slid, V_cm. progress(fraction, F_x) per run."""
    system = System.from_scene(scene)
    todo = windows(sweep(system, 0.0, scene.F_x_range[1], matrix))
    rows = []
    for k, (a, b, pairs) in enumerate(todo):
        F = 0.5 * (a + b)
        q, xi = equilibrium(scene, F)
        kind = "eigenvector" if spectrum(system, q, xi).pairs.size else "random-velocity"
        s = summarize(simulate(system, q, xi, F, t_end, perturbation=Perturbation(kind, amplitude, k)))
        rows.append({"window": [a, b], "complex_pairs": pairs, "F_x": F, "perturbation": kind,
                     "sigma_predicted": s["sigma_predicted"], "sigma_measured": s["sigma_measured"],
                     "M_max": s["M_max"], "slid": s["slid"], "V_cm": s["V_cm"]})
        if progress is not None:
            progress((k + 1) / len(todo), F)
    return rows
