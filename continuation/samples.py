"""Samples: branch points with their tracked spectra, the data collision detection works on.

A sample is a point x = (u, p) of the branch at coordinate s of the step's segment (segment.py),
its eigenvalues in tracked order (label i continues label i of the neighbouring sample), their
status (spectra.eigen_status) and, for the fast detection, their slopes along the branch:

    d lambda_i / d tau = l_i^H (dA/dtau) r_i,      tau the arclength along the unit tangent t,

from the normalised left and right eigenvectors (spectra.eigenvalue_slopes), with dA/dtau
from finite differences of the stability matrix along t (matrix_derivative). On a segment of
length L with unit normal sigma, x'(s) = t L / (sigma . t), so d lambda / ds follows (slopes).
Matching the labels of a new sample uses these slopes: label i goes to the eigenvalue nearest to
the trapezoid prediction lambda_i + (slope_i + slope_new) ds / 2 (spectra.match_eigenvalues on
the predicted values), which follows a fast eigenvalue through a cluster.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np
from scipy.optimize import linear_sum_assignment

from .problem import Problem
from .spectra import Eigensystem, eigen_status, eigenvalue_slopes, imag_threshold, match_eigenvalues

Array = np.ndarray
_uid = itertools.count()


@dataclass(frozen=True)
class Sample:
    """A branch point at segment coordinate s: x = (u, p), tracked eigenvalues, status per
    eigenvalue, status threshold thr; excluded modes (never part of a collision); with slopes:
    tangent t (unit, oriented along the branch), dlam = d lambda / d tau along t, and the
    eigensystem (vectors in label order) that seeds the collision locator."""

    s: float
    x: Array
    eigvals: Array
    status: Array
    thr: float
    excluded: Array
    tangent: Optional[Array] = None
    dlam: Optional[Array] = None
    system: Optional[Eigensystem] = None
    guard: Optional[Array] = None
    uid: int = field(default_factory=lambda: next(_uid), init=False, repr=False, compare=False)

    @property
    def p(self) -> float:
        return float(self.x[-1])

    def at(self, s: float) -> "Sample":
        """The same point at another segment coordinate (a new step starts at its old end)."""
        return replace(self, s=s)

    def relabel(self, perm: Array) -> "Sample":
        """Labels permuted: new[i] = old[perm[i]]."""
        take = lambda a: None if a is None else a[perm]  # noqa: E731
        return replace(self, eigvals=self.eigvals[perm], status=self.status[perm],
                       excluded=self.excluded[perm], dlam=take(self.dlam), guard=take(self.guard),
                       system=None if self.system is None else self.system.permuted(perm))

    def slopes(self, segment) -> Array:
        """d lambda / ds on `segment` (s in [0, 1] from x_a to x_b): dlam L / (sigma . t)."""
        return self.dlam * (segment.length / float(segment.sigma @ self.tangent))


def matrix_derivative(problem: Problem, x: Array, t: Array, side: int = 0):
    """dA/dtau at x along the unit direction t, by finite differences of problem.stability_matrix
    with step h = problem.derivative_step(x): central (side 0, error O(h^2)), or one-sided
    second order towards side +1 / -1, (-3 A(x) + 4 A(x + h t) - A(x + 2h t)) / 2h, at the end
    of a step where the other side lies beyond a contact event. Dense or sparse as A is."""
    h = problem.derivative_step(x)
    A = lambda y: problem.stability_matrix(y[:-1], y[-1])  # noqa: E731
    if side == 0:
        return (A(x + h * t) - A(x - h * t)) * (0.5 / h)
    d = h * side
    return (A(x + d * t) * 4.0 - A(x) * 3.0 - A(x + 2.0 * d * t)) * (0.5 / d)


def predicted_match(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                    ds_ref: float, ds_new: float) -> Array:
    """Labels of `values` continuing `ref_values`: perm minimising sum_i |ref_i + ds_ref
    ref_dlam_i / 2 + ds_new dlam_perm(i) / 2 - values_perm(i)| (trapezoid prediction; ds_* =
    the step projected on each end's unit tangent)."""
    cost = np.abs((ref_values + 0.5 * ds_ref * ref_dlam)[:, None] - (values - 0.5 * ds_new * dlam)[None, :])
    nearest = np.argmin(cost, axis=1)
    if np.unique(nearest).size == nearest.size:
        return nearest
    return linear_sum_assignment(cost)[1]


def continuation_perm(left: Sample, right: Sample) -> Array:
    """Labels of `right` continuing `left`: by prediction if both carry slopes, else by the
    nearest eigenvalue (spectra.match_eigenvalues)."""
    if left.dlam is None or right.dlam is None:
        return match_eigenvalues(left.eigvals, right.eigvals)
    step = right.x - left.x
    return predicted_match(left.eigvals, left.dlam, right.eigvals, right.dlam,
                           float(step @ left.tangent), float(step @ right.tangent))


def make_sample(s: float, x: Array, system: Eigensystem, rel_tol: float,
                reference: Optional[Sample] = None, tangent: Optional[Array] = None,
                dlam: Optional[Array] = None) -> Sample:
    """Sample at s, labels continuing `reference` when given (by prediction when both carry
    slopes, else by nearest eigenvalue: spectra.match_eigenvalues)."""
    values = np.asarray(system.values, dtype=complex)
    excluded = system.excluded if system.excluded is not None else np.zeros(values.size, bool)
    system = Eigensystem(values, system.right, system.left, excluded, system.guard)
    sample = Sample(s, x, values, eigen_status(values, rel_tol), imag_threshold(values, rel_tol),
                    excluded, tangent, dlam, system if system.right is not None else None,
                    system.guard)
    return sample if reference is None else sample.relabel(continuation_perm(reference, sample))


def sample_at(problem: Problem, s: float, x: Array, rel_tol: float, reference: Optional[Sample],
              tangent: Optional[Array] = None, side: int = 0) -> Sample:
    """The sample of the branch point x: eigenvalues only (tangent None), or the eigensystem
    with vectors and the slopes along `tangent` (matrix_derivative on `side`)."""
    u, p = x[:-1], float(x[-1])
    if tangent is None:
        return make_sample(s, x, problem.eigensystem(u, p), rel_tol, reference)
    system = problem.eigensystem(u, p, vectors=True)
    dlam = eigenvalue_slopes(system, matrix_derivative(problem, x, tangent, side))
    return make_sample(s, x, system, rel_tol, reference, tangent, dlam)
