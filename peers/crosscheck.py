"""Both codes from one state: our dynamics and LAMMPS's on the same exported scene.

    start = start_state(system, F_x, "rest")                # peers/lammps_deck.py
    steps = Steps.plan(t_end, default_dt(system, start))
    result = crosscheck(system, start, steps, find_lammps(), workdir)

Our stepper (dynamics.Stepper) and LAMMPS (the deck of peers/lammps_deck.py, written to
`workdir` and run there) start from the same positions, at rest, with zero histories, under
the same loads, and take the same steps of dt. Every `every` steps both record every disk;
the deviation at a frame is the largest |ours - LAMMPS| over the disks, for x, y and theta
(theta rebuilt from LAMMPS's omega_z and tq_z, peers/lammps_run.py). They agree to rounding
only where they model the same physics: the linear Mindlin law and the scene's
conventions = "lammps" (docs/physics.md); with "model" they part by the lever arm's
O(delta / 2R) (lever_arm_band).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.dynamics.simulate import (SECONDS_PER_DISK_STEP, UnstableStep, choose_dt,
                                            stability_limit, whole_strides)
from diskfriction.dynamics.start import spectrum
from diskfriction.dynamics.stepper import Stepper
from diskfriction.memory import require_memory
from diskfriction.peers.lammps_deck import DUMP_FILE, Start, deck
from diskfriction.peers.lammps_run import Lammps, read_dump, rebuild_theta
from diskfriction.symbolic import System

LAMMPS_RATIO = 4.2
"""LAMMPS's time per disk-step over ours at N = 10 (2.4-4.2 from N = 10 000 to 10, docs/lammps.md)."""

FRAMES = 1000
"""Default number of recorded frames of a cross-check (every = steps / FRAMES, rounded up)."""


@dataclass(frozen=True)
class Steps:
    """dt [time], steps (a multiple of every) ending exactly at t_end, every: steps between
    frames."""

    dt: float
    steps: int
    every: int

    @classmethod
    def plan(cls, t_end: float, dt_max: float, every: Optional[int] = None) -> Steps:
        """The fewest steps of at most dt_max that end on t_end and that `every` divides
        (every None: FRAMES frames)."""
        if not (math.isfinite(t_end) and t_end > 0 and math.isfinite(dt_max) and dt_max > 0):
            raise ValueError(f"t_end and dt must be positive numbers (got {t_end}, {dt_max})")
        every = every or max(1, math.ceil(whole_strides(t_end, dt_max, 1) / FRAMES))
        n = whole_strides(t_end, dt_max, every)
        return cls(t_end / n, n, every)

    def seconds(self, N: int) -> float:
        """Estimated wall time of both codes [s]: ours at SECONDS_PER_DISK_STEP, LAMMPS at
        LAMMPS_RATIO times it (benchmarks/lammps_speed.py)."""
        return (1 + LAMMPS_RATIO) * SECONDS_PER_DISK_STEP * self.steps * N

    @property
    def frames(self) -> int:
        return self.steps // self.every + 1


def default_dt(system: System, start: Start) -> float:
    """dynamics.simulate's default step at the start: 0.05 x 2 / omega_max of M^-1 J [time]."""
    return choose_dt(_start_spectrum(system, start))


def plan_steps(system: System, start: Start, t_end: float, dt: Optional[float] = None,
               every: Optional[int] = None) -> Steps:
    """Steps.plan with dt at most `dt` (None: default_dt), checked against the stability limit
    2 / omega_max of the start (dynamics.simulate): UnstableStep if not below it, as simulate."""
    spec = _start_spectrum(system, start)
    steps = Steps.plan(t_end, choose_dt(spec) if dt is None else dt, every)
    if steps.dt >= stability_limit(spec):
        raise UnstableStep(steps.dt, spec)
    return steps


def _start_spectrum(system: System, start: Start):
    """The spectrum of M^-1 J at the start, with zero histories (LAMMPS starts with none)."""
    return spectrum(system, start.q, np.zeros(2 * system.N))


