"""Rough wall time of a packing command's parts, for the estimate each prints before it starts
(models/packing/commands_checks.check_packing), and a run's time steps, known before any work.

Rules fitted to runs on the project's 2-core machine, good to a factor of 2 to 3 on those runs:
enough to tell minutes from days (what each was fitted on, and the shears since:
docs/notes/packings-speed.md, "The time estimates against the shears they were fitted on").
- The preparation: PREPARE_SECONDS_N1024 (N / 1024)^1.75, its FIRE steps growing as N^0.75 and
  each step as N; fitted to 1.04 s at 256 disks and 11.6 s at 1024
  (docs/notes/packings-preparation.md, "Cost").
- The shear without spectra (spectra none): SHEAR_START_SECONDS + NONE_SECONDS_PER_STRAIN
  N^NONE_EXPONENT per unit strain, fitted to the shears of 2026-12-02 (5d116c6 to 11eff34, scene
  defaults, seed 1, to gamma = 0.01): 32 disks in 0.84 s, 64 disks in 4.5 to 6.7 s, 256 disks in
  32 to 62 s and 1024 disks in 1239 s, the last three with the machine busy (the rule: 0.84,
  3.4, 54 and 860 s; docs/notes/packings-lammps.md).
- With sampled spectra (sample:DGAMMA): that, and the spectrum at each grid strain,
  DENSE_SAMPLE_SECONDS_N256 (N / 256)^3 dense (0.27 s at 256 disks on one BLAS thread) or
  WINDOW_SAMPLE_SECONDS_N1024 (N / 1024)^1.5 by a window (about 0.1 to 0.5 s per shift-invert
  at 1024 disks, docs/notes/packings-window-methods.md, several per sample while it is sized).
- The shear with every eigenvalue (spectra full, dense; two scan workers, as bifurcate runs it):
  SHEAR_START_SECONDS + DENSE_SECONDS_PER_STRAIN N^2.5 per unit strain, fitted to the shears of
  2026-12-02 (9b7bcfe: 32 disks to gamma = 0.01 in 3.3 to 7.4 s, 64 disks in 29.6 to 53.4 s; the
  rule gives 5.8 and 33 s besides its start).
- With a spectral window, WINDOW_SECONDS_PER_STRAIN N^2.5, fitted to 256 disks to 0.05 with the
  window [-3, 8] in about 5 minutes (the rule: 525 s) and 1024 disks at 4.7e5 to 5.9e5 s per
  unit strain (the rule: 3.4e5 s). A window costs more the more eigenvalues it holds.
- A dynamics run from a state (models/packing/dynamics.py): SECONDS_PER_DISK_STEP per disk and step,
  with dt = STABLE_FRACTION 2 / omega_max and omega_max = OMEGA_MAX_OVER_OMEGA_0 omega_0
  (PackingScene.omega_0: one small disk on one contact at the typical overlap).
"""
from __future__ import annotations

from typing import Optional

from diskfriction.models.packing.dynamics import STABLE_FRACTION
from diskfriction.scenes.packing import PackingScene

PREPARE_SECONDS_N1024 = 11.6
PREPARE_EXPONENT = 1.75
SHEAR_EXPONENT = 2.5
DENSE_SECONDS_PER_STRAIN = 0.1
WINDOW_SECONDS_PER_STRAIN = 0.01
NONE_SECONDS_PER_STRAIN = 0.082
NONE_EXPONENT = 2.0
DENSE_SAMPLE_SECONDS_N256 = 0.3
WINDOW_SAMPLE_SECONDS_N1024 = 1.0
SHEAR_START_SECONDS = 4.0
"""What a shear costs besides its strain: the kernels loaded, the first spectra (16 disks to
gamma = 0.002: 4 to 9 s in a fresh map worker)."""

OMEGA_MAX_OVER_OMEGA_0 = 2.4
"""sqrt(max |lambda|) of M^-1 J over omega_0: 2.25 to 2.48 over the states of 24 to 256 disks
sheared to gamma = 1e-4 to 0.002 (seeds 3, 1, 1, 1)."""

