"""Runs from a branch point: simulate(...) -> Trajectory, summarize(...) -> dict.

    system = System.from_scene(scene)
    branch = sweep(system, 0.0, F_x)                # ends exactly at F_x
    traj = simulate(system, branch.q[-1], branch.xi[-1], F_x, t_end=2000.0,
                    perturbation=Perturbation("eigenvector", 1e-6))
    summary = summarize(traj)

Raw units throughout (MODEL.md): time in sqrt(m / k_n ...) units of the scene, not tau.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

import numpy as np

from diskfriction.dynamics.growth import fit_growth, oscillation_period
from diskfriction.dynamics.onset import OnsetParams, sliding_onset
from diskfriction.dynamics.start import Perturbation, Spectrum, perturb, spectrum
from diskfriction.dynamics.stepper import Stepper
from diskfriction.dynamics.trajectory import Trajectory
from diskfriction.symbolic import System

DT_FRACTION = 0.05
"""dt = DT_FRACTION * 2 / omega_max: velocity Verlet is stable for omega dt < 2 and its phase
error per period is (omega dt)^2 / 24; at 0.05 the fastest mode has 3e-4 relative frequency
error and the slow complex pairs far less."""

FRAMES_PER_PERIOD = 20
"""Default recording: this many frames per period of the growing pair (or of the median mode),
enough for the envelope of M (dynamics/growth.py) and the period mean of x (dynamics/onset.py)."""

CHUNK_STEPS = 200_000
"""Steps per call into numba between progress reports."""

Progress = Callable[[float], None]


def choose_dt(spec: Spectrum, fraction: float = DT_FRACTION) -> float:
    """dt = fraction * 2 / omega_max, omega_max^2 = largest |eigenvalue| of M^-1 J [time]."""
    if not 0 < fraction < 1:
        raise ValueError(f"dt fraction must be in (0, 1) (got {fraction})")
    return fraction * 2.0 / spec.omega_max


def simulate(system: System, q: np.ndarray, xi: np.ndarray, F_x: float, t_end: float,
             dt: Optional[float] = None, stride: Optional[int] = None,
             perturbation: Perturbation = Perturbation(), dt_fraction: float = DT_FRACTION,
             onset: OnsetParams = OnsetParams(), progress: Optional[Progress] = None
             ) -> Trajectory:
    """Newton's equations from the equilibrium (q, xi) at load F_x, perturbed, to t_end.

    dt: step [time]; None takes choose_dt(spectrum of M^-1 J at (q, xi), dt_fraction).
    stride: steps between recorded frames; None records FRAMES_PER_PERIOD per oscillation period.
    progress(t) is called between chunks of CHUNK_STEPS steps (never inside the step loop).
    """
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be a positive number (got {t_end})")
    spec = spectrum(system, q, xi)
    dt = choose_dt(spec, dt_fraction) if dt is None else float(dt)
    n_steps = max(1, math.ceil(t_end / dt - 1e-9))
    root = spec.root(0) if spec.pairs.size else 0j
    period = oscillation_period(spec.eigenvalues, root.real)
    stride = stride or max(1, int(period / (FRAMES_PER_PERIOD * dt)))
    q0, v0, xi0 = perturb(system, q, xi, perturbation, spec)
    stepper = Stepper(system, q0, v0, xi0, F_x, dt, stride, n_steps // stride + 1)
    done = 0
    while done < n_steps:
        chunk = min(CHUNK_STEPS, n_steps - done)
        stepper.advance(chunk)
        done += chunk
        if progress is not None:
            progress(stepper.t)
    fr = stepper.frames()
    breach_t = np.where(stepper.breach_t < 0, np.nan, stepper.breach_t)
    onset_t, onset_x = sliding_onset(fr.t, fr.q[:, :system.N], period, onset)
    return Trajectory(fr.t, fr.q, fr.v, fr.energy, fr.slip, breach_t, stepper.breach_x.copy(),
                      onset_t, onset_x, float(F_x), dt, stride, n_steps, system.N,
                      spec.eigenvalues, abs(root.imag), root.real, system.overlaps(q),
                      perturbation)


def summarize(traj: Trajectory, sigma_predicted: Optional[float] = None) -> dict:
    """Plain-type summary of a run (raw units), for JSON:

    slid: some disk's onset of sliding was detected; sigma_measured / sigma_predicted: growth
    rate of the fitted exponential phase of M(t) (M grows at 2 sigma; None if no exponential
    phase was found, fit["reason"] says why) and the largest
    |Im sqrt(lambda)| of M^-1 J at the start (or the value given); fit: its window and quality;
    V_cm: centre-of-mass velocity dC_x/dt fitted over the last half of the run; C_y_range;
    first_breach / onset: per disk {"t": [...], "x": [...]} (None where it never happened);
    M_max; budget_error: max |budget - budget(0)|; W_slip: energy dissipated by sliding.
    """
    fit = fit_growth(traj)
    half = traj.t >= traj.t[-1] / 2
    V_cm = float(np.polyfit(traj.t[half], traj.C_x[half], 1)[0]) if half.sum() > 1 else 0.0

    def listed(a):
        return [None if not np.isfinite(v) else float(v) for v in a]

    sigma_pred = traj.sigma_predicted if sigma_predicted is None else float(sigma_predicted)
    return {
        "F_x": traj.F_x,
        "t_end": float(traj.t[-1]),
        "dt": traj.dt,
        "slid": bool(np.isfinite(traj.onset_t).any()),
        "sigma_measured": fit.as_dict()["sigma"],
        "sigma_predicted": sigma_pred,
        "fit": fit.as_dict(),
        "V_cm": V_cm,
        "C_y_range": float(np.ptp(traj.C_y)),
        "M_max": float(traj.M.max()),
        "first_breach": {"t": listed(traj.breach_t), "x": listed(traj.breach_x)},
        "onset": {"t": listed(traj.onset_t), "x": listed(traj.onset_x)},
        "budget_error": traj.budget_error(),
        "W_slip": float(traj.W_slip[-1]),
        "perturbation": {"kind": traj.perturbation.kind, "amplitude": traj.perturbation.amplitude,
                         "seed": traj.perturbation.seed, "pair": traj.perturbation.pair},
    }
