"""Runs from a branch point: simulate(...) -> Trajectory, summarize(...) -> dict.

    system = System.from_scene(scene)
    eq = equilibrium_at(system, F_x)                # models.chain.equilibrium: exactly at F_x
    traj = simulate(system, eq.q, eq.xi, F_x, t_end=2000.0,
                    perturbation=Perturbation("eigenvector", 1e-6))
    summary = summarize(traj)

Raw units throughout (docs/model.md#units): time in sqrt(m / k_n ...) units of the scene, not tau.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from diskfriction.dynamics.growth import fit_growth, oscillation_period
from diskfriction.dynamics.onset import OnsetParams, sliding_onset
from diskfriction.dynamics.start import Perturbation, Spectrum, perturb, spectrum
from diskfriction.dynamics.stepper import Stepper
from diskfriction.dynamics.trajectory import BUDGET_BOUND, Trajectory
from diskfriction.memory import require_memory
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

DT_FRACTION = 0.05
"""dt = DT_FRACTION * 2 / omega_max: velocity Verlet is stable for omega dt < 2 and its phase
error per period is (omega dt)^2 / 24; at 0.05 the fastest mode has 3e-4 relative frequency
error and the slow complex pairs far less."""

FRAMES_PER_PERIOD = 20
"""Default recording: this many frames per period of the growing pair (or of the median mode),
enough for the envelope of M (dynamics/growth.py) and the period mean of x (dynamics/onset.py)."""

SECONDS_PER_DISK_STEP = 3.5e-8
"""The stepper's cost, 0.032-0.036 us per disk and step at N = 10 .. 10 000 on one core
(benchmarks/dynamics_speed.py): what RunPlan.seconds and run_seconds estimate a run with."""
SECONDS_PER_FRAME = 3.8e-6
"""Summary, trajectory.npz and run.png per recorded frame at N = 10: 1.7, 1.9 and 1.7 s, 5.3 s
in all, for the 1.4e6 frames of a run to t = 40000 at F_x = 0.09 (2 busy cores;
docs/notes/chain-dynamics.md, "Cost")."""
OMEGA_MAX_OVER_Y = 1.7
"""omega_max of M^-1 J over the substrate's y-mode sqrt(3/2 k_n delta_w^(1/2) / m), which sets
a run's step: 17.8 against 10.5 on the paper's branch at N = 10 .. 100."""

CHUNK_STEPS = 200_000
"""Steps per call into numba between progress reports."""

Progress = Callable[[float], None]


def choose_dt(spec: Spectrum, fraction: float = DT_FRACTION) -> float:
    """dt = fraction * 2 / omega_max, omega_max^2 = largest |eigenvalue| of M^-1 J [time]."""
    if not 0 < fraction < 1:
        raise ValueError(f"dt fraction must be in (0, 1) (got {fraction})")
    return fraction * stability_limit(spec)


def stability_limit(spec: Spectrum) -> float:
    """2 / omega_max [time]: velocity Verlet amplifies a mode of frequency omega once
    omega dt >= 2, so no step at or beyond this limit can resolve the start state's spectrum."""
    return 2.0 / spec.omega_max


class UnstableStep(ValueError):
    """A time step at or beyond the stability limit 2 / omega_max of the start state."""

    def __init__(self, dt: float, spec: Spectrum):
        super().__init__(
            f"dt = {dt:.6g} is not below velocity Verlet's stability limit 2 / omega_max = "
            f"{stability_limit(spec):.6g} at the start (omega_max = {spec.omega_max:.6g}, the "
            f"fastest mode of M^-1 J): the run would blow up; the default dt is "
            f"{choose_dt(spec):.4g}")
        self.dt = dt


@dataclass(frozen=True)
class RunPlan:
    """Steps and recording of a run to t_end: n_steps steps of dt [time] end exactly at t_end;
    a frame every `stride` steps; period [time] of the growing pair (or the median mode)."""

    dt: float
    n_steps: int
    stride: int
    period: float

    @property
    def frames(self) -> int:
        return self.n_steps // self.stride + 1

    def seconds(self, N: int) -> float:
        """Estimated wall time of the steps and of what `simulate` does with the frames [s]
        (SECONDS_PER_DISK_STEP, SECONDS_PER_FRAME)."""
        return SECONDS_PER_DISK_STEP * self.n_steps * N + SECONDS_PER_FRAME * self.frames

    def frame_bytes(self, ndof: int, N: int) -> float:
        """Memory of the recorded frames: t, q, v, 5 energy columns, N slips [bytes]."""
        return 8.0 * self.frames * (1 + 2 * ndof + 5 + N)