SECONDS_PER_DISK_STEP = 6e-7
"""A run's cost per disk and time step, frames and contact searches included: 5.4e-7, 5.9e-7 and
7.3e-7 s at 24, 128 and 256 disks (4e5, 1e5 and 5e4 steps, 2000 frames, the machine busy)."""

GROWTH_STEPS = 2e4
"""The time steps a run takes to show a complex pair's growth into sliding: from 10 times the
perturbation (1e-10) to 1e-3 delta_0, 10 to 14 e-foldings (the rate itself is fitted over the
first few, below models/packing/dynamics.LINEAR_RANGE), which the slowest median growth measured
(sigma = 0.018 omega_0 at mu = 0.3, docs/packings.md, Maps) takes in about 800 / omega_0, 2e4
steps of the default dt."""

MAX_RUN_STEPS = 5000 * GROWTH_STEPS
"""The most time steps a run may take, 1e8 (a 24-disk run of 1e8 steps takes 25 minutes, a
256-disk run 4 hours)."""


def prepare_seconds(N: int) -> float:
    """Estimated wall time of the preparation of N disks [s]."""
    return PREPARE_SECONDS_N1024 * (N / 1024) ** PREPARE_EXPONENT


def shear_seconds(N: int, gamma: float, spectra: str, window: bool) -> float:
    """Estimated wall time of a shear of N disks from gamma = 0 to `gamma` with `spectra`
    (resolved: "full", "none" or "sample:DGAMMA") and a spectral window or not [s]: the
    equilibria (NONE_SECONDS_PER_STRAIN N^NONE_EXPONENT per unit strain), and every state's
    spectrum tracked with its collisions (full: the dense or window rule), or the spectrum at
    each grid strain (sample: sample_seconds each)."""
    branch = NONE_SECONDS_PER_STRAIN * float(N) ** NONE_EXPONENT * gamma
    if spectra == "none":
        return SHEAR_START_SECONDS + branch
    if spectra == "full":
        rate = WINDOW_SECONDS_PER_STRAIN if window else DENSE_SECONDS_PER_STRAIN
        return SHEAR_START_SECONDS + rate * float(N) ** SHEAR_EXPONENT * gamma
    samples = 1.0 + gamma / float(spectra.partition(":")[2])
    return SHEAR_START_SECONDS + branch + samples * sample_seconds(N, window)


def sample_seconds(N: int, window: bool) -> float:
    """Estimated wall time of the spectrum at one grid strain [s]: a dense eigendecomposition
    of 3N x 3N, DENSE_SAMPLE_SECONDS_N256 (N / 256)^3, or a window's shift-invert,
    WINDOW_SAMPLE_SECONDS_N1024 (N / 1024)^1.5."""
    if window:
        return WINDOW_SAMPLE_SECONDS_N1024 * (N / 1024) ** 1.5
    return DENSE_SAMPLE_SECONDS_N256 * (N / 256) ** 3


def spectra_words(spectra: str, window: bool) -> str:
    """How the estimate names a shear's spectra."""
    if spectra == "none":
        return "without spectra"
    if spectra == "full":
        return "with a window" if window else "with every eigenvalue"
    return f"with the spectrum{' in a window' if window else ''} every {spectra.partition(':')[2]}"


def time_step(scene: PackingScene) -> float:
    """The default step of a run, STABLE_FRACTION 2 / omega_max, before any spectrum is known
    (omega_max = OMEGA_MAX_OVER_OMEGA_0 omega_0) [time]."""
    return STABLE_FRACTION * 2.0 / (OMEGA_MAX_OVER_OMEGA_0 * scene.omega_0)


def run_steps(scene: PackingScene, t_end: float, dt: Optional[float] = None) -> float:
    """The time steps of a run to t_end with the step dt, or the default step (time_step)."""
    return t_end / (dt or time_step(scene))


def run_seconds(scene: PackingScene, steps: float) -> float:
    """Estimated wall time of a run of `steps` time steps on the scene's N disks [s]."""
    return SECONDS_PER_DISK_STEP * scene.N * steps
