"""The spectrum of a shear on an evenly spaced strain grid (a packing scene's spectra
"sample:DGAMMA", docs/packings.md#spectra): the equilibrium at every grid strain
gamma_k = k DGAMMA that a segment of the branch passes, and the eigenvalues of the scene's matrix
there (every one, or a spectral window's), their complex pairs counted. No collision is located:
the samples give the counts, growth rates and per-strain statistics of a branch whose steps
took no spectrum.

The equilibrium at gamma_k is solved at fixed strain (Newton, the branch's tolerance) from the
accepted state k before it, with the contact rows and histories committed there (the branch's
rows and xi columns): within a step no contact event happens (the shear cuts its steps at
them), so this is the state the branch passes through at gamma_k, to the Newton tolerance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.linalg.solves import blas_threads
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.spectra.tracking import count_complex_pairs
from diskfriction.continuation.spectra.window import SpectralWindow, WindowCrowded
from diskfriction.continuation.stepping.newton import fixed_p_newton
from diskfriction.models.packing.equilibria import (LINEAR_SOLVER, WINDOW_EXTRA, WINDOW_MARGIN,
                                                    PackingEquilibria, largest_force)
from diskfriction.models.packing.network import Network


@dataclass(frozen=True)
class SpectrumSample:
    """The spectrum at one grid strain: gamma; eigenvalues (complex) of the branch's matrix at the
    equilibrium there (every one, the translations' zeros included; with a window those
    within it and its guard bands); n_complex, the complex pairs among them (in the window,
    with one); residual max|F| over the disks there [force]."""

    gamma: float
    eigenvalues: np.ndarray
    n_complex: int
    residual: float


class SampleFailed(RuntimeError):
    """No equilibrium at a grid strain within a step of the branch (Newton did not converge)."""


def grid_strains(start: float, stop: float, every: float) -> np.ndarray:
    """The grid strains k every (k an integer) with start <= k every <= stop: one grid for every
    segment of a run, anchored at gamma = 0."""
    first, last = math.ceil(start / every - 1e-9), math.floor(stop / every + 1e-9)
    strains = np.arange(first, last + 1) * every
    return strains[(strains >= start) & (strains <= stop)]


def sampled_spectra(network: Network, mass: np.ndarray, segment: Branch, every: float,
                    window: Optional[tuple[float, float]], matrix: str, newton_tol: float,
                    rel_tol: float, done_before: float = -math.inf) -> tuple[SpectrumSample, ...]:
    """The samples of one segment of a shear (shear.shear_segment's branch, its rows and xi
    columns): at every grid strain in [its first gamma, its last] above done_before (the last
    strain an earlier segment sampled), the equilibrium solved from the accepted state before
    it (module docstring) and its spectrum: dense, or by a spectral window (lo, hi) sized at the
    first sample and widened where it crowds. SampleFailed where no equilibrium is found."""
    gamma = segment.p
    strains = grid_strains(float(gamma[0]), float(gamma[-1]), every)
    strains = strains[strains > done_before]
    with blas_threads():  # as the continuation's spectra: one BLAS thread (solves.blas_threads)
        return tuple(_samples(network, mass, segment, strains, window, matrix, newton_tol, rel_tol))


def _samples(network, mass, segment, strains, window, matrix, newton_tol, rel_tol):
    """sampled_spectra's samples at `strains`, one after another."""
    gamma = segment.p
    solver = None if window is None else SpectralWindow(*window, margin=WINDOW_MARGIN, extra=WINDOW_EXTRA)
    for g in strains:
        k = min(int(np.searchsorted(gamma, g, side="right")) - 1, len(gamma) - 1)
        problem = PackingEquilibria(network, segment.u[k], segment.xi[k], segment.rows[k],
                                    float(gamma[k]), mass, matrix, newton_tol)
        q = segment.u[k]
        if g != gamma[k]:
            share = (g - gamma[k]) / (gamma[k + 1] - gamma[k])
            guess = (1.0 - share) * segment.u[k] + share * segment.u[k + 1]
            result = fixed_p_newton(problem, guess, float(g), newton_tol, 20, LINEAR_SOLVER)
            if not result.converged:
                raise SampleFailed(f"no equilibrium at the grid strain gamma = {g:.9g} between "
                                   f"the branch's states at {gamma[k]:.9g} and {gamma[k + 1]:.9g} "
                                   f"(Newton's residual stayed at {result.residual:.3g})")
            q = result.x[:-1]
        eigenvalues, n_complex, solver = _spectrum(problem, q, float(g), solver, rel_tol)
        yield SpectrumSample(float(g), eigenvalues, n_complex, largest_force(problem, q, float(g)))


def _spectrum(problem: PackingEquilibria, q: np.ndarray, gamma: float,
              solver: Optional[SpectralWindow], rel_tol: float):
    """(eigenvalues, complex pairs, the window solver to carry on) at (q, gamma): dense (solver
    None; pairs counted without the translations' zeros, as the shear counts them) or by the
    window (sized at its first use, widened where it crowds; pairs in the window)."""
    if solver is None:
        values = DenseSpectra().eigensystem(problem, q, gamma).values
        return values, count_complex_pairs(values[values != 0], rel_tol), None
    solver = solver.prepared(problem, q, gamma)
    while True:
        try:
            system = solver.eigensystem(problem, q, gamma)
            break
        except WindowCrowded:
            solver = solver.widened(problem, q, gamma)
    values = system.values[~system.excluded]
    return values, count_complex_pairs(values[solver.inside(values)], rel_tol), solver


def with_samples(segment: Branch, samples: tuple[SpectrumSample, ...]) -> Branch:
    """The segment with its samples as labelled points "sample"."""
    return replace(segment, labelled={**segment.labelled, "sample": samples})
