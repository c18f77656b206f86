"""Continuation-derived computations: the branch with its collisions, spectra at given loads,
the pure y shear-wave eigenmode. Raw units in every result (docs/model.md#units)."""
from __future__ import annotations

import numpy as np

from diskfriction.reports.registry import ComputationFailed, computation
from diskfriction.scenes import Scene


def _system(scene: Scene):
    from diskfriction.symbolic import System

    return System.from_scene(scene)


def _sweep(scene: Scene, F_from: float, F_to: float, matrix: str, ds_max=None, detection=True,
           tol_p=None):
    """models.chain.sweep with the report's failures turned into ComputationFailed."""
    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.models.chain.sweep import SweepParams, sweep

    det = DetectionParams(enabled=detection, **({"tol_p": tol_p} if tol_p else {}))
    try:
        return sweep(_system(scene), F_from, F_to, matrix, SweepParams(ds_max=ds_max, detection=det))
    except (ContinuationError, EquilibriumError, np.linalg.LinAlgError) as error:
        raise ComputationFailed(f"sweep {F_from:g} -> {F_to:g} ({matrix}): {error}") from None


def sweep_span(scene: Scene) -> float:
    """The span models.chain.sweep scales its steps with: max(|F_to - F_from|, F_from)."""
    a, b = scene.F_x_range
    return max(abs(b - a), a)


@computation("branch")
def branch(scene: Scene, matrix: str, ds_divisions: int, tol_p: float | None = None) -> dict:
    """The branch over the scene's F_x range with every collision located (models.chain.sweep,
    ds_max = span / ds_divisions). Rows: F_x, tracked eigenvalues of `matrix` [raw], n_complex,
    leg; condition: each tracked eigenvalue's condition number (nan without vectors);
    collisions: F_x, kind, double eigenvalue [raw], resolved; status: how each leg ended, in
    words (Stop.sentence: "reached", or why not)."""
    import time

    t0 = time.perf_counter()
    b = _sweep(scene, *scene.F_x_range, matrix, sweep_span(scene) / ds_divisions, tol_p=tol_p)
    seconds = time.perf_counter() - t0
    return {"F_x": b.F_x, "eigenvalues": b.eigenvalues, "condition": b.condition,
            "n_complex": b.n_complex, "leg": b.leg,
            "residual": b.residual, "x1": b.q[:, 0],
            "collision_F_x": np.array([c.p for c in b.collisions], dtype=float),
            "collision_eigenvalue": np.array([c.eigenvalue for c in b.collisions], dtype=float),
            "collision_kind": [c.kind for c in b.collisions],
            "collision_resolved": [bool(c.resolved) for c in b.collisions],
            "status": [leg.status.sentence(leg.stop - leg.start) for leg in b.of_kind("leg")],
            "points": len(b), "seconds": seconds}


@computation("spectra_at")
def spectra_at(scene: Scene, matrix: str, loads: list[float]) -> dict:
    """Eigenvalues of `matrix` [raw] at exactly each load (one sweep from rest per load), the
    number of complex pairs, the state (q, xi). A load the branch from rest does not reach has
    nan rows and its message in `failed`."""
    from diskfriction.models.chain.equilibrium import NoEquilibrium, equilibrium_at
    from diskfriction.continuation.spectra.tracking import count_complex_pairs

    system = _system(scene)
    n, k = system.ndof, len(loads)
    out = {"loads": np.array(loads, dtype=float), "eigenvalues": np.full((k, n), np.nan + 0j),
           "n_complex": np.full(k, -1), "q": np.full((k, n), np.nan),
           "xi": np.full((k, 2 * scene.N), np.nan), "residual": np.full(k, np.nan), "failed": {}}
    for i, F in enumerate(loads):
        try:
            eq = equilibrium_at(system, F)
        except NoEquilibrium as error:
            out["failed"][repr(F)] = str(error)
            continue
        lam = np.linalg.eigvals(system.stability_matrix(system.jacobian(eq.q, eq.xi), matrix))
        out["eigenvalues"][i], out["q"][i], out["xi"][i] = lam, eq.q, eq.xi
        out["residual"][i] = eq.residual
        out["n_complex"][i] = count_complex_pairs(lam)
    return out