def run_seconds(scene: Scene, t_end: float) -> float:
    """Rough wall time of the steps of a run to t_end [time] on `scene` [s], before its start's
    spectrum is known: dt = DT_FRACTION 2 / omega_max with omega_max = OMEGA_MAX_OVER_Y
    sqrt(kappa_w0 / m) (kappa_w0 the substrate's normal stiffness at rest, Scene.kappa_w0;
    Hertz: 3/2 k_n delta_w0^(1/2)), and SECONDS_PER_DISK_STEP per disk and step."""
    omega_max = OMEGA_MAX_OVER_Y * math.sqrt(scene.kappa_w0 / scene.m)
    return SECONDS_PER_DISK_STEP * scene.N * t_end * omega_max / (2 * DT_FRACTION)


def whole_strides(t_end: float, dt_max: float, stride: int) -> int:
    """The fewest steps of equal length t_end / n <= dt_max, n a whole number of strides
    (>= 1): the run ends exactly at t_end, on a recorded frame."""
    return stride * max(1, math.ceil(t_end / (stride * dt_max) - 1e-9))


def plan_run(spec: Spectrum, t_end: float, dt: Optional[float] = None,
             stride: Optional[int] = None, dt_fraction: float = DT_FRACTION) -> RunPlan:
    """The steps of a run to t_end. dt is an upper bound (None: choose_dt(spec, dt_fraction)):
    the run takes n_steps equal steps of t_end / n_steps, n_steps the smallest multiple of the
    stride with t_end / n_steps <= dt, so that no step passes t_end, the last one ends on it and
    the last frame is the end state. stride None: FRAMES_PER_PERIOD frames per period.
    Raises UnstableStep if the step is not below stability_limit(spec)."""
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be a positive number (got {t_end})")
    dt_max = choose_dt(spec, dt_fraction) if dt is None else float(dt)
    if not (np.isfinite(dt_max) and dt_max > 0):
        raise ValueError(f"dt must be a positive number (got {dt_max})")
    period = oscillation_period(spec.eigenvalues, spec.leading_root.real)
    stride = stride or max(1, int(period / (FRAMES_PER_PERIOD * dt_max)))
    n_steps = whole_strides(t_end, dt_max, stride)
    plan = RunPlan(t_end / n_steps, n_steps, stride, period)
    if plan.dt >= stability_limit(spec):
        raise UnstableStep(plan.dt, spec)
    return plan


def simulate(system: System, q: np.ndarray, xi: np.ndarray, F_x: float, t_end: float,
             dt: Optional[float] = None, stride: Optional[int] = None,
             perturbation: Perturbation = Perturbation(), dt_fraction: float = DT_FRACTION,
             onset: OnsetParams = OnsetParams(), progress: Optional[Progress] = None,
             spec: Optional[Spectrum] = None) -> Trajectory:
    """Newton's equations from the equilibrium (q, xi) at load F_x, perturbed, to t_end.

    dt: largest step [time] (plan_run: the steps end exactly at t_end); None takes
    choose_dt(spectrum of M^-1 J at (q, xi), dt_fraction); one not below the stability limit
    2 / omega_max raises UnstableStep. stride: steps between recorded frames; None records
    FRAMES_PER_PERIOD per oscillation period. Raises NotEnoughMemory
    (diskfriction.memory) before anything is allocated when the frames would not fit.
    progress(t) is called between chunks of CHUNK_STEPS steps (never inside the step loop).
    spec: the spectrum of M^-1 J at (q, xi) if the caller has it (start.spectrum).
    """
    spec = spec or spectrum(system, q, xi)
    plan = plan_run(spec, t_end, dt, stride, dt_fraction)
    require_memory(plan.frame_bytes(system.ndof, system.N),
                   f"recording {plan.frames} frames of a run to t_end = {t_end:g}")
    q0, v0, xi0 = perturb(system, q, xi, perturbation, spec)
    stepper = Stepper(system, q0, v0, xi0, F_x, plan.dt, plan.stride, plan.frames)
    done = 0
    while done < plan.n_steps:
        chunk = min(CHUNK_STEPS, plan.n_steps - done)
        stepper.advance(chunk)
        done += chunk
        if progress is not None:
            progress(stepper.t)
    fr = stepper.frames()
    breach_t = np.where(stepper.breach_t < 0, np.nan, stepper.breach_t)
    onset_t, onset_x = sliding_onset(fr.t, fr.q[:, :system.N], plan.period, onset)
    root = spec.leading_root
    return Trajectory(fr.t, fr.q, fr.v, fr.energy, fr.slip, breach_t, stepper.breach_x.copy(),
                      onset_t, onset_x, float(F_x), plan.dt, plan.stride, plan.n_steps, system.N,
                      spec.eigenvalues, abs(root.imag), root.real, system.overlaps(q),
                      perturbation)