@dataclass(frozen=True)
class CrossCheck:
    """Deviations of our run from LAMMPS's at every frame: t (f,) [time]; dx, dy, dtheta (f,)
    the largest |ours - LAMMPS| over the disks [length, rad] (dtheta None without rotation);
    ours: our positions (f, ndof); breach_t (N,): our first Coulomb cap at each substrate
    contact [time] (nan if none); the steps, the start, LAMMPS's version."""

    t: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dtheta: Optional[np.ndarray]
    ours: np.ndarray
    breach_t: np.ndarray
    steps: Steps
    start: Start
    lammps_version: str

    def deviations(self) -> dict[str, np.ndarray]:
        """The deviation series by name: x, y (and theta with rotation)."""
        series = {"x": self.dx, "y": self.dy}
        return series | ({"theta": self.dtheta} if self.dtheta is not None else {})

    def summary(self) -> dict:
        """JSON-ready: the run's parameters and the largest deviation of each coordinate."""
        return {"F_x": self.start.F_x, "start": self.start.kind, "start_note": self.start.note,
                "t_end": float(self.t[-1]), "dt": self.steps.dt, "steps": self.steps.steps,
                "every": self.steps.every, "lammps_version": self.lammps_version,
                "substrate_contacts_capped": int(np.isfinite(self.breach_t).sum()),
                "max_deviation": {name: float(d.max()) for name, d in self.deviations().items()}}


def our_run(system: System, start: Start, steps: Steps) -> tuple[np.ndarray, np.ndarray]:
    """Our positions (frames, ndof) from the start at rest with zero histories, and the first
    Coulomb cap at each substrate contact [time] (nan if none)."""
    n = system.ndof
    require_memory(8.0 * steps.frames * (3 + 2 * n + system.N),
                   f"recording {steps.frames} frames of the cross-check")
    stepper = Stepper(system, start.q, np.zeros(n), np.zeros(2 * system.N), start.F_x, steps.dt,
                      steps.every, steps.frames)
    stepper.advance(steps.steps)
    return stepper.frames().q, np.where(stepper.breach_t < 0, np.nan, stepper.breach_t)


def crosscheck(system: System, start: Start, steps: Steps, lammps: Lammps, workdir: Path
               ) -> CrossCheck:
    """Run both codes from `start` for `steps` (LAMMPS in `workdir`) and compare."""
    scene, N = system.scene, system.N
    lammps_deck = deck(scene, start, steps.dt, steps.steps, steps.every)
    lammps_deck.save(workdir)
    ours, breach_t = our_run(system, start, steps)
    lammps.run(workdir, {})
    dump = read_dump(Path(workdir) / DUMP_FILE)
    if dump.steps.size != ours.shape[0]:
        raise ValueError(f"LAMMPS wrote {dump.steps.size} snapshots, ours {ours.shape[0]} frames")
    dev = lambda a, b: np.abs(a - b).max(axis=1)  # noqa: E731
    dtheta = None
    if scene.resolved_effects.rotation:  # LAMMPS's theta starts from 0, ours from the start's
        turned = ours[:, 2 * N:] - start.q[2 * N:]
        dtheta = dev(turned, rebuild_theta(dump, steps.dt, steps.every, scene.I))
    return CrossCheck(dump.steps * steps.dt, dev(ours[:, :N], dump["xu"]),
                      dev(ours[:, N:2 * N], dump["yu"]), dtheta, ours, breach_t, steps, start,
                      lammps.version)


def lever_arm_band(system: System, positions: np.ndarray, t: float) -> tuple[float, float]:
    """The range of the deviation in theta [rad] that the lever arm makes at time t between
    conventions "model" and "lammps" (positions: a run's frames (f, ndof) up to t, ours).

    The disk-disk torques differ by the relative amount eps = delta / 2R (arm R against
    R - delta/2; eps: its largest value over the run and the pairs). A response to the
    torques in step with them differs by eps times itself: the low end, eps Theta, with Theta
    the largest |theta - theta_0| of the run. A stiffness changed by eps shifts frequencies by
    eps/2 of themselves, and the phase error of an oscillation grows as (eps/2) omega t: the
    high end, (eps/2) omega_max t Theta, with omega_max the fastest mode at the start
    (no mode drifts faster). Both ends are O(delta)."""
    N, R = system.N, system.scene.R
    eps = max(max(float(system.overlaps(q)[:N].max()) for q in positions), 0.0) / (2 * R)
    rotation = float(np.abs(positions[:, 2 * N:] - positions[0, 2 * N:]).max())
    omega_max = spectrum(system, positions[0], np.zeros(2 * N)).omega_max
    return eps * rotation, eps / 2 * omega_max * t * rotation