def wave_content(y: np.ndarray) -> tuple[int, float]:
    """(n, purity) of a displacement pattern y_1..y_N on the ring: the dominant discrete
    wavenumber n (k = 2 pi n / L) and the fraction of sum y^2 it carries (Parseval)."""
    N = y.size
    power = np.abs(np.fft.rfft(y)) ** 2
    power[1:(N + 1) // 2] *= 2  # the +n and -n terms; n = 0 and n = N/2 appear once
    n = int(np.argmax(power))
    return n, float(power[n] / power.sum())


@computation("shear_mode")
def shear_mode(scene: Scene, F_x: float) -> dict:
    """The pure y transverse wave among the eigenvectors of J (the paper's Fig. 6).

    At the equilibrium at F_x, every real eigenvector v of J, with its theta components scaled
    by R (so all are lengths) and |v| = 1, is scored by w_y * purity: w_y = sum of v_y^2 (its
    weight on the y dofs) and purity = the fraction of the y pattern carried by one wavenumber
    n != 0 (wave_content; n = 0 is the uniform up-down motion, not a wave). The best one is
    the shear wave: wavelength L / n [length], k = 2 pi n / L, omega = sqrt(eigenvalue of
    M^-1 J whose eigenvector overlaps it most) [1 / time], V2 = omega / k [length / time].
    """
    from diskfriction.models.chain.equilibrium import equilibrium_at

    system = _system(scene)
    N = scene.N
    if not scene.resolved_effects.rotation:
        raise ComputationFailed("the shear mode is defined for rotating disks (3N dofs)")
    eq = equilibrium_at(system, F_x)
    q, xi = eq.q, eq.xi
    J = system.jacobian(q, xi)
    lam, V = np.linalg.eig(J)
    scale = np.r_[np.ones(2 * N), np.full(N, scene.R)]
    best = None
    scores = np.zeros(lam.size)
    for i in np.flatnonzero(np.abs(lam.imag) <= 1e-9 * np.abs(lam).max()):
        v = V[:, i].real * scale
        v /= np.linalg.norm(v)
        w_y = float(np.sum(v[N:2 * N] ** 2))
        n, purity = wave_content(v[N:2 * N])
        scores[i] = w_y * purity if n else 0.0
        if n and (best is None or scores[i] > best[0]):
            best = (scores[i], i, v, w_y, n, purity)
    if best is None:
        raise ComputationFailed(f"no real eigenvector of J carries a wave at F_x = {F_x:g}")
    score, i, v, w_y, n, purity = best
    mu, W = np.linalg.eig(system.stability_matrix(J, "M^-1 J"))
    overlap = np.abs(W.conj().T @ (V[:, i].real / np.linalg.norm(V[:, i].real)))
    overlap /= np.linalg.norm(W, axis=0)
    j = int(np.argmax(overlap))
    omega = float(np.sqrt(mu[j].real)) if mu[j].real > 0 else float("nan")
    wavelength = scene.L / n
    k = 2 * np.pi / wavelength
    if v[N:2 * N][np.argmax(np.abs(v[N:2 * N]))] < 0:
        v = -v  # a sign convention for the plot: the largest y component positive
    return {"F_x": F_x, "vector": v, "lambda_J": float(lam[i].real), "lambda_MJ": float(mu[j].real),
            "overlap_MJ": float(overlap[j]), "omega": omega, "wavelength": wavelength, "k": k,
            "V2": omega / k, "n": n, "w_y": w_y, "purity": purity, "score": float(score),
            "w_x": float(np.sum(v[:N] ** 2)), "w_theta": float(np.sum(v[2 * N:] ** 2)),
            "runner_up": float(np.sort(scores)[-2]) if scores.size > 1 else 0.0,
            "pair_overlaps": system.overlaps(q)[:N]}