def summarize(traj: Trajectory, sigma_predicted: Optional[float] = None) -> dict:
    """Plain-type summary of a run (raw units), for JSON:

    t_end: the time the run ended (its last step and last frame); accurate: the energy budget
    closes within budget_bound of the energy exchanged (dynamics/trajectory.py; budget_error,
    energy_exchanged, budget_relative); slid: some disk's onset of sliding was detected, None
    when the run is not accurate (its dynamics are not resolved, so neither is the answer);
    sigma_measured / sigma_predicted: growth rate of the fitted exponential phase of M(t) (M
    grows at 2 sigma; None if no exponential phase was found, fit["reason"] says why) and the
    largest |Im sqrt(lambda)| of M^-1 J at the start (or the value given); fit: its window and
    quality; V_cm: centre-of-mass velocity dC_x/dt fitted over the last half of the run;
    C_y_range; first_breach / onset: per disk {"t": [...], "x": [...]} (None where it never
    happened); M_max; W_slip: energy dissipated by sliding.
    """
    fit = fit_growth(traj)
    half = traj.t >= traj.t[-1] / 2
    fitted = half.sum() > 1 and np.isfinite(traj.C_x[half]).all()
    V_cm = float(np.polyfit(traj.t[half], traj.C_x[half], 1)[0]) if fitted else float("nan")

    def listed(a):
        return [finite(v) for v in a]

    sigma_pred = traj.sigma_predicted if sigma_predicted is None else float(sigma_predicted)
    accurate = traj.accurate
    return {
        "F_x": traj.F_x,
        "t_end": traj.steps * traj.dt,
        "dt": traj.dt,
        "accurate": accurate,
        "slid": bool(np.isfinite(traj.onset_t).any()) if accurate else None,
        "sigma_measured": fit.as_dict()["sigma"],
        "sigma_predicted": sigma_pred,
        "fit": fit.as_dict(),
        "V_cm": finite(V_cm),
        "C_y_range": finite(float(np.ptp(traj.C_y))),
        "M_max": finite(float(traj.M.max())),
        "first_breach": {"t": listed(traj.breach_t), "x": listed(traj.breach_x)},
        "onset": {"t": listed(traj.onset_t), "x": listed(traj.onset_x)},
        "budget_error": finite(traj.budget_error()),
        "energy_exchanged": finite(traj.energy_exchanged()),
        "budget_relative": finite(traj.budget_relative()),
        "budget_bound": BUDGET_BOUND,
        "W_slip": finite(float(traj.W_slip[-1])),
        "perturbation": {"kind": traj.perturbation.kind, "amplitude": traj.perturbation.amplitude,
                         "seed": traj.perturbation.seed, "pair": traj.perturbation.pair},
    }


def finite(value: float) -> Optional[float]:
    """value as a float, None if it is not finite (JSON has no inf or nan)."""
    return float(value) if np.isfinite(value) else None


def inaccuracy(summary: dict) -> str:
    """Why a run's results are not reported (summary["accurate"] false), in one line."""
    if summary["budget_relative"] is None:
        return (f"the energy budget overflowed: dt = {summary['dt']:.4g} does not resolve the run")
    return (f"the energy budget error {summary['budget_error']:.3g} is "
            f"{summary['budget_relative']:.2g} of the energy exchanged "
            f"({summary['energy_exchanged']:.3g}), beyond the bound {summary['budget_bound']:g}: "
            f"dt = {summary['dt']:.4g} does not resolve the run")
